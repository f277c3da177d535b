#!/usr/bin/python3
"""A contact sheet of a pcisim labelled dataset (pcisim-dataset's folder), labels drawn over the frames.

  scripts/dataset_contact_sheet.py DIR OUT.png [--samples N] [--frame K|--frame last] [--cols C]
                                   [--dpi D] [--title TEXT]

Takes the first N samples of DIR/manifest.json and frame K of each (default the last one), and
draws one tile per sample, C tiles a row. A tile is two panels: the plain frame, and the same
frame with its labels: the contrast mask tinted by branch (branches_FFFF.png), each branch with
visible contrast as a thin centerline in its colour, the wire's projected polyline in yellow, its
keypoints as cyan dots and its tip as a red circle. Each tile's title has the sample, the frame,
the C-arm angles and the branch the tip is in. Missing files are skipped; exits 2 when DIR has no
sample to draw. Needs python3-matplotlib, python3-numpy and python3-pil (all Debian's).
"""
import argparse
import glob
import json
import os
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
from PIL import Image  # noqa: E402

# qualitative branch colours, leaving out tab20's red, grey, olive and cyan (used for the wire marks)
BRANCH_COLOURS = ListedColormap([plt.get_cmap("tab20")(i) for i in (0, 2, 4, 8, 10, 12, 5, 9, 3, 13, 11, 1)])
MASK_ALPHA = 0.35
# layout, in inches
PANEL_IN = 2.4
PANEL_GAP_IN = 0.04
TILE_GAP_IN = 0.18
TILE_TITLE_IN = 0.26
MARGIN_IN = 0.08
TITLE_IN = 0.28
LEGEND_ROW_IN = 0.24
LEGEND_WRAP_IN = 9.0  # narrower sheets put the branch colours on a row of their own


def frame_arg(s):
    if s == "last":
        return s
    if not re.fullmatch(r"\d+", s):
        raise argparse.ArgumentTypeError("must be a frame number >= 0 or 'last'")
    return int(s)


def branch_colour(label):
    return BRANCH_COLOURS((int(label) - 1) % BRANCH_COLOURS.N)


def load_json(path):
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return None


def load_png(path):
    try:
        return np.array(Image.open(path))
    except OSError:
        return None


def sample_dirs(root, count):
    """(sample number, folder) of the first count samples: the manifest's, else whatever samples/* has."""
    manifest = load_json(os.path.join(root, "manifest.json"))
    picked = []
    if manifest and manifest.get("samples"):
        for i, s in enumerate(manifest["samples"]):
            d = os.path.join(root, s.get("dir", f"samples/{s.get('sample', i):07d}"))
            picked.append((s.get("sample", i), d))
    else:
        for d in sorted(glob.glob(os.path.join(root, "samples", "*"))):
            if os.path.isdir(d) and os.path.basename(d).isdigit():
                picked.append((int(os.path.basename(d)), d))
    return [(n, d) for n, d in picked if os.path.isdir(d)][:count], manifest


def last_frame(sdir):
    nums = [int(m.group(1)) for p in glob.glob(os.path.join(sdir, "frame_*.png"))
            if (m := re.fullmatch(r"frame_(\d+)\.png", os.path.basename(p)))]
    return max(nums) if nums else None


def split_polyline(points):
    """runs of [c, r] points between the nulls, as (cols, rows) arrays."""
    runs, run = [], []
    for p in list(points or []) + [None]:
        if p is None:
            if len(run) > 1:
                a = np.array(run, dtype=float)
                runs.append((a[:, 0], a[:, 1]))
            run = []
        else:
            run.append(p[:2])
    return runs


def angle_text(deg, pos, neg):
    v = round(float(deg), 1)
    if v == 0:
        return f"{pos}/{neg} 0.0"
    return f"{pos if v > 0 else neg} {abs(v):.1f}"


