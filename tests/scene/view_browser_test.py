#!/usr/bin/env python3
"""`kanesim view --html` in a real browser: Debian's chromium, headless, WebGL through
SwiftShader, driven over the DevTools protocol (tests/viz/cdp.py).

The page was written by `kanesim view shapes.mech --html`; the CSV by `kanesim run` of the same
model with every frame position and body rotation. What would be wrong if it failed: the
viewer does not show the simulated motion — a body missing, or drawn somewhere else than its
frame (p_WB) or turned otherwise than R_WB at an output instant or between two (where the page
interpolates; the CSV of a run at a 4x finer interval gives the truth there), or the page has
errors, or it asks for something outside the file.

Usage: view_browser_test.py --page P.html --csv C.csv --fine F.csv --body NAME=FRAME:BODY ...
                            [--png OUT.png]   (then a 1000x560 screenshot at mid-run, for the docs)
"""
import argparse
import csv
import math
import os
import pathlib
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "viz"))
import cdp  # noqa: E402

# Poses reach the page as float32 and are multiplied by three.js in double: ~1e-6 at an
# instant. Between instants the page interpolates (lerp, slerp) where the simulation moves on
# a curve: the chord error of motion at these speeds over 0.01 s is below 2e-3.
AT_INSTANT = 5e-6
BETWEEN = 2e-3
failures = []


def check(ok, message):
    if not ok:
        failures.append(message)
    return ok


def read_csv(path):
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    return {name: [float(r[i]) for r in rows[1:]] for i, name in enumerate(rows[0])}


def check_poses(page, cols, k, bodies, tol, where):
    shown = page.evaluate("kanesimViewer.bodyPoses()")
    for name, (frame, body) in bodies.items():
        got = shown.get(name)
        if not check(got is not None, f"{where}: no body {name} on the page (has {sorted(shown)})"):
            continue
        p = [cols[f"{frame}.r[{i + 1}]"][k] for i in range(3)]
        R = [[cols[f"{body}.R[{i + 1},{j + 1}]"][k] for j in range(3)] for i in range(3)]
        dp = max(abs(a - b) for a, b in zip(got["p"], p))
        dr = max(abs(got["R"][i][j] - R[i][j]) for i in range(3) for j in range(3))
        check(dp <= tol, f"{where}: {name} at {got['p']}, simulated {p} (off by {dp:.2e})")
        check(dr <= tol, f"{where}: {name} turned {got['R']}, simulated {R} (off by {dr:.2e})")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--chromium", default="chromium")
    ap.add_argument("--page", required=True)
    ap.add_argument("--csv", required=True)
    ap.add_argument("--fine", required=True)
    ap.add_argument("--body", action="append", required=True)
    ap.add_argument("--png")
    args = ap.parse_args()
    bodies = {}
    for item in args.body:
        name, spec = item.split("=", 1)
        bodies[name] = tuple(spec.split(":"))
    cols, fine = read_csv(args.csv), read_csv(args.fine)
    times, fine_times = cols["time"], fine["time"]
    url = pathlib.Path(args.page).resolve().as_uri()
    with cdp.Chromium(args.chromium, 1200, 700) as browser:
        page = browser.new_page(1200, 700)
        k0 = len(times) // 3
        page.navigate(f"{url}?t={times[k0]}")
        page.wait_for("window.kanesimViewer && (kanesimViewer.ready || kanesimViewer.failed)", 60, "page ready")
        errors = page.evaluate("kanesimViewer.errors")
        if check(page.evaluate("kanesimViewer.ready") and not errors, f"the page failed: {errors}"):
            check_poses(page, cols, k0, bodies, AT_INSTANT, f"?t={times[k0]}")
            for k in (0, 1, len(times) // 2, len(times) - 1):
                page.evaluate(f"kanesimViewer.seek({times[k]})")
                check_poses(page, cols, k, bodies, AT_INSTANT, f"seek({times[k]})")
            # Between instants: the fine run's rows that fall between two output instants.
            for kf in (6, len(fine_times) // 2 + 2, len(fine_times) - 3):
                t = fine_times[kf]
                if min(abs(t - x) for x in times) < 1e-9:
                    continue
                page.evaluate(f"kanesimViewer.seek({t})")
                check_poses(page, fine, kf, bodies, BETWEEN, f"seek({t}) between instants")
        urls = [e["request"]["url"] for e in page.events("Network.requestWillBeSent")]
        outside = [u for u in urls if not (u.startswith(url) or u.startswith("data:") or u.startswith("blob:"))]
        check(not outside, f"requests outside the file: {outside}")
    if args.png and not failures:
        with cdp.Chromium(args.chromium, 1000, 560) as browser:
            page = browser.new_page(1000, 560)
            page.navigate(f"{url}?t={times[len(times) // 2]}")
            page.wait_for("window.kanesimViewer && kanesimViewer.ready", 60, "page ready")
            page.wait_for("new Promise(r => requestAnimationFrame(() => requestAnimationFrame(() => r(true))))", 10)
            png = page.screenshot()
            check(png.startswith(b"\x89PNG"), "the screenshot is not a PNG")
            pathlib.Path(args.png).write_bytes(png)
    for f in failures:
        print("FAIL:", f)
    print(f"view page: {len(bodies)} bodies: {'FAILED' if failures else 'passed'}")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
