# plots pcisim-bench rod's results: the rod's tip error against the exact elastica, against the
# time per 30 Hz step, one series per segment count. usage: rod.py rod.json rod.png
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = json.load(open(sys.argv[1]))
cases = []
for r in rows:
    key = (r["case"], r["load"])
    if key not in cases:
        cases.append(key)
fig, axes = plt.subplots(1, len(cases), figsize=(5 * len(cases), 4.5), squeeze=False)
for ax, (case, load) in zip(axes[0], cases):
    pts = [r for r in rows if r["case"] == case and r["load"] == load]
    for n in sorted({r["segments"] for r in pts}):
        color = None
        for solver, marker, ls in (("gauss_seidel", "o", "-"), ("direct", "s", "--")):
            s = sorted([r for r in pts if r["segments"] == n and r.get("solver", "gauss_seidel") == solver],
                       key=lambda r: r["ms_p50"])
            if not s:
                continue
            line = ax.plot([r["ms_p50"] for r in s], [max(abs(r["error_pct"]), 1e-4) for r in s], marker=marker,
                           ls=ls, color=color, label=f"{n} segments, {solver.replace('_', '-')}")[0]
            color = line.get_color()
        ax.axhline(max(abs(s[0]["static_error_pct"]), 1e-4), lw=0.6, ls=":", color=color)
    ax.axhline(1.0, color="k", lw=0.8, ls="--")
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.set_xlabel("ms per 30 Hz step (median, 2-core machine)")
    ax.set_ylabel("|tip error| against the elastica (%)")
    ax.set_title(f"{case}, load {load:g}")
    ax.grid(alpha=0.3, which="both")
axes[0][0].legend(fontsize=7)
fig.suptitle("Cosserat rod: accuracy against time (circles: Gauss-Seidel, squares: direct; dotted: converged "
             "equilibrium; dashed: 1 %)")
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=90)
