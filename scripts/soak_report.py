#!/usr/bin/env python3
"""Reads what scripts/soak left in its --out folder and writes the soak report: RSS over time per
process (plot, and the slope of a least-squares line after the first minute), the force checks,
frames published / captured / streamed, and every bad-input counter. Exits 1 when a check fails."""
import argparse, csv, json, os, platform, re, subprocess, sys, datetime
from collections import defaultdict


def machine():
    model = "unknown CPU"
    for line in open("/proc/cpuinfo"):
        if line.startswith("model name"):
            model = line.split(":", 1)[1].strip()
            break
    mem_gib = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2**30
    return f"{model}, {os.cpu_count()} cores, {mem_gib:.0f} GiB, {platform.system()} {platform.release()}"


def slope_per_min(ts, ys):
    n = len(ts)
    if n < 3:
        return float("nan")
    mt, my = sum(ts) / n, sum(ys) / n
    var = sum((t - mt) ** 2 for t in ts)
    return sum((t - mt) * (y - my) for t, y in zip(ts, ys)) / var * 60 if var > 0 else float("nan")


def last_match(path, pattern):
    if not os.path.exists(path):
        return None
    m = None
    for line in open(path, errors="replace"):
        mm = re.search(pattern, line)
        if mm:
            m = mm
    return m


