# plots pcisim-bench wire-force's results: the dead end's hub and tip force against the feed, the
# capstan's and end-on's measured forces against their textbook values, and the tip's spin against
# the hub's turn (torque lag).
# usage: wire-force.py wire-force.json wire-force.png
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

runs = json.load(open(sys.argv[1]))["runs"]
fig, grid = plt.subplots(2, 2, figsize=(14, 9.6))
axes = grid.flatten()

ax = axes[0]
for r in runs:
    if r["case"] != "dead_end":
        continue
    cols = r["curve_columns"]
    curve = [dict(zip(cols, row)) for row in r["curve"]]
    ax.plot([c["commanded_mm"] for c in curve], [c["hub_n"] for c in curve], label="hub force (what the hand feels)")
    ax.plot([c["commanded_mm"] for c in curve], [c["tip_n"] for c in curve], label="tip on the end")
    ax2 = ax.twinx()
    ax2.plot([c["commanded_mm"] for c in curve], [c["fed_mm"] for c in curve], color="grey", ls="--", lw=0.8,
             label="fed (grip slips above 1 N)")
    ax2.set_ylabel("fed mm", color="grey")
    ax.axhline(1.0, color="k", lw=0.6, ls=":")
    ax.set_xlabel("commanded feed mm (tube closed 124 mm along it)")
    ax.set_ylabel("force N")
    ax.set_title(f"dead end: crumpled ≤ {r['max_crumpled_mm']:.2f} mm, past the wall ≤ {max(r['worst_mm'], 0):.3f} mm")
    ax.legend(fontsize=7, loc="upper left")
    ax2.legend(fontsize=7, loc="lower right")

ax = axes[1]
caps = [r for r in runs if r["case"] == "capstan" and r["drawn_through"]]
for angle in sorted({r["angle_deg"] for r in caps}):
    s = sorted([r for r in caps if r["angle_deg"] == angle], key=lambda r: r["mu"])
    line = ax.plot([r["mu"] for r in s], [r["pull_n"] / r["hold_n"] for r in s], "o", label=f"{angle:g}° measured")[0]
    mus = [0.04 + 0.005 * i for i in range(75)]
    ax.plot(mus, [math.exp(m * s[0]["wrap_rad"]) for m in mus], color=line.get_color(), lw=0.8)
ax.set_xlabel("μ")
ax.set_ylabel("pull / hold")
ax.set_title("capstan: lines e^(μθ), dots the rod")
ax.legend(fontsize=7)
ax.grid(alpha=0.3)

ax = axes[2]
ends = [r for r in runs if r["case"] == "end_on" and r["buckled"]]
for c in sorted({r["clearance_mm"] for r in ends}):
    s = sorted([r for r in ends if r["clearance_mm"] == c], key=lambda r: r["length_mm"])
    ax.plot([r["length_mm"] for r in s], [r["buckling_n"] for r in s], "o", label=f"clearance {c:g} mm")
if ends:
    ls = [20 + i for i in range(90)]
    ei = ends[0]["euler_n"] * (ends[0]["length_mm"] * 1e-3) ** 2
    ax.plot(ls, [ei / (l * 1e-3) ** 2 for l in ls], color="k", lw=0.8, label="Euler, clamped-pinned")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("free length mm")
ax.set_ylabel("hub force at first buckling N")
ax.set_title("end on")
ax.legend(fontsize=7)
ax.grid(alpha=0.3, which="both")

ax = axes[3]
for r in runs:
    if r["case"] != "torque_lag" or not r["completed"]:
        continue
    cols = r["curve_columns"]
    curve = [dict(zip(cols, row)) for row in r["curve"]]
    label = f"{'tortuous' if r['tortuous'] else 'straight'}, friction {'on' if r['friction'] else 'off'}"
    ax.plot([c["t_s"] for c in curve], [c["tip_deg"] for c in curve], label=f"tip: {label}")
    hub = [(c["t_s"], c["hub_deg"]) for c in curve]
if any(r["case"] == "torque_lag" and r["completed"] for r in runs):
    ax.plot([h[0] for h in hub], [h[1] for h in hub], color="k", lw=0.8, ls="--", label="hub")
ax.set_xlabel("time from the turn's start s")
ax.set_ylabel("rotation °")
ax.set_title("torque lag: the hub turned 360° at 180°/s, then held")
ax.legend(fontsize=7)
ax.grid(alpha=0.3)

fig.suptitle("The rod wire with its wall inside the solve, against mechanics (pcisim-bench wire-force)")
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
