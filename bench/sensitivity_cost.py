#!/usr/bin/env python3
"""Cost of n parameter sensitivities (`kanesim run --sensitivity`, issue 44) against the n + 1
plain runs that would give the same derivatives by differences of whole runs: the median CPU
time (user + system of the process: robust on a loaded machine, where wall time is not) of
REPEAT repetitions, each running the plain model and its n = 1, 2, 4 sensitivities in turn
(so that load drifts hit all alike), at each model's own experiment settings and default
integrator. The same derivatives by forward differences take n + 1 runs, by central
differences 2n + 1.

Usage: bench/sensitivity_cost.py [KANESIM] [--repeat 5]
Prints a Markdown table (docs/benchmarks/2026-11-29_sensitivity_cost.md).
"""
import argparse
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
NS = (1, 2, 4)
# (name, model, extra arguments, four parameters: the first n are differentiated)
CASES = [
    ("double pendulum", "examples/double_pendulum.mech", [], ["rod1.L", "rod2.m", "rod1.m", "rod2.L"]),
    ("four-bar (closed loop)", "examples/fourbar.mech", [], ["a", "b", "c", "d"]),
    ("rolling disk", "examples/rolling_disk.mech", [], ["a", "m", "g", "lean_rate"]),
    ("chain N=10", "examples/chain.mech", ["--set", "N=10"], ["L", "m", "q0", "j[2].u.start"]),
]


def run(kanesim, mech, extra, params, out):
    """CPU seconds of one run and its right-hand-side count."""
    args = [kanesim, "run", os.path.join(ROOT, mech), *extra, "--stats", "-o", out]
    if params:
        args += ["--sensitivity", ",".join(params)]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(args, capture_output=True, text=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    rhs = int(re.search(r"right-hand sides\s+(\d+)", p.stderr).group(1))
    return (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), rhs


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("kanesim", nargs="?", default=os.path.join(ROOT, "build/cli/kanesim"))
    ap.add_argument("--repeat", type=int, default=5)
    a = ap.parse_args()
    head = " | ".join(f"n = {n}: CPU ms, ÷ {n + 1} runs" for n in NS)
    print(f"| model (its experiment, default integrator) | 1 run: CPU ms, right-hand sides | {head} | right-hand sides, n = 4 |")
    print("|---|---:|" + "---:|" * len(NS) + "---:|")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "out.csv")
        for name, mech, extra, params in CASES:
            times = {n: [] for n in (0, *NS)}
            rhs = {}
            for _ in range(a.repeat):
                for n in times:
                    t, rhs[n] = run(a.kanesim, mech, extra, params[:n], out)
                    times[n].append(t)
            med = {n: statistics.median(v) * 1e3 for n, v in times.items()}
            cells = " | ".join(f"{med[n]:.0f}, {med[n] / ((n + 1) * med[0]):.2f}" for n in NS)
            print(f"| {name} | {med[0]:.0f}, {rhs[0]} | {cells} | {rhs[4]} |")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
