"""Plot for pcisim-bench xray: error vs ms per projector and detector.

Reads DIR/xray.json (this machine) and any DIR/xray.<machine>.json (runs on other machines, e.g.
xray.h200.json from the GPU machine); writes DIR/xray.png."""
import glob
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "docs/benchmarks"
reports = {"this machine": json.load(open(f"{out}/xray.json"))}
for path in sorted(glob.glob(f"{out}/xray.*.json")):
    reports[os.path.basename(path)[len("xray."):-len(".json")]] = json.load(open(path))
report = reports["this machine"]
fig, ax = plt.subplots(figsize=(8, 5))
series = {}
exacts = []
for name, rep in reports.items():
    for r in rep["rows"]:
        if r["projector"] == "exact":
            exacts.append((name, r))
            continue
        series.setdefault((name, r["projector"], r["detector"]), []).append(r)
for (name, proj, det), rs in sorted(series.items()):
    rs.sort(key=lambda r: r["step_voxels"])
    ms = [r["median_ms"] for r in rs]
    err = [100 * r["rmse_rel"] for r in rs]
    ax.plot(ms, err, "o-" if name == "this machine" else "s--", label=f"{proj} {det}$^2$ ({name})")
    for r, x, y in zip(rs, ms, err):
        ax.annotate(f'{r["step_voxels"]:g}', (x, y), textcoords="offset points", xytext=(4, 4), fontsize=7)
ymax = max(100 * r["rmse_rel"] for rs in series.values() for r in rs) if series else 1
for name, r in exacts:
    ax.axvline(r["median_ms"], color="grey", ls=":", lw=1)
    ax.text(r["median_ms"], ymax, f' exact {r["detector"]}$^2$ ({name})', rotation=90, va="top", fontsize=6,
            color="grey")
ax.set_xscale("log")
ax.set_yscale("log")
ax.set_xlabel("ms per frame (median)")
ax.set_ylabel("RMSE vs exact, % of max line integral")
others = "; ".join(f"{n}: {r['machine']}, {r.get('gpu') or 'no GPU'}" for n, r in reports.items() if n != "this machine")
ax.set_title(f"DRR error vs time (labels: step in voxels)\nthis machine: {report['machine']}" + (f"\n{others}" if others else ""),
             fontsize=7)
ax.grid(True, which="both", alpha=0.3)
ax.legend(fontsize=6, loc="upper right")
fig.tight_layout()
fig.savefig(f"{out}/xray.png", dpi=110)
