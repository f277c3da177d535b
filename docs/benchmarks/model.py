# plots pcisim-bench model's results: each sweep's accuracy (AI, OV, radius error) against the
# pipeline's seconds. usage: model.py model.json model.png
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = [r for r in json.load(open(sys.argv[1])) if not r["failed"]]
sweeps = []
for r in rows:
    if r["sweep"] not in sweeps:
        sweeps.append(r["sweep"])
fig, axes = plt.subplots(1, 3, figsize=(15, 4.5))
for ax, key, label in zip(axes, ["ai_mm", "ov", "radius_mean_mm"], ["AI (mm)", "OV", "radius error mean (mm)"]):
    for s in sweeps:
        pts = [r for r in rows if r["sweep"] == s]
        ax.scatter([r["seconds"] for r in pts], [r[key] for r in pts], label=s, s=18)
    ax.set_xlabel("model time (s, 2-core machine)")
    ax.set_ylabel(label)
    ax.grid(alpha=0.3)
axes[0].axhline(0.3, color="k", lw=0.8, ls="--")
axes[1].axhline(0.95, color="k", lw=0.8, ls="--")
axes[2].axhline(0.15, color="k", lw=0.8, ls="--")
axes[0].legend(fontsize=7)
fig.suptitle("CTA modeling: accuracy against time (dashed: issue #13 targets)")
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=90)