def tile_title(sample, k, meta):
    arm = (meta or {}).get("c_arm") or {}
    wire = (meta or {}).get("wire") or {}
    parts = [f"sample {sample} frame {k}"]
    if "primary_deg" in arm and "secondary_deg" in arm:
        parts[0] += ": " + angle_text(arm["primary_deg"], "LAO", "RAO")
        parts.append(angle_text(arm["secondary_deg"], "CRA", "CAU"))
    if meta is not None:
        parts.append(f"tip in {wire.get('tip_branch') or 'none'}")
    return ", ".join(parts)


def branch_names(tiles):
    """label -> names of the branches with visible contrast in the tiles (one name unless samples disagree)."""
    names = {}
    for t in tiles:
        for v in ((t["meta"] or {}).get("vessels") or []):
            if v.get("contrast_visible"):
                names.setdefault(v.get("label", 0), set()).add(v.get("branch", "?"))
    return {lab: "/".join(sorted(n)) for lab, n in sorted(names.items())}


def draw_labels(ax, meta, branches, mask, shape):
    # contrast mask tinted by branch, clear where there is none
    if branches is not None or mask is not None:
        tint = np.zeros(shape + (4,))
        if mask is not None and mask.shape == shape:
            tint[mask > 0] = (1, 1, 1, MASK_ALPHA)  # masked but with no branch: white
        if branches is not None and branches.shape == shape:
            for label in np.unique(branches):
                if label:
                    tint[branches == label] = branch_colour(label)[:3] + (MASK_ALPHA,)
        ax.imshow(tint, interpolation="nearest")
    if meta is None:
        return
    for v in meta.get("vessels") or []:
        if not v.get("contrast_visible"):
            continue
        for c, r in split_polyline(v.get("points_px")):
            ax.plot(c, r, color=branch_colour(v.get("label", 0)), lw=0.6)
    wire = meta.get("wire") or {}
    for c, r in split_polyline(wire.get("nodes_px")):
        ax.plot(c, r, color="yellow", lw=0.6)
    kp = np.array([p for p in wire.get("keypoints") or [] if p and len(p) > 2 and p[2] > 0], dtype=float)
    if len(kp):
        ax.plot(kp[:, 0], kp[:, 1], ls="none", marker="o", ms=1.8, mew=0, color="cyan")
    tip = wire.get("tip_px")
    if tip:
        ax.plot([tip[0]], [tip[1]], ls="none", marker="o", ms=6, mew=0.8, mfc="none", color="red")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("dataset_dir")
    ap.add_argument("out_png")
    ap.add_argument("--samples", type=int, default=8)
    ap.add_argument("--frame", type=frame_arg, default="last", metavar="K|last")
    ap.add_argument("--cols", type=int, default=4)
    ap.add_argument("--dpi", type=int, default=150)
    ap.add_argument("--title", default="")
    a = ap.parse_args()
    if a.samples < 1 or a.cols < 1 or a.dpi < 1:
        sys.exit("dataset_contact_sheet: --samples, --cols and --dpi must be >= 1")
    dirs, manifest = sample_dirs(a.dataset_dir, a.samples)

    # gather what exists of each picked sample's frame
    tiles = []
    for sample, sdir in dirs:
        k = last_frame(sdir) if a.frame == "last" else a.frame
        frame = load_png(os.path.join(sdir, f"frame_{k:04d}.png")) if k is not None else None
        if frame is None or frame.ndim != 2:
            print(f"dataset_contact_sheet: skipping {sdir}: no frame {a.frame}", file=sys.stderr)
            continue
        tiles.append({
            "sample": sample, "k": k, "frame": frame,
            "meta": load_json(os.path.join(sdir, f"frame_{k:04d}.json")),
            "mask": load_png(os.path.join(sdir, f"mask_{k:04d}.png")),
            "branches": load_png(os.path.join(sdir, f"branches_{k:04d}.png")),
        })
    if not tiles:
        what = f"no sample has frame {a.frame}" if dirs else "no samples"
        print(f"dataset_contact_sheet: nothing to draw in {a.dataset_dir}: {what}", file=sys.stderr)
        sys.exit(2)

    # fixed layout: header (title, legend rows), then rows of tiles (title over two panels)
    marks = [
        Patch(facecolor=(1, 1, 1, 0.5), label="contrast mask"),
        Line2D([], [], color="white", lw=0.8, label="centerline"),
        Line2D([], [], color="yellow", lw=0.8, label="wire"),
        Line2D([], [], ls="none", marker="o", ms=3, mew=0, color="cyan", label="keypoints"),
        Line2D([], [], ls="none", marker="o", ms=6, mew=0.8, mfc="none", color="red", label="tip"),
    ]
    colours = [Patch(facecolor=branch_colour(lab), label=name) for lab, name in branch_names(tiles).items()]
    h, w = tiles[0]["frame"].shape
    pw, ph = PANEL_IN, PANEL_IN * h / w
    tile_w = 2 * pw + PANEL_GAP_IN
    cols = min(a.cols, len(tiles))
    rows = (len(tiles) + cols - 1) // cols
    fig_w = 2 * MARGIN_IN + cols * tile_w + (cols - 1) * TILE_GAP_IN
    legends = [marks + colours] if fig_w >= LEGEND_WRAP_IN or not colours else [marks, colours]
    header = TITLE_IN + LEGEND_ROW_IN * len(legends) + 0.08
    fig_h = header + rows * (TILE_TITLE_IN + ph) + (rows - 1) * TILE_GAP_IN + MARGIN_IN
    fig = plt.figure(figsize=(fig_w, fig_h), facecolor="black")
    for i, t in enumerate(tiles):
        row, col = divmod(i, cols)
        x0 = MARGIN_IN + col * (tile_w + TILE_GAP_IN)
        y_top = fig_h - header - row * (TILE_TITLE_IN + ph + TILE_GAP_IN)
        label = tile_title(t["sample"], t["k"], t["meta"])
        fig.text((x0 + tile_w / 2) / fig_w, (y_top - TILE_TITLE_IN / 2) / fig_h, label,
                 color="white", fontsize=7.5, ha="center", va="center")
        shape = t["frame"].shape
        for j in range(2):
            left, bottom = x0 + j * (pw + PANEL_GAP_IN), y_top - TILE_TITLE_IN - ph
            ax = fig.add_axes([left / fig_w, bottom / fig_h, pw / fig_w, ph / fig_h])
            ax.imshow(t["frame"], cmap="gray", vmin=0, vmax=65535, interpolation="nearest")
            if j == 1:
                draw_labels(ax, t["meta"], t["branches"], t["mask"], shape)
            # keep to the image, whatever the labels reach
            ax.set_xlim(-0.5, shape[1] - 0.5)
            ax.set_ylim(shape[0] - 0.5, -0.5)
            ax.axis("off")

    # header: title, then the legend of the marks and of the branch colours
    title = a.title
    if not title:
        name = (manifest or {}).get("name")
        title = os.path.basename(os.path.normpath(a.dataset_dir)) + (f" ({name})" if name else "")
        title += f": {len(tiles)} samples, frame {a.frame}"
    fig.text(0.5, 1 - TITLE_IN / 2 / fig_h, title, color="white", fontsize=10, ha="center", va="center")
    for i, handles in enumerate(legends):
        y = 1 - (TITLE_IN + LEGEND_ROW_IN * (i + 0.5)) / fig_h
        fig.legend(handles=handles, loc="center", bbox_to_anchor=(0.5, y), ncol=len(handles), frameon=False,
                   fontsize=6.5, labelcolor="white", handlelength=1.4, columnspacing=1.2, borderaxespad=0,
                   borderpad=0)
    fig.savefig(a.out_png, dpi=a.dpi, facecolor="black")
    print(f"dataset_contact_sheet: {len(tiles)} samples -> {a.out_png}")


if __name__ == "__main__":
    main()
