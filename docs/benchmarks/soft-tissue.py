# plots pcisim-bench soft-tissue's results: the fiducial error against the neo-Hookean FEM,
# against ms per step, one series per particle radius and solver. usage: soft-tissue.py IN.json OUT.png
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = json.load(open(sys.argv[1]))
fig, ax = plt.subplots(figsize=(7, 4.5))
series = {}
for r in rows:
    label = "r %.1f mm, %s%s" % (r["radius_mm"], r["solver"], " w %.1f" % r["sor_w"] if r["solver"] == "jacobi" else "")
    series.setdefault(label, []).append((r["step_ms_p50"], r["mean_error_mm"]))
for label, pts in sorted(series.items()):
    pts.sort()
    ax.plot([p[0] for p in pts], [p[1] for p in pts], "o-", label=label, markersize=4)
ax.set_xscale("log")
ax.set_xlabel("ms per 1/60 s step (p50)")
ax.set_ylabel("mean fiducial error vs FEM (mm)")
ax.set_title("soft tissue: accuracy against time")
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
