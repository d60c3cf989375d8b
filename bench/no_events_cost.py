#!/usr/bin/env python3
"""Cost of the event machinery in models without events (issue 41: "skip all event
machinery, at no cost, in a model that has none"; docs/benchmarks/2026-11-29_no_events_cost.md).

Runs `kanesim run MODEL --stats` for the examples without stops, contacts, when clauses or
exact friction with each binary given (one built before events existed, one after),
alternated, N times, and prints per model: whether the rows are identical, the steps and
right-hand sides of each (the same when no event function is evaluated), and the medians of
the "integrate" phase of --stats with their ratio.

Usage: bench/no_events_cost.py N OLD_BIN NEW_BIN
"""
import os
import re
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# (model, extra arguments): a tree, a chain, closed loops, a rolling contact, a forced cart.
MODELS = [("double_pendulum", []), ("chain", []), ("fourbar", []), ("slider_crank", []),
          ("rolling_disk", []), ("spring_mass", [])]


def once(binary, model, extra, out):
    p = subprocess.run([binary, "run", os.path.join(ROOT, "examples", model + ".mech"), "-o", out, "--stats"] + extra,
                       capture_output=True, text=True, check=True)
    steps = int(re.search(r"^\s+steps\s+(\d+)", p.stderr, re.M).group(1))
    rhs = int(re.search(r"^\s+right-hand sides\s+(\d+)", p.stderr, re.M).group(1))
    integrate = float(re.search(r"^\s+integrate\s+([0-9.e-]+)$", p.stderr, re.M).group(1))
    with open(out) as f:
        rows = f.read()
    return steps, rhs, integrate, rows


def main():
    n, old, new = int(sys.argv[1]), sys.argv[2], sys.argv[3]
    print("| model | rows identical | steps old / new | RHS old / new | integrate old (ms) | new (ms) | new / old |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as d:
        for model, extra in MODELS:
            t = {old: [], new: []}
            seen = {}
            for _ in range(n):
                for b in (old, new):
                    steps, rhs, integrate, rows = once(b, model, extra, os.path.join(d, "out.csv"))
                    t[b].append(integrate)
                    seen[b] = (steps, rhs, rows)
            m_old, m_new = statistics.median(t[old]) * 1e3, statistics.median(t[new]) * 1e3
            same = "yes" if seen[old][2] == seen[new][2] else "no"
            print(f"| {model} | {same} | {seen[old][0]} / {seen[new][0]} | {seen[old][1]} / {seen[new][1]} | "
                  f"{m_old:.3g} | {m_new:.3g} | {m_new / m_old:.3f} |")


if __name__ == "__main__":
    main()
