#!/usr/bin/env python3
"""What a user pays for the front end, in fresh processes (issue 40; docs/benchmarks.md
"Front end in a fresh process"): for each binary, alternated run by run, N processes of
`kanesim --version` and of `kanesim check MODEL` (load, elaborate, compile and a summary
line) for each model; the CPU time (user + system) of each child process, which on a shared
machine does not count the waiting that wall time would. A model's row also gives its cost
above `--version`'s median: the front end without the process start.

    python3 bench/frontend_fresh.py N BIN1[,BIN2...] MODEL[:--set,N=100] ...

A model argument may carry options after a colon, comma-separated
(examples/chain.mech:--set,N=100). Prints medians and, in brackets, the 10th percentile (on
a shared machine the fast runs are the cost without interference), and each binary's
median over the first's; "pf" is the median of the minor page faults per process.
"""
import os
import statistics
import subprocess
import sys
import time


FAULTS = {}  # (binary, label) -> minor page faults of each run


def cpu_of(cmd, key=None):
    """(wall, user + system CPU) seconds of one child process; its minor page faults go to
    FAULTS[key] (fresh memory the process touches: each costs 1.5-4 us on this VM)."""
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    _, _, ru = os.wait4(p.pid, 0)
    if key is not None:
        FAULTS.setdefault(key, []).append(ru.ru_minflt)
    return time.perf_counter() - t0, ru.ru_utime + ru.ru_stime


def front_end(binary, model, opts, label):
    """CPU seconds of one `kanesim check MODEL` process."""
    return cpu_of([binary, "check", model, *opts], (binary, label))[1]


def summary(xs):
    xs = sorted(xs)
    return statistics.median(xs), xs[len(xs) // 10]


def main():
    n = int(sys.argv[1])
    bins = sys.argv[2].split(",")
    models = []
    for arg in sys.argv[3:]:
        path, _, opts = arg.partition(":")
        models.append((arg, path, [o for o in opts.split(",") if o]))
    rows = {("--version (CPU)", b): [] for b in bins}
    for label, _, _ in models:
        for b in bins:
            rows[(label, b)] = []
    for _ in range(n):
        for b in bins:  # alternated, so that a change of the machine's load hits every binary
            rows[("--version (CPU)", b)].append(cpu_of([b, "--version"], (b, "--version (CPU)"))[1])
            for label, path, opts in models:
                rows[(label, b)].append(front_end(b, path, opts, label))
    labels = ["--version (CPU)"] + [m[0] for m in models]
    start = {b: summary(rows[("--version (CPU)", b)])[0] for b in bins}
    print("| what | " + " | ".join(f"`{os.path.basename(b)}` ms: median (p10) [above start]" for b in bins) +
          (" | ratio of medians |" if len(bins) > 1 else " |"))
    print("|---|" + "---|" * len(bins) + ("---|" if len(bins) > 1 else ""))
    for label in labels:
        cells = [summary(rows[(label, b)]) for b in bins]
        above = ["" if label == labels[0] else f" [{1e3 * (cells[i][0] - start[b]):.3f}]" for i, b in enumerate(bins)]
        faults = [f" {statistics.median(FAULTS[(b, label)]):.0f} pf" for b in bins]
        line = f"| {label} | " + " | ".join(f"{1e3 * m:.3f} ({1e3 * p:.3f}){a}{f}" for (m, p), a, f in
                                           zip(cells, above, faults))
        if len(bins) > 1:
            line += " | " + ", ".join(f"{cells[i][0] / cells[0][0]:.2f}" for i in range(1, len(bins)))
        print(line + " |")
    print(f"\n{n} fresh processes per cell; load average {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
