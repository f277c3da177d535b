# plots pcisim-bench motion's results: the recovered motion's mean error at the ventricular points
# at end-systole against the seconds one frame's registration takes, one series per pyramid depth
# (plain cine) and one for tagged images. usage: motion.py motion.json motion.png
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = json.load(open(sys.argv[1]))
plain = [r for r in rows if "run" not in r]
tagged = [r["run"] for r in rows if "run" in r]
fig, ax = plt.subplots(figsize=(7, 4.5))
for levels in sorted({r["levels"] for r in plain}):
    for sigma, marker in ((1.0, "o"), (1.5, "s"), (2.5, "^")):
        s = sorted([r for r in plain if r["levels"] == levels and r["sigma_vox"] == sigma],
                   key=lambda r: r["seconds_per_frame"])
        if s:
            ax.plot([r["seconds_per_frame"] for r in s], [r["mean_mm"] for r in s], marker=marker,
                    label=f"{levels} levels, sigma {sigma:g}")
if tagged:
    s = sorted(tagged, key=lambda r: r["seconds_per_frame"])
    ax.plot([r["seconds_per_frame"] for r in s], [r["mean_mm"] for r in s], "k*--", label="tagged, 3 levels, sigma 1.5")
ax.axhline(0.5, color="k", lw=0.8, ls=":", label="issue #14 target (0.5 mm)")
ax.axvline(120 / 19, color="grey", lw=0.8, ls=":", label="20-frame cycle in 2 min")
ax.set_xlabel("seconds per frame (2-core machine; points along a line: 20, 50, 100 iterations)")
ax.set_ylabel("mean error at the ventricular points (mm)")
ax.set_ylim(0, None)
ax.grid(alpha=0.3)
ax.legend(fontsize=7)
ax.set_title("Motion from a synthetic cine by demons: accuracy against time")
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
