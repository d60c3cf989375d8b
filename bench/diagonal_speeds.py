#!/usr/bin/env python3
"""Cost of Lesser's diagonal speeds (`kanesim run --speeds diagonal`, issue 44) against the
joint speeds: the median CPU time (user + system, of the process: robust on a loaded machine,
where wall time is not) of REPEAT alternating runs of each, the right-hand sides each took,
and how far the joint angles of the two runs differ over the first 2 s (the double
pendulum and the chains are chaotic: later the two runs' different round-off has grown). Long stop times, so that integration
dominates the process's time.

Usage: bench/diagonal_speeds.py [KANESIM] [--repeat 7] [--rtol 1e-8]
Prints a Markdown table (docs/benchmarks.md "Diagonal speeds").
"""
import argparse
import csv
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
CASES = [
    ("double pendulum", "examples/double_pendulum.mech", []),
    ("Lesser fig. 1", "tests/sim/models/lesser_fig1.mech", []),
    ("chain N=5", "examples/chain.mech", ["--set", "N=5"]),
    ("chain N=10", "examples/chain.mech", ["--set", "N=10"]),
    ("chain N=20", "examples/chain.mech", ["--set", "N=20"]),
]


def run(kanesim, mech, extra, rtol, out, diagonal):
    args = [kanesim, "run", os.path.join(ROOT, mech), *extra, "--stop-time", "20", "--rtol", str(rtol),
            "--integrator", "dop853", "--stats", "-o", out]
    if diagonal:
        args += ["--speeds", "diagonal"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(args, capture_output=True, text=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rhs = int(re.search(r"right-hand sides\s+(\d+)", p.stderr).group(1))
    return cpu, rhs


def angles(path):
    with open(path) as f:
        rows = list(csv.reader(f))
    cols = [i for i, n in enumerate(rows[0]) if n.endswith(".q") or ".q[" in n]
    return [[float(r[i]) for i in cols] for r in rows[1:] if float(r[0]) <= 2.0]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("kanesim", nargs="?", default=os.path.join(ROOT, "build/cli/kanesim"))
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--rtol", type=float, default=1e-8)
    a = ap.parse_args()
    print(f"| model (T = 20 s, rtol {a.rtol:g}, DOP853) | joint speeds: CPU (ms), f evals | diagonal: CPU (ms), f evals | ratio | per f eval | max abs Δq, t ≤ 2 s |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, mech, extra in CASES:
            times = {False: [], True: []}
            rhs = {}
            for _ in range(a.repeat):
                for diagonal in (False, True):  # alternating, so load drifts hit both alike
                    t, n = run(a.kanesim, mech, extra, a.rtol, os.path.join(tmp, f"{int(diagonal)}.csv"), diagonal)
                    times[diagonal].append(t)
                    rhs[diagonal] = n
            qa, qb = angles(os.path.join(tmp, "0.csv")), angles(os.path.join(tmp, "1.csv"))
            dq = max(abs(x - y) for ra, rb in zip(qa, qb) for x, y in zip(ra, rb))
            ma, mb = statistics.median(times[False]) * 1e3, statistics.median(times[True]) * 1e3
            per = (mb / rhs[True]) / (ma / rhs[False])
            print(f"| {name} | {ma:.2f}, {rhs[False]} | {mb:.2f}, {rhs[True]} | {mb / ma:.1f} | {per:.1f} | {dq:.1e} |")
            sys.stdout.flush()


if __name__ == "__main__":
    main()
