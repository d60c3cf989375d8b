#!/usr/bin/env python3
"""Cost of writing output rows (docs/benchmarks.md "Output rows").

Runs `kanesim run examples/double_pendulum.mech -o FILE --stats` with each binary given,
alternated, N times, for 1001 rows (the model's 10 s) and 20001 rows (--stop-time 200), and
prints the medians of the "integrate" and "output" phases of --stats and of the process's
CPU time (user + system).

Usage: bench/output_rows.py N BIN[,BIN...]
"""
import os
import re
import resource
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODEL = os.path.join(ROOT, "examples/double_pendulum.mech")


def once(binary, extra, out):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run([binary, "run", MODEL, "-o", out, "--stats"] + extra,
                       capture_output=True, text=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    phase = {k: float(v) for k, v in re.findall(r"^\s+(integrate|output)\s+([0-9.e-]+)$", p.stderr, re.M)}
    return phase["integrate"], phase["output"], cpu


def main():
    n = int(sys.argv[1])
    bins = sys.argv[2].split(",")
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "rows.csv")
        for label, extra in (("1001 rows", []), ("20001 rows", ["--stop-time", "200"])):
            samples = {b: [] for b in bins}
            for _ in range(n):
                for b in bins:
                    samples[b].append(once(b, extra, out))
            for b in bins:
                s = samples[b]
                med = [statistics.median(x[i] for x in s) * 1e3 for i in range(3)]
                print(f"{label:11s} {b:28s} integrate {med[0]:8.3f} ms  output {med[1]:8.3f} ms  "
                      f"process CPU {med[2]:8.3f} ms  (n={n})")


if __name__ == "__main__":
    main()
