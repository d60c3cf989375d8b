#!/usr/bin/env python3
"""Compares two kanesim binaries on the change-point runs of issue 20, for changes that must
not change them (docs/benchmarks.md "Chains: several loops singular at once"): the single
parallelogram matrix of bench/change_points.py (a = 0.5, 0.6 x every integrator x both forms x
rtol 1e-4 ... 1e-12: 100 cells) and the chains of bench/change_point_chains.py (N = 2, 10, 40 x
rtol 1e-8, 1e-10, 1e-12 x every integrator, reduced form). Each cell runs OLD then NEW (alternated,
for the CPU times on a noisy machine) and compares the CSV byte for byte, the exit code and
stderr. Prints one line per cell (same/DIFFERS, exit codes, CPU old/new); exit 1 if any differs.

Usage: scripts/same_change_points.py OLD NEW [--only single|chains] [--n 2,10,40]
       [--integrators dop853,...] [--rtol 1e-8,...] [--timeout 300]
"""
import argparse
import filecmp
import os
import resource
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SINGLE = os.path.join(ROOT, "tests/stress/models/parallelogram.mech")
CHAIN = os.path.join(ROOT, "tests/stress/models/parallelogram_chain.mech")
INTEGRATORS = ["dop853", "cvode", "cvode-bdf", "ida", "arkode"]


def run(binary, args, out, timeout):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        p = subprocess.run([binary] + args + ["-o", out], capture_output=True, text=True, timeout=timeout)
        code, err = p.returncode, p.stderr
    except subprocess.TimeoutExpired:
        code, err = "timeout", ""
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return code, err, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def cells(only, ns, integrators, rtols):
    if only in ("all", "single"):
        for a in ("0.5", "0.6"):
            for solver in ("dense", "sparse"):
                for integ in INTEGRATORS:
                    for rtol in ("1e-4", "1e-6", "1e-8", "1e-10", "1e-12"):
                        yield ("single a=%s %s %s %s" % (a, solver, integ, rtol),
                               ["run", SINGLE, "--set", "a=" + a, "--stop-time", "20", "--interval", "0.01", "--rtol",
                                rtol, "--integrator", integ, "--solver", solver, "--output", "crank_pivot.q",
                                "--output", "rocker_pivot.q"])
    if only in ("all", "chains"):
        for n in ns:
            for integ in integrators:
                for rtol in rtols:
                    args = ["run", CHAIN, "--set", "N=%d" % n, "--stop-time", "20", "--rtol", rtol, "--integrator",
                            integ, "--solver", "auto", "--output", "rj0.q", "--output", "rj0.u"]
                    for i in range(1, n + 1):
                        args += ["--output", "rj[%d].q" % i]
                    yield ("chain N=%d %s %s" % (n, integ, rtol), args)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("old")
    ap.add_argument("new")
    ap.add_argument("--only", default="all", choices=["all", "single", "chains"])
    ap.add_argument("--n", default="2,10,40")
    ap.add_argument("--integrators", default=",".join(INTEGRATORS), help="chains only")
    ap.add_argument("--rtol", default="1e-8,1e-10,1e-12", help="chains only")
    ap.add_argument("--timeout", type=float, default=300)
    o = ap.parse_args()
    differ = 0
    with tempfile.TemporaryDirectory() as tmp:
        a_out, b_out = os.path.join(tmp, "old.csv"), os.path.join(tmp, "new.csv")
        for name, args in cells(o.only, [int(x) for x in o.n.split(",")], o.integrators.split(","),
                               o.rtol.split(",")):
            for f in (a_out, b_out):
                if os.path.exists(f):
                    os.remove(f)
            ca, ea, ta = run(o.old, args, a_out, o.timeout)
            cb, eb, tb = run(o.new, args, b_out, o.timeout)
            same_rows = (os.path.exists(a_out) == os.path.exists(b_out) and
                         (not os.path.exists(a_out) or filecmp.cmp(a_out, b_out, shallow=False)))
            same = same_rows and ca == cb and ea == eb
            differ += 0 if same else 1
            print("%-40s %s  exit %s/%s  CPU %.2f/%.2f s" % (name, "same" if same else "DIFFERS", ca, cb, ta, tb),
                  flush=True)
            if not same:
                print("   rows %s, stderr old: %s | new: %s" % ("same" if same_rows else "differ",
                                                               ea.strip()[-160:], eb.strip()[-160:]), flush=True)
    return 1 if differ else 0


if __name__ == "__main__":
    sys.exit(main())
