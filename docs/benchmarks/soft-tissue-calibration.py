# plots pcisim-calibrate's report: mean fiducial error against the probe's travel, for the bead
# motion itself (a model that does not deform), each radius's calibrated model and the paper's
# model (shape matching alone) at its optimum; the tuning kidney left, the held-out one right.
# usage: soft-tissue-calibration.py soft-tissue-calibration.json soft-tissue-calibration.png
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

report = json.load(open(sys.argv[1]))
fig, axes = plt.subplots(1, 2, figsize=(11, 4.5), sharey=True)
for ax, organ, title in ((axes[0], "tuning", "tuning kidney"), (axes[1], "held_out", "held-out kidney (not re-tuned)")):
    first = report["optima"][0][organ]
    travel = [s["travel_mm"] for s in first]
    ax.plot(travel, [s["reference_displacement_mm"] for s in first], "k-o", lw=2, label="no deformation (bead motion)")
    for opt in report["optima"]:
        label = f"r {opt['radius_mm']} mm, c {opt['compliance_s2']:.0e}, K {opt['bulk_kpa']} kPa, {opt['contact']}"
        line = ax.plot(travel, [s["mean_mm"] for s in opt[organ]], "-s", label=label)[0]
        paper = opt["paper_model"][organ]
        if paper:
            ax.plot(travel, [s["mean_mm"] for s in paper], ":", color=line.get_color(),
                    label=f"r {opt['radius_mm']} mm, shape matching alone (c {opt['paper_model']['compliance_s2']:.0e})")
    ax.set_title(title)
    ax.set_xlabel("probe travel (mm)")
    ax.grid(alpha=0.3)
axes[0].set_ylabel("mean fiducial error (mm)")
axes[1].legend(fontsize=7, loc="upper left")
fig.suptitle("Soft-tissue calibration against the neo-Hookean FEM")
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
