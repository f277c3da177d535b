#!/usr/bin/env python3
"""Plots a pcisim-bench guidewire report (both wire models): tip error vs median ms per step.

usage: plot_bench.py REPORT.json OUT.png

One marker per setting; blue for the chain-mail, red for the rod (darker: more segments), marker
by SDF spacing, and a line through each (model, segments, spacing) series as the chain-mail's
optimisation passes or the rod's substeps grow.
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
    spacings = sorted({r["sdf_spacing_mm"] for r in rows})
    markers = ["o", "s", "^", "D"]
    maps = {"chain_mail": plt.get_cmap("Blues"), "rod": plt.get_cmap("Reds")}
    fig, ax = plt.subplots(figsize=(9, 6))
    floor = 1e-2  # the reference itself has zero error; draw it at the floor of the log axis
    for model in ("chain_mail", "rod"):
        mrows = [r for r in rows if r.get("model", "chain_mail") == model and r.get("limits", "given") == "given"]
        segments = sorted({r["segments"] for r in mrows})
        for si, n in enumerate(segments):
            colour = maps[model](0.35 + 0.65 * si / max(len(segments) - 1, 1))
            for mi, sp in enumerate(spacings):
                series = sorted((r for r in mrows if r["segments"] == n and r["sdf_spacing_mm"] == sp),
                                key=lambda r: r["passes"])
                if not series:
                    continue
                xs = [r.get("wire_median_ms", r["median_ms"]) for r in series]
                ys = [max(r["tip_rms_mm"], floor) for r in series]
                ax.plot(xs, ys, "-", color=colour, alpha=0.35, linewidth=1)
                ax.scatter(xs, ys, color=colour, marker=markers[mi % len(markers)], s=28,
                           label=f"{model} {n} seg, {sp} mm")
                for r, x, y in zip(series, xs, ys):
                    ax.annotate(str(r["passes"]), (x, y), textcoords="offset points", xytext=(3, 3), fontsize=6)
    # the chain-mail with its limits derived from the section: stars
    for limits, colour in (("nitinol_core", "tab:green"), ("steel_core", "tab:olive")):
        for r in (r for r in rows if r.get("limits") == limits):
            ax.scatter([r.get("wire_median_ms", r["median_ms"])], [max(r["tip_rms_mm"], floor)], color=colour,
                       marker="*", s=80,
                       label=f"chain_mail {r['segments']} seg, {limits} limits, {r['sdf_spacing_mm']} mm")
    ref = report.get("reference", {})
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("the wire's median ms per physics step (guidewire, contact, friction; single thread)")
    ax.set_ylabel("tip RMS distance from the reference (mm)")
    ax.set_title("Guidewire, both models: accuracy vs cost (labels: chain-mail passes / rod substeps)\n"
                 f"reference: rod {ref.get('segments')} seg, {ref.get('substeps')} substeps, "
                 f"{ref.get('sdf_spacing_mm')} mm SDF; {report.get('machine', '')}", fontsize=9)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=6, ncol=3, loc="best")
    fig.tight_layout()
    fig.savefig(argv[2], dpi=130)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
