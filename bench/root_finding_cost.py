#!/usr/bin/env python3
"""Cost of locating events (issue 41; docs/benchmarks/2026-11-29_root_finding.md).

Runs `kanesim run` on the event-rich cases with each binary given, alternated (OLD first in
odd rounds, NEW first in even ones), N rounds, and prints per case: the steps, right-hand
sides and events of each, the largest difference between their event times (the events
logged by --stats, paired in order), the medians of the "integrate" phase of --stats and of
the process's CPU time (user + sys), and their ratios. With --callgrind, also each binary's
instructions (valgrind --tool=callgrind, one run: they do not vary from run to run).

Cases: Talos (example-robot-data 6.0.0's talos_reduced.urdf, 1 s, fixed base and
--floating: stops from the URDF's limits, exact friction) and the event rows of
bench/events_race.py at rtol = atol = 1e-10 (ball 2 s, rod on its stop 3 s, Coulomb
oscillator 110 s, chain of rods on stops 1.5 s).

Usage: bench/root_finding_cost.py N OLD_BIN NEW_BIN --talos URDF --package-path DIR [--callgrind]
"""
import argparse
import os
import re
import resource
import statistics
import subprocess
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
MODELS = os.path.join(HERE, "models")


def cases(talos, package_path):
    out = []
    if talos:
        base = [talos, "--package-path", package_path, "--stop-time", "1"]
        out += [("Talos fixed base, 1 s", base), ("Talos --floating, 1 s", base + ["--floating"])]
    for name, model, stop in [("ball, 2 s", "bounce_ball.mech", 2), ("rod on its stop, 3 s", "stop_pendulum.mech", 3),
                              ("Coulomb oscillator, 110 s", "coulomb_oscillator.mech", 110),
                              ("chain on stops, 1.5 s", "stop_chain.mech", 1.5)]:
        out.append((name + ", rtol 1e-10", [os.path.join(MODELS, model), "--stop-time", str(stop), "--interval",
                                            str(stop), "--rtol", "1e-10", "--atol", "1e-10"]))
    return out


def once(binary, args, out):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run([binary, "run"] + args + ["-o", out, "--stats"], capture_output=True, text=True, check=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    steps = int(re.search(r"^\s+steps\s+(\d+)", p.stderr, re.M).group(1))
    rhs = int(re.search(r"^\s+right-hand sides\s+(\d+)", p.stderr, re.M).group(1))
    integrate = float(re.search(r"^\s+integrate\s+([0-9.e-]+)$", p.stderr, re.M).group(1))
    times = [float(t) for t in re.findall(r"^\s+t = (\S+)", p.stderr, re.M)]
    return steps, rhs, times, integrate, cpu


def instructions(binary, args, out):
    with tempfile.TemporaryDirectory() as tmp:
        p = subprocess.run(["valgrind", "--tool=callgrind", "--callgrind-out-file=" + os.path.join(tmp, "cg"), binary,
                            "run"] + args + ["-o", out], capture_output=True, text=True, check=True)
    return int(re.search(r"Collected : (\d+)", p.stderr).group(1))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("n", type=int)
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--talos")
    ap.add_argument("--package-path")
    ap.add_argument("--callgrind", action="store_true")
    a = ap.parse_args()
    print("| case | steps old / new | RHS old / new | events old / new | max event-time difference (s) "
          "| integrate old / new (ms) | new / old | CPU old / new (ms) | new / old |"
          + (" instructions old / new (1e6) | new / old |" if a.callgrind else ""))
    print("|---|---|---|---|---|---|---|---|---|" + ("---|---|" if a.callgrind else ""))
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "rows.csv")
        for name, args in cases(a.talos, a.package_path):
            res = {"old": [], "new": []}
            for r in range(a.n):
                for which in (("old", "new") if r % 2 == 0 else ("new", "old")):
                    res[which].append(once(getattr(a, which), args, out))
            o, n = res["old"][0], res["new"][0]
            diff = max((abs(x - y) for x, y in zip(o[2], n[2])), default=0.0)
            io, inn = (statistics.median(x[3] for x in res[k]) * 1e3 for k in ("old", "new"))
            co, cn = (statistics.median(x[4] for x in res[k]) * 1e3 for k in ("old", "new"))
            row = (f"| {name} | {o[0]} / {n[0]} | {o[1]} / {n[1]} | {len(o[2])} / {len(n[2])} | {diff:.2g} "
                   f"| {io:.4g} / {inn:.4g} | {inn / io:.3f} | {co:.4g} / {cn:.4g} | {cn / co:.3f} |")
            if a.callgrind:
                ko, kn = instructions(a.old, args, out), instructions(a.new, args, out)
                row += f" {ko / 1e6:.1f} / {kn / 1e6:.1f} | {kn / ko:.3f} |"
            print(row, flush=True)


if __name__ == "__main__":
    main()
