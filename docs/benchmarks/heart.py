"""Plot for pcisim-bench heart: mean error vs median ms per step, one line per solver and
cluster size, substeps x iterations labelled. Reads DIR/heart.json, writes DIR/heart.png."""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks"
report = json.load(open(f"{out}/heart.json"))
fig, axes = plt.subplots(1, 2, figsize=(13, 5), sharey=True)
markers = {1: "o", 2: "s", 4: "^", 8: "D", 16: "v", 32: "P"}
series = {}
for r in report["rows"]:
    series.setdefault((r["cluster_mm"], r["solver"]), []).append(r)
for ax, by in zip(axes, ("substeps", "iterations")):
    for (cm, solver), rows in sorted(series.items()):
        color = ax._get_lines.get_next_color()
        # one line per fixed value of the other knob, so each line shows what `by` buys
        other = "iterations" if by == "substeps" else "substeps"
        for value in sorted({r[other] for r in rows}):
            line = sorted((r for r in rows if r[other] == value), key=lambda r: r[by])
            ax.plot([r["median_ms"] for r in line], [max(r["mean_err_mm"], 1e-6) for r in line], "-",
                    color=color, alpha=0.5, marker=markers.get(value, "x"), markersize=4,
                    label=f"{solver}, " + (f"{cm:g} mm clusters" if cm else "global cluster") if value == min(r[other] for r in rows) else None)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median ms per step")
    ax.set_title(f"lines: more {by} (markers: {'iterations' if by == 'substeps' else 'substeps'} 1/2/4/8/16)")
    ax.grid(True, which="both", alpha=0.3)
axes[0].set_ylabel("mean particle error vs reference, mm")
axes[1].legend(fontsize=7)
fig.suptitle(f"beating template heart, {report['body']['particles']} particles ({report['body']['free']} free), 72 bpm, 30 Hz - {report['machine']}", fontsize=9)
fig.tight_layout()
fig.savefig(f"{out}/heart.png", dpi=110)
