"""OV and false centerline per case of the phantom family (pcisim-bench model --family N):
each split's cases sorted, the targets dashed. Usage: model-family.py model-family.json out.png"""
import json
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt

rows = json.load(open(sys.argv[1]))
groups = []
for r in rows:
    if r["group"] not in groups:
        groups.append(r["group"])
fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4))
for g in groups:
    ov = sorted(0.0 if r["failed"] else r["ov"] for r in rows if r["group"] == g)
    fa = sorted(r["false_mm"] for r in rows if r["group"] == g and not r["failed"])
    a.plot(range(1, len(ov) + 1), ov, "o-", label=g)
    b.plot(range(1, len(fa) + 1), fa, "o-", label=g)
a.axhline(0.95, ls="--", c="gray", lw=1)
a.axhline(0.90, ls=":", c="gray", lw=1)
a.set_xlabel("case (sorted)")
a.set_ylabel("OV")
a.set_ylim(0, 1.02)
a.set_title("overlap (target: median 0.95, 5 % tail 0.90)")
a.legend()
b.axhline(10, ls="--", c="gray", lw=1)
b.axhline(40, ls=":", c="gray", lw=1)
b.set_yscale("symlog", linthresh=10)
b.set_xlabel("case (sorted)")
b.set_ylabel("false centerline, mm")
b.set_title("false centerline (target: median 10, worst 40 mm)")
b.legend()
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=90)
