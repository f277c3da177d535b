"""Plot for pcisim-bench xray: error vs ms per projector and detector (reads DIR/xray.json, writes DIR/xray.png)."""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks"
report = json.load(open(f"{out}/xray.json"))
fig, ax = plt.subplots(figsize=(7, 4.5))
series = {}
for r in report["rows"]:
    if r["projector"] == "exact":
        continue
    series.setdefault((r["projector"], r["detector"]), []).append(r)
for (proj, det), rs in sorted(series.items()):
    rs.sort(key=lambda r: r["step_voxels"])
    ms = [r["median_ms"] for r in rs]
    err = [100 * r["rmse_rel"] for r in rs]
    ax.plot(ms, err, "o-", label=f"{proj} {det}$^2$")
    for r, x, y in zip(rs, ms, err):
        ax.annotate(f'{r["step_voxels"]:g}', (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
for r in report["rows"]:
    if r["projector"] == "exact":
        ax.axvline(r["median_ms"], color="grey", ls=":", lw=1)
        ax.text(r["median_ms"], ax.get_ylim()[1] if ax.lines else 1, f' exact {r["detector"]}$^2$', rotation=90,
                va="top", fontsize=7, color="grey")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("ms per frame (median)")
ax.set_ylabel("RMSE vs exact, % of max line integral")
gpu = report.get("gpu") or "no GPU"
ax.set_title(f"DRR error vs time (labels: step in voxels)\n{report['machine']}; {gpu}", fontsize=8)
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(f"{out}/xray.png", dpi=110)
