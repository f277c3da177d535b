#!/usr/bin/python3
"""A contact sheet of captured fluoroscopy frames (pcisim-capture's PNG + JSON sidecars).

  scripts/contact_sheet.py FRAMES_DIR OUT.png [--first-s T] [--count N] [--every K] [--cols C]
                           [--crop X0 Y0 W H] [--title TEXT] [--gif OUT.gif] [--dpi D]

Takes N frames from FRAMES_DIR (frame_NNNNNN.png, sorted), every K-th, starting at the first
frame whose sidecar's sim_time_s >= T; labels each with its simulation time and, when the
sidecar has it, the heart phase. --gif also writes the picked frames as an animated GIF at
half size, looping, at the capture's frame rate. Needs python3-matplotlib (and, for --gif,
python3-pil: both Debian's).
"""
import argparse
import glob
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.image as mpimg  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("frames_dir")
    ap.add_argument("out_png")
    ap.add_argument("--first-s", type=float, default=0.0)
    ap.add_argument("--count", type=int, default=8)
    ap.add_argument("--every", type=int, default=1)
    ap.add_argument("--cols", type=int, default=4)
    ap.add_argument("--crop", type=int, nargs=4, metavar=("X0", "Y0", "W", "H"))
    ap.add_argument("--title", default="")
    ap.add_argument("--gif")
    ap.add_argument("--dpi", type=int, default=110)
    a = ap.parse_args()
    if a.count < 1 or a.every < 1 or a.cols < 1:
        sys.exit("contact_sheet: --count, --every and --cols must be >= 1")
    pngs = sorted(glob.glob(os.path.join(a.frames_dir, "frame_*.png")))
    if not pngs:
        sys.exit(f"contact_sheet: no frame_*.png in {a.frames_dir}")
    picked = []
    for p in pngs:
        side = p[:-4] + ".json"
        meta = json.load(open(side)) if os.path.exists(side) else {}
        t = meta.get("sim_time_s", 0.0)
        if t < a.first_s:
            continue
        picked.append((p, meta))
    picked = picked[:: a.every][: a.count]
    if not picked:
        sys.exit(f"contact_sheet: no frame at or after {a.first_s} s")
    rows = (len(picked) + a.cols - 1) // a.cols
    fig, axes = plt.subplots(rows, a.cols, figsize=(3.2 * a.cols, 3.4 * rows), squeeze=False)
    for ax in axes.flat:
        ax.axis("off")
    for ax, (p, meta) in zip(axes.flat, picked):
        img = mpimg.imread(p)
        if a.crop:
            x0, y0, w, h = a.crop
            img = img[y0 : y0 + h, x0 : x0 + w]
        ax.imshow(img, cmap="gray", vmin=0, vmax=1)
        label = f"t = {meta.get('sim_time_s', 0.0):.3f} s"
        if "heart_phase" in meta:
            label += f", phase {meta['heart_phase']:.2f}"
        ax.set_title(label, fontsize=9)
    if a.title:
        fig.suptitle(a.title, fontsize=11)
    fig.tight_layout()
    fig.savefig(a.out_png, dpi=a.dpi)
    print(f"contact_sheet: {len(picked)} frames -> {a.out_png}")
    if a.gif:
        from PIL import Image

        frames = []
        for p, _ in picked:
            img = mpimg.imread(p)
            if a.crop:
                x0, y0, w, h = a.crop
                img = img[y0 : y0 + h, x0 : x0 + w]
            g = Image.fromarray((255 * img).clip(0, 255).astype("uint8"))
            frames.append(g.resize((g.width // 2, g.height // 2)))
        times = [m.get("sim_time_s", 0.0) for _, m in picked]
        step_ms = 1000 * (times[-1] - times[0]) / max(1, len(times) - 1) if len(times) > 1 else 100
        frames[0].save(a.gif, save_all=True, append_images=frames[1:], duration=max(20, int(step_ms)), loop=0)
        print(f"contact_sheet: {len(frames)} frames -> {a.gif}")


if __name__ == "__main__":
    main()
