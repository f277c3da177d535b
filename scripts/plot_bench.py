#!/usr/bin/env python3
"""Plots a pcisim-bench guidewire report: tip error vs median ms per step.

usage: plot_bench.py REPORT.json OUT.png

One marker per setting; colour by segment count, marker by SDF spacing, and a line through
each (segments, spacing) series as optimisation passes grow.
"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def main(argv):
    if len(argv) != 3:
        print(__doc__)
        return 2
    with open(argv[1]) as f:
        report = json.load(f)
    rows = report["rows"]
    segments = sorted({r["segments"] for r in rows})
    spacings = sorted({r["sdf_spacing_mm"] for r in rows})
    markers = ["o", "s", "^", "D"]
    cmap = plt.get_cmap("viridis")
    fig, ax = plt.subplots(figsize=(8, 5.5))
    floor = 1e-3  # the reference itself has zero error; draw it at the floor of the log axis
    for si, n in enumerate(segments):
        colour = cmap(si / max(len(segments) - 1, 1))
        for mi, sp in enumerate(spacings):
            series = sorted((r for r in rows if r["segments"] == n and r["sdf_spacing_mm"] == sp),
                            key=lambda r: r["passes"])
            if not series:
                continue
            xs = [r["median_ms"] for r in series]
            ys = [max(r["tip_rms_mm"], floor) for r in series]
            ax.plot(xs, ys, "-", color=colour, alpha=0.35, linewidth=1)
            ax.scatter(xs, ys, color=colour, marker=markers[mi % len(markers)], s=28,
                       label=f"{n} seg, {sp} mm")
            for r, x, y in zip(series, xs, ys):
                ax.annotate(str(r["passes"]), (x, y), textcoords="offset points", xytext=(3, 3), fontsize=6)
    ref = report.get("reference", {})
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("median ms per physics step (single thread)")
    ax.set_ylabel("tip RMS error vs reference (mm)")
    ax.set_title("Guidewire: accuracy vs cost (labels: optimisation passes)\n"
                 f"reference {ref.get('segments')} seg, {ref.get('passes')} passes, "
                 f"{ref.get('sdf_spacing_mm')} mm SDF; {report.get('machine', '')}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6, ncol=3, loc="best")
    fig.tight_layout()
    fig.savefig(argv[2], dpi=130)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
