#!/usr/bin/python3
"""Plots docs/benchmarks/haptics_trace.csv: the force each interpolation scheme renders against
the 1 kHz physics reference. Usage: plot_haptics.py DIR (writes DIR/haptics.png)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

out_dir = sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks"
with open(f"{out_dir}/haptics_trace.csv") as f:
    rows = list(csv.DictReader(f))
cols = ["reference_n", "zero_order_hold_n", "linear_extrapolation_n", "local_model_n"]
t = [float(r["t_s"]) for r in rows]
fig, axes = plt.subplots(2, 1, figsize=(10, 7), sharex=True)
for c in cols:
    axes[0].plot(t, [float(r[c]) for r in rows], label=c.replace("_n", "").replace("_", " "),
                 linewidth=1.6 if c == "reference_n" else 0.9)
axes[0].set_ylabel("axial force (N)")
axes[0].legend(loc="upper left")
axes[0].set_title("force rendered at 1 kHz between 30 Hz physics steps")
for c in cols[1:]:
    axes[1].plot(t, [float(r[c]) - float(r["reference_n"]) for r in rows], label=c.replace("_n", "").replace("_", " "),
                 linewidth=0.8)
axes[1].set_ylabel("error vs 1 kHz physics (N)")
axes[1].set_xlabel("time (s)")
axes[1].legend(loc="upper left")
fig.tight_layout()
fig.savefig(f"{out_dir}/haptics.png", dpi=110)
