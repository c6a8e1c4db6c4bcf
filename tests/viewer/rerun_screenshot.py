#!/usr/bin/env python3
"""Does the real Rerun viewer open an orbitlash log with its plots?

    python tests/viewer/rerun_screenshot.py LOG.mcap SHOT.png [--cells COLSxROWS]

Exports the log with viewer/rerun_export.py, opens the .rrd in the Rerun viewer under
Xvfb with software rendering (Mesa's llvmpipe Vulkan), saves what it shows with
`rerun --screenshot-to`, and checks the screenshot: the first tab's views laid out as
COLS × ROWS cells (2x3 for the reference log: three temperature views beside backlash,
heat flows and the eclipse flag) must each hold plotted lines, i.e. enough saturated
pixels (the viewer's chrome is grey; series are coloured). A viewer that opened the
raw MCAP would show a table and fail here.

Exit 0 = plots seen (or a SKIP line when no X server or viewer can start here),
1 = the viewer showed no plot in some view, 2 = the check could not run.
"""
import argparse
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
EXPORT = os.path.join(HERE, "..", "..", "viewer", "rerun_export.py")


def refusal(shot, log):
    """Why the screenshot must not be written at `shot` (a phrase), or None."""
    same = os.path.realpath(shot) == os.path.realpath(log)
    if not same and os.path.exists(shot) and os.path.exists(log):
        same = os.path.samefile(shot, log)  # a hard link
    if same:
        return "it is the log itself"
    if os.path.islink(shot):
        return "it is a symbolic link (give the file itself, or another name)"
    if os.path.lexists(shot) and not os.path.isfile(shot):
        return "it is not a regular file"
    return None


def main():
    p = argparse.ArgumentParser()
    p.add_argument("log")
    p.add_argument("shot")
    p.add_argument("--cells", default="2x3")
    a = p.parse_args()
    cols, rows = (int(x) for x in a.cells.split("x"))
    # ORBITLASH_REQUIRE_VIEWER=1 (CI): a viewer that cannot start is a failure, not a skip
    strict = os.environ.get("ORBITLASH_REQUIRE_VIEWER") == "1"
    why = refusal(a.shot, a.log)
    if why:
        print(f"FAIL: will not write the screenshot {a.shot}: {why}")
        return 2
    rerun = shutil.which("rerun", path=os.path.dirname(sys.executable)) or shutil.which("rerun")
    xvfb = shutil.which("xvfb-run")
    if not rerun or not xvfb:
        print(f"{'FAIL' if strict else 'SKIP'}: the Rerun viewer cannot start here ({'no rerun' if not rerun else 'no xvfb-run'})")
        return 1 if strict else 0
    rrd = os.path.splitext(a.shot)[0] + ".rrd"
    r = subprocess.run([sys.executable, EXPORT, a.log, "-o", rrd])
    if r.returncode != 0:
        print("FAIL: viewer/rerun_export.py could not export the log")
        return 2
    if os.path.exists(a.shot):
        os.remove(a.shot)
    env = dict(os.environ, XDG_RUNTIME_DIR=os.environ.get("XDG_RUNTIME_DIR", "/tmp"))
    # The X pointer rests at the screen's centre: a screen far larger than the window
    # keeps it off the window, so no hover tooltip is in the screenshot.
    cmd = [xvfb, "-a", "-s", "-screen 0 6400x4000x24", rerun, rrd,
           "--screenshot-to", a.shot, "--window-size", "1500x900"]
    try:
        v = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    except subprocess.TimeoutExpired:
        print("FAIL: the viewer did not save a screenshot within 300 s")
        return 1
    if v.returncode != 0 or not os.path.exists(a.shot):
        tail = "\n".join(v.stderr.strip().splitlines()[-5:])
        if not strict and any(w in v.stderr.lower() for w in ("adapter", "vulkan", "display")):
            print(f"SKIP: the Rerun viewer could not start a renderer here:\n{tail}")
            return 0
        print(f"FAIL: the viewer exited {v.returncode} without a screenshot:\n{tail}")
        return 1

    import numpy as np
    from PIL import Image

    img = np.asarray(Image.open(a.shot).convert("RGB")).astype(int)
    h, w, _ = img.shape
    saturated = (img.max(axis=2) - img.min(axis=2)) > 60
    # The views sit between the tab bar (top 7 %) and the time panel (bottom 5 %).
    top, bottom = int(0.07 * h), int(0.95 * h)
    bad = []
    for i in range(cols):
        for j in range(rows):
            y0 = top + (bottom - top) * j // rows
            y1 = top + (bottom - top) * (j + 1) // rows
            x0, x1 = w * i // cols, w * (i + 1) // cols
            share = saturated[y0:y1, x0:x1].mean()
            print(f"[rerun] view cell ({i}, {j}): {100 * share:.2f} % coloured pixels")
            if share < 0.003:
                bad.append((i, j))
    print(f"[rerun] screenshot {a.shot}: {w}×{h}")
    if bad:
        print(f"FAIL: no plot in view cell(s) {bad}")
        return 1
    print("RESULT: OK, the viewer shows plots in every view")
    return 0


if __name__ == "__main__":
    sys.exit(main())
