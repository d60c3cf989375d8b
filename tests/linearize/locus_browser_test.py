#!/usr/bin/env python3
"""The root locus page of `kanesim linearize --sweep ... --html` in a real browser (Debian's
chromium, headless, driven over the DevTools protocol by tests/viz/cdp.py).

  locus_browser_test.py --chromium C --page locus.html --csv locus.csv

The page's test hook (window.kanesimLocus) reads back what its two dygraphs hold: every
point of the complex-plane plot and every row of the real-part plot. They must be the
eigenvalues of the CSV table that the same command wrote (to 1e-12), each point in the
colour bin of its parameter value, with no JavaScript error and no request leaving the file.
Exit 0 when every check passes; 1 with the failures listed.
"""
import argparse
import csv
import math
import os
import pathlib
import sys

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "viz"))
import cdp  # noqa: E402

TOL = 1e-12
failures = []


def check(ok, message):
    if not ok:
        failures.append(message)
    return ok


def close(a, b):
    if a is None or b is None:
        return a is None and b is None
    return abs(a - b) <= TOL * max(1.0, abs(a), abs(b))


def read_csv(path):
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = rows[0], rows[1:]
    m = (len(header) - 2) // 2
    check(header[-1] == "max_real" and len(header) == 2 * m + 2, f"CSV header {header}")
    num = lambda s: None if s in ("null", "") else float(s)  # noqa: E731
    values = [float(r[0]) for r in body]
    eig = [[(num(r[1 + 2 * k]), num(r[2 + 2 * k])) for k in range(m)] for r in body]
    return header[0], values, eig


def run(args):
    name, values, eig = read_csv(args.csv)
    n, m = len(values), len(eig[0]) if eig else 0
    check(n >= 2 and m >= 2, f"the CSV has {n} rows of {m} eigenvalues: too few for a test")
    url = pathlib.Path(args.page).resolve().as_uri()
    with cdp.Chromium(args.chromium, 1200, 900) as browser:
        page = browser.new_page(1200, 900)
        page.navigate(url)
        page.wait_for("window.kanesimLocus && (kanesimLocus.ready || kanesimLocus.failed)", 60, "the page ready")
        errors = page.evaluate("kanesimLocus.errors")
        if not check(page.evaluate("kanesimLocus.ready") and not errors, f"the page failed: {errors}"):
            return
        points = page.evaluate("kanesimLocus.locusPoints()")
        real = page.evaluate("kanesimLocus.realParts()")
        colours = page.evaluate("kanesimLocus.binColours")
        # The real-part plot: one row per value, the CSV's real parts in its order.
        check(len(real) == n, f"real-part plot: {len(real)} rows, the CSV {n}")
        for i, row in enumerate(real[:n]):
            check(close(row[0], values[i]), f"real-part plot row {i}: {name} = {row[0]}, the CSV {values[i]}")
            check(len(row) == m + 1, f"real-part plot row {i}: {len(row) - 1} series, the CSV {m}")
            for k in range(min(m, len(row) - 1)):
                check(close(row[k + 1], eig[i][k][0]),
                      f"real-part plot {name} = {values[i]}: Re lambda{k + 1} = {row[k + 1]}, the CSV {eig[i][k][0]}")
        # The complex plane: the same multiset of (re, im), each in its value's colour bin
        # (bins in the order of the values: the bin index never decreases with the value).
        expected = sorted((re, im, i) for i in range(n) for re, im in eig[i] if re is not None and im is not None)
        got = sorted(points)
        check(len(got) == len(expected), f"complex plane: {len(got)} points, the CSV {len(expected)}")
        nb = len(colours)
        for (re, im, b), (ere, eim, i) in zip(sorted((p[0], p[1], p[2]) for p in got), expected):
            if not (close(re, ere) and close(im, eim)):
                check(False, f"complex plane: point ({re}, {im}), the CSV ({ere}, {eim}) at {name} = {values[i]}")
                break
        bins = {}
        for re, im, b in got:
            bins.setdefault((re, im), set()).add(b)
        for re, im, i in expected:
            want = 0 if n == 1 else min(nb - 1, i * nb // n)
            check(want in bins.get((re, im), set()),
                  f"complex plane: ({re}, {im}) of {name} = {values[i]} not in colour bin {want}")
        check(nb == min(n, 64) and len(set(colours)) == nb, f"colours: {colours}")
        # The two plots are drawn: canvases of the plot's size.
        size = page.evaluate("[...document.querySelectorAll('#locus canvas, #real canvas')].map(c => c.width)")
        check(len(size) >= 2 and min(size) > 300, f"plot canvases {size}")
        urls = [e["request"]["url"] for e in page.events("Network.requestWillBeSent")]
        outside = [u for u in urls if not (u.startswith(url) or u.startswith("data:") or u.startswith("blob:"))]
        check(not outside, f"requests outside the file: {outside}")
        problems = [e["entry"]["text"] for e in page.events("Log.entryAdded") if e["entry"]["level"] == "error"]
        problems += [e["exceptionDetails"].get("text", "") for e in page.events("Runtime.exceptionThrown")]
        problems += page.evaluate("kanesimLocus.errors")
        check(not problems, f"errors in the console: {problems}")
        print(f"{n} values x {m} eigenvalues: {len(got)} points in the complex plane, {len(real)} real-part rows")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--chromium", default="chromium")
    parser.add_argument("--page", required=True)
    parser.add_argument("--csv", required=True)
    args = parser.parse_args()
    try:
        run(args)
    except cdp.ProtocolError as e:
        failures.append(f"browser: {e}")
    for f in failures:
        print("FAIL:", f)
    print("locus page:", "FAILED" if failures else "passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