def load(path, default=None):
    try:
        return json.load(open(path))
    except (OSError, ValueError):
        return default


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--out", required=True)
    ap.add_argument("--report")
    a = ap.parse_args()
    out = a.out
    logs = os.path.join(out, "logs")

    rss = defaultdict(list)
    with open(os.path.join(out, "rss.csv")) as f:
        for row in csv.DictReader(f):
            rss[row["process"]].append((float(row["t_s"]), int(row["rss_kb"]) / 1024.0))
    console = load(os.path.join(out, "console.json"), {})
    flood = load(os.path.join(out, "flood.json"), {})
    stats = load(os.path.join(out, "stats.json"), {})
    observer = load(os.path.join(out, "observer.json"), {})

    failures = []
    rows = []
    for name, pts in sorted(rss.items()):
        half = pts[-1][0] / 2
        late = [(t, y) for t, y in pts if t >= half] or pts
        s = slope_per_min([t for t, _ in late], [y for _, y in late])
        rows.append((name, pts[0][1], max(y for _, y in pts), pts[-1][1], s))

    forces = console.get("forces", {})
    frames = console.get("frames", {})
    if forces.get("non_finite", 1) != 0:
        failures.append(f"non-finite force commands: {forces.get('non_finite')}")
    if forces.get("over_peak", 1) != 0:
        failures.append(f"force commands beyond the peak: {forces.get('over_peak')}")
    if forces.get("received", 0) == 0:
        failures.append("no force command received")
    cap = last_match(os.path.join(logs, "capture.log"), r"capture: (\d+) frames written.*?(\d+) undecodable")
    captured = int(cap.group(1)) if cap else None
    capture_bad = int(cap.group(2)) if cap else None
    # frames the server published while the capture ran: the capture puts each pipeline's frames
    # (numbered from 0 after every scene reload) in a folder of its own; in each, the first to the
    # last frame number is what was published, and a gap is a lost frame
    published = 0
    for folder, _, files in os.walk(os.path.join(out, "frames")):
        seqs = [load(os.path.join(folder, n), {}).get("frame") for n in files if n.endswith(".json")]
        seqs = [q for q in seqs if isinstance(q, int)]
        if seqs:
            published += max(seqs) - min(seqs) + 1
    if captured is None:
        failures.append("the capture did not report (crashed?)")
    elif captured < published:
        failures.append(f"frames lost: {published} published while the capture ran, {captured} captured")
    bridge = last_match(os.path.join(logs, "bridge.log"), r"(\d+) force commands received, (\d+) bad")
    remote = last_match(os.path.join(logs, "remote.log"), r"remote: done: (.*)")
    for name in ("server", "bridge", "capture", "remote", "console", "flood"):
        path = os.path.join(logs, f"{name}.log")
        if os.path.exists(path):
            text = open(path, errors="replace").read()
            for bad in ("AddressSanitizer", "terminate called", "Segmentation fault", "core dumped"):
                if bad in text:
                    failures.append(f"{name}: '{bad}' in its log")

    minutes = console.get("seconds", 0) / 60
    lines = [
        "# Soak and fault run",
        "",
        f"`scripts/soak --minutes {minutes:.1f}` on {machine()}, {datetime.date.today()}. Server (built-in scene), "
        "instrument bridge (a scripted trainee going into the LAD and back every 40 s), fluoroscopy capture, remote "
        "gateway with one observer page, an instructor console (beam on, a C-arm move every 5 s, contrast every 20 s, "
        "a scene reload every 2 min) and `pcisim-lcm-flood` publishing malformed messages on every channel, all over "
        "udpm inside a private network namespace. Regenerate with `scripts/soak --minutes 10 --report "
        "docs/benchmarks/soak.md`.",
        "",
        "## Memory",
        "",
        "RSS sampled every 5 s; the slope is a least-squares line through the second half of the run (the first "
        "half holds the start and the first scene reload, whose rebuild leaves the allocator holding more pages: a "
        "step, visible in the plot, not a growth).",
        "",
        "| process | RSS at start (MiB) | max (MiB) | at end (MiB) | slope (MiB/min) |",
        "|---|---|---|---|---|",
    ]
    for name, first, peak, last, s in rows:
        lines.append(f"| {name} | {first:.1f} | {peak:.1f} | {last:.1f} | {s:+.3f} |")
    if "server" in rss:
        per_min = []
        for minute in range(0, int(max(t for t, _ in rss["server"]) // 60) + 1):
            near = min(rss["server"], key=lambda p: abs(p[0] - 60 * minute))
            per_min.append(f"{near[1]:.1f}")
        lines += ["", f"Server RSS at each minute (MiB; scene reloads every 2 min): {', '.join(per_min)}."]
    lines += ["", "![RSS over time](soak.png)", "", "## Forces (every command the server sent, checked by the console)", ""]
    lines.append(
        f"{forces.get('received', 0)} force commands: {forces.get('non_finite', '?')} non-finite, "
        f"{forces.get('over_peak', '?')} beyond the scene's peak of {forces.get('peak_force_n', '?')} N; largest "
        f"|axial force| {forces.get('max_abs_force_n', float('nan')):.3f} N. "
        f"Messages on the force channel that were not the server's (the flood's): {forces.get('undecodable', '?')}.")
    lines += ["", "## Frames", ""]
    lines.append(
        f"Published by the server while the capture ran (from the frame numbers in the capture's sidecars, each "
        f"pipeline counting from 0, over {console.get('sent', {}).get('reloads', '?')} scene reloads): {published}; "
        f"written by the capture: {captured}; received by the console (which starts once the server runs): "
        f"{frames.get('received')}; streamed to the observer page: {observer.get('frames', '?')} (the gateway paces "
        f"pages; it drops frames for a slow page by design).")
    lines += ["", "## Bad input counted", "", "| where | count |", "|---|---|"]
    lines.append(f"| server, LCM messages dropped as bad (last pipeline) | {stats.get('lcm', {}).get('dropped_bad', '?')} |")
    for k, v in sorted(stats.get("session", {}).items()) if isinstance(stats.get("session"), dict) else []:
        lines.append(f"| server, session: {k} | {v} |")
    lines.append(f"| bridge, bad force commands | {bridge.group(2) if bridge else '?'} |")
    lines.append(f"| capture, undecodable frames | {capture_bad if capture_bad is not None else '?'} |")
    lines.append(f"| remote gateway | {remote.group(1) if remote else '?'} |")
    if flood:
        lines += ["", "## What the flood sent", "", "```", json.dumps(flood, indent=1)[:3000], "```"]
    lines += ["", "## Verdict", ""]
    lines.append("PASS: no crash, every force finite and within the peak, no frame lost." if not failures
                 else "FAIL:\n" + "\n".join(f"- {f}" for f in failures))
    text = "\n".join(lines) + "\n"
    open(os.path.join(out, "soak.md"), "w").write(text)

    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, ax = plt.subplots(figsize=(8, 4.5))
        for name, pts in sorted(rss.items()):
            ax.plot([t / 60 for t, _ in pts], [y for _, y in pts], label=name)
        ax.set_xlabel("time (min)")
        ax.set_ylabel("RSS (MiB)")
        ax.set_yscale("log")
        ax.set_title("pcisim soak: resident memory per process")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
        fig.tight_layout()
        fig.savefig(os.path.join(out, "soak.png"), dpi=110)
        if a.report:
            fig.savefig(os.path.join(os.path.dirname(a.report), "soak.png"), dpi=110)
    except ImportError:
        print("soak_report: matplotlib missing, no plot", file=sys.stderr)
    if a.report:
        open(a.report, "w").write(text)
    print(text)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
