"""Plot for pcisim-bench blood: the eq 12 field error and the wire tip's deviation against the
blood effect's median ms per step, one line per link radius, cell spacings labelled.
Reads DIR/blood.json, writes DIR/blood.png."""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks"
report = json.load(open(f"{out}/blood.json"))
fig, axes = plt.subplots(1, 2, figsize=(12, 4.5))
links = sorted({r["link_mm"] for r in report["rows"]})
panels = (("rel_err", 100.0, "field error vs 0.25 mm spacing, % of mean speed"),
          ("tip_rms_mm", 1.0, "wire tip path vs 0.25 mm spacing, RMS mm"))
for ax, (key, scale, label) in zip(axes, panels):
    for link in links:
        # the reference itself has zero error: left off the log axis
        rows = sorted((r for r in report["rows"] if r["link_mm"] == link and r["spacing_mm"] > 0.25),
                      key=lambda r: r["blood_p50_ms"])
        xs = [r["blood_p50_ms"] for r in rows]
        ys = [max(r[key] * scale, 1e-4) for r in rows]
        ax.plot(xs, ys, "o-", label=f"link radius {link:g} mm")
        for r, x, y in zip(rows, xs, ys):
            ax.annotate(f'{r["spacing_mm"]:g} mm', (x, y), textcoords="offset points", xytext=(4, 4), fontsize=8)
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("blood_flow effect, median ms per step (full default scene)")
    ax.set_ylabel(label)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
fig.suptitle("Blood chain-mail spacing: accuracy against cost")
fig.tight_layout()
fig.savefig(f"{out}/blood.png", dpi=110)
