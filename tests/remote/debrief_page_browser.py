#!/usr/bin/python3
"""debrief.html in headless Chromium with no network (issue #35): the page a session writes opens
from the file alone and renders its figures and pictures.

Makes the sample page (pcisim_server_tests' DebriefPage test writes it from a scripted session),
opens it in Chromium inside a private network namespace with only loopback, and checks the DOM
Chromium built (the figures' rows, the pictures' elements, the embedded frame decoded) and the
screenshot's pixels (the path drawn green and red, the beam's bar blue, the frame grey). Leaves
the screenshot in --out. Exits 77 (skip) when namespaces or Chromium are missing.
"""
import argparse, os, shutil, struct, subprocess, sys, tempfile, zlib

SKIP = 77


def skip(why):
    print("debrief_page_browser: SKIP: " + why)
    sys.exit(SKIP)


def read_png_rgb(path):
    """8-bit RGB or RGBA, not interlaced (what Chromium's screenshots are): rows of (r, g, b)."""
    data = open(path, "rb").read()
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and colour in (2, 6) and interlace == 0, "unexpected PNG format"
            channels = 3 if colour == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for r in range(height):
        f = raw[r * (stride + 1)]
        line = bytearray(raw[r * (stride + 1) + 1:(r + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = previous[i]
            c = previous[i - channels] if i >= channels else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append([tuple(line[k:k + 3]) for k in range(0, stride, channels)])
        previous = line
    return rows


def count_near(rows, colour, tolerance=40):
    return sum(1 for row in rows for px in row if all(abs(px[k] - colour[k]) <= tolerance for k in range(3)))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--build", required=True)
    ap.add_argument("--source", required=True)
    ap.add_argument("--out", required=True)
    args = ap.parse_args()
    if os.environ.get("PCISIM_IN_NETNS") != "1":
        if not (shutil.which("chromium") or shutil.which("chromium-browser")):
            skip("Debian chromium is not installed (scripts/setup installs it)")
        return subprocess.call([os.path.join(args.source, "scripts/in-private-netns"), sys.executable] + sys.argv)

    os.makedirs(args.out, exist_ok=True)
    page = os.path.abspath(os.path.join(args.build, "tests", "debrief-page-sample.html"))
    subprocess.run([os.path.join(args.build, "tests", "pcisim_server_tests"), "--gtest_filter=DebriefPage.ASessions*"],
                   check=True, stdout=subprocess.DEVNULL)
    assert os.path.exists(page), "the DebriefPage test did not write " + page
    browser = shutil.which("chromium") or shutil.which("chromium-browser")
    profile = tempfile.mkdtemp(prefix="pcisim-chromium-")
    common = [browser, "--headless=new", "--no-sandbox", "--disable-gpu", "--hide-scrollbars",
              "--user-data-dir=" + profile, "--window-size=1000,1800"]
    try:
        dom = subprocess.run(common + ["--dump-dom", "file://" + page], check=True, capture_output=True, text=True,
                             timeout=90).stdout
        shot = os.path.join(args.out, "debrief-page.png")
        subprocess.run(common + ["--screenshot=" + shot, "file://" + page], check=True, capture_output=True,
                       timeout=90)
    finally:
        shutil.rmtree(profile, ignore_errors=True)

    print("debrief_page_browser: the DOM %d characters" % len(dom))
    # the DOM Chromium built: every figure row and picture
    for text in ("Procedure time (s)", "Fluoroscopy time, beam on (s)", "Air kerma at the reference point (mGy)",
                 "Tip path through the vessels (mm)", "Time off the route to the target (s)",
                 "Force events above the risk force", "LAO 40 / CRA 25"):
        assert text in dom, "missing in the rendered page: " + text
    for element in ('class="pathon"', 'class="pathoff"', 'class="pathref"', 'class="fluoro"', 'class="forceline"',
                    "data:image/png;base64,"):
        assert element in dom, "missing in the rendered page: " + element
    # the screenshot: the pictures drawn (their colours as the page's style gives them)
    rows = read_png_rgb(shot)
    found = {name: count_near(rows, colour) for name, colour in (
        ("path on the route", (0x2e, 0xcc, 0x40)), ("path off the route", (0xff, 0x41, 0x36)),
        ("the beam's bar", (0x4a, 0x90, 0xd9)), ("the cine bar", (0xe0, 0x8a, 0x1e)))}
    print("debrief_page_browser: pixels " + ", ".join("%s %d" % kv for kv in found.items()))
    for name, n in found.items():
        assert n >= 30, "the screenshot shows too little of " + name
    print("debrief_page_browser: PASS (%s)" % shot)
    return 0


if __name__ == "__main__":
    sys.exit(main())
