#!/usr/bin/env python3
"""Python's cost over the C++ run (docs/benchmarks.md "Python").

1. Call overhead: Model.run on a run so short that the C++ work is tiny (one output row),
   minus the wall time of sim::Simulate measured in C++ around the call
   (r.stats["simulate_seconds"]: the run as `kanesim run` does it, setup included), so what
   remains is argument conversion, option resolution and signal selection, the GIL
   release, the result's conversion and the NumPy copies. Also a 501-row run, to show the copy's share.
2. A sweep from Python (kanesim.sweep) against `kanesim sweep` on the same grid and
   metrics (the command's time includes its process start, loading and files).

Usage: PYTHONPATH=build/python python3 bench/python_overhead.py [--kanesim build/cli/kanesim]
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import time

import kanesim

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))



def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kanesim", default=os.path.join(ROOT, "build", "cli", "kanesim"))
    ap.add_argument("--threads", type=int, default=2)
    args = ap.parse_args()

    m = kanesim.load(os.path.join(ROOT, "examples", "double_pendulum.mech"))
    print("| what | Model.run, per call | sim::Simulate inside it | overhead (the difference, per call) |")
    print("|---|---|---|---|")
    for label, kw in [("run, 1 row (stop_time = start)", dict(stop_time=0.0, interval=1.0)),
                      ("run, 1 row, outputs=['*.q']", dict(stop_time=0.0, interval=1.0, outputs=["*.q"])),
                      ("run, 501 rows x 4 (0.5 s of the double pendulum)", dict(stop_time=0.5, interval=0.001))]:
        total, inner, over = [], [], []
        for _ in range(2000 if kw["stop_time"] == 0 else 300):
            t0 = time.perf_counter()
            r = m.run(**kw)
            dt = time.perf_counter() - t0
            total.append(dt)
            inner.append(r.stats["simulate_seconds"])
            over.append(dt - r.stats["simulate_seconds"])
        f = lambda xs: f"{min(xs) * 1e6:.1f} / {statistics.median(xs) * 1e6:.1f} µs"
        print(f"| {label} | {f(total)} | {f(inner)} | {f(over)} |")
    print("(min / median over the calls)")

    model = os.path.join(ROOT, "examples", "spring_mass.mech")
    grid = {"k": [10 + 10 * i for i in range(20)], "mass": [1, 2, 3, 4, 5]}
    metrics = ["final:slider.q", "max:slider.q", "cross:slider.q=0"]
    sm = kanesim.load(model, set={"F0": 0})
    times_py, times_py_load = [], []
    for _ in range(5):
        t0 = time.perf_counter()
        t = kanesim.sweep(sm, grid=grid, metrics=metrics, stop_time=3, threads=args.threads)
        times_py.append(time.perf_counter() - t0)
        t0 = time.perf_counter()
        kanesim.sweep(kanesim.load(model, set={"F0": 0}), grid=grid, metrics=metrics, stop_time=3,
                      threads=args.threads)
        times_py_load.append(time.perf_counter() - t0)
    assert t.failed == 0 and len(t) == 100
    times_cli = []
    with tempfile.TemporaryDirectory() as tmp:
        for i in range(5):
            cmd = [args.kanesim, "sweep", model, "--set", "F0=0", "--grid", "k=10:10:200", "--grid", "mass=1:1:5",
                   "--stop-time", "3", "-j", str(args.threads), "-o", os.path.join(tmp, str(i)), "--no-progress"]
            for x in metrics:
                cmd += ["--metric", x]
            t0 = time.perf_counter()
            subprocess.run(cmd, check=True, capture_output=True)
            times_cli.append(time.perf_counter() - t0)
    print()
    print(f"| sweep, 100 scenarios of spring_mass (3 s, 3 metrics), {args.threads} threads | min of 5 |")
    print("|---|---|")
    print(f"| kanesim.sweep (model loaded before) | {min(times_py) * 1e3:.1f} ms |")
    print(f"| kanesim.load + kanesim.sweep | {min(times_py_load) * 1e3:.1f} ms |")
    print(f"| kanesim sweep (process, load, files) | {min(times_cli) * 1e3:.1f} ms |")


if __name__ == "__main__":
    sys.exit(main())
