#!/usr/bin/env python3
"""Change-point matrix of issue 20 (docs/benchmarks.md "Change points").

The single parallelogram four-bar of tests/stress/models/parallelogram.mech (a = 0.5, b = 0.6:
two branches meet at its change points; --set a=0.6: all links equal, a third one meets there)
over 20 s, for every integrator x the reduced (--solver dense) and the multiplier
(--solver sparse) form x rtol 1e-4 ... 1e-12: the exit code, the wall time, the time reached,
and whether the rows stay on the parallelogram branch (rocker angle = crank angle modulo 2 pi).

An outcome is one of
  branch    exit 0 and every row on the branch (max |rocker - crank| mod 2 pi < 1e-3 rad)
  exit 2    stopped (time; cause: "stuck" = 1000 steps in one near-singular zone, "turn" = the
            branch monitor saw the velocity turn, rho = sigma_min/sigma_max of the loop's rows
            there; "KKT singular" = the multiplier form's matrix lost rank); the rows kept must
            be on the branch
  WRONG     exit 0 off the branch, or rows off the branch before a stop: a silent wrong answer

Usage: bench/change_points.py [KANESIM] [--a 0.5,0.6] [--timeout 120]
"""
import argparse
import csv
import math
import os
import re
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODEL = os.path.join(ROOT, "tests/stress/models/parallelogram.mech")
INTEGRATORS = ["dop853", "cvode", "cvode-bdf", "ida", "arkode"]
FORMS = [("reduced", "dense"), ("multiplier", "sparse")]
RTOLS = ["1e-4", "1e-6", "1e-8", "1e-10", "1e-12"]
BRANCH_TOL = 1e-3


def read_rows(out):
    """The numeric rows of the CSV `out` (none if the run wrote none); the file is removed."""
    if not os.path.exists(out):
        return []
    with open(out) as f:
        r = csv.reader(f)
        next(r, None)
        rows = [[float(x) for x in row] for row in r if row]
    os.remove(out)
    return rows


def run_parallelogram(kanesim, a, integrator, solver, rtol, timeout, tmp, outputs):
    """20 s of the parallelogram (`--set a=A`), rows every 0.01 s of `outputs`: the exit code (None
    on a timeout), stderr, the wall time and the rows (shared by bench/change_point_energy.py)."""
    out = os.path.join(tmp, "p.csv")
    args = [kanesim, "run", MODEL, "--set", "a=%s" % a, "--stop-time", "20", "--interval", "0.01",
            "--rtol", rtol, "--integrator", integrator, "--solver", solver]
    for name in outputs:
        args += ["--output", name]
    t0 = time.monotonic()
    try:
        p = subprocess.run(args + ["-o", out], capture_output=True, text=True, timeout=timeout)
        code, err = p.returncode, p.stderr
    except subprocess.TimeoutExpired:
        code, err = None, "timeout"
    return code, err.strip(), time.monotonic() - t0, read_rows(out)


def run(kanesim, a, integrator, solver, rtol, timeout, tmp):
    code, err, wall, rows = run_parallelogram(kanesim, a, integrator, solver, rtol, timeout, tmp,
                                              ["crank_pivot.q", "rocker_pivot.q"])
    off = max((abs(math.remainder(row[2] - row[1], 2 * math.pi)) for row in rows), default=0.0)
    reached = rows[-1][0] if rows else float("nan")
    return code, err, wall, off, reached


def outcome(code, err, off, reached):
    if code is None:
        return "TIMEOUT"
    if off >= BRANCH_TOL:
        return "WRONG (off %.2g rad, exit %d)" % (off, code)
    if code == 0:
        return "branch"
    if code == 2:
        cause = err.split("numerical failure at t = ", 1)[-1]
        t = float(cause.split(":", 1)[0])
        m = re.search(r"within ([0-9.e+-]+) of losing rank", cause)
        rho = (", rho %s" % m.group(1)) if m else ""
        if "without passing the change point" in cause:
            why = "stuck" + rho
        elif "left its assembly branch" in cause:
            why = "turn" + rho
        elif "pivot ratio of the multiplier system" in cause:
            why = "KKT singular"
        else:
            why = cause.split(":", 1)[-1].strip()[:60]
        return "exit 2 at %.3f (%s)" % (t, why)
    return "exit %d: %s" % (code, err[-80:])


def grid_options():
    """The command line of this script and bench/change_point_energy.py."""
    ap = argparse.ArgumentParser()
    ap.add_argument("kanesim", nargs="?", default=os.path.join(ROOT, "build/cli/kanesim"))
    ap.add_argument("--a", default="0.5,0.6")
    ap.add_argument("--timeout", type=float, default=120)
    ap.add_argument("--integrators", default=",".join(INTEGRATORS))
    ap.add_argument("--rtols", default=",".join(RTOLS))
    ap.add_argument("--forms", default="reduced,multiplier")
    return ap.parse_args()


def print_grid(o, tmp, heading, cell):
    """One table per a and form: a row per integrator, a column per rtol, each cell
    cell(a, integrator, solver, rtol, tmp) (a string); heading follows "20 s" in the title."""
    forms = [f for f in FORMS if f[0] in o.forms.split(",")]
    rtols = o.rtols.split(",")
    for a in o.a.split(","):
        for form, solver in forms:
            print("\n### a = %s, %s form (--solver %s), 20 s%s\n" % (a, form, solver, heading))
            print("| integrator | " + " | ".join(rtols) + " |")
            print("|---|" + "---|" * len(rtols))
            for integrator in o.integrators.split(","):
                cells = [cell(a, integrator, solver, rtol, tmp) for rtol in rtols]
                print("| %s | %s |" % (integrator, " | ".join(cells)), flush=True)


def main():
    o = grid_options()

    def cell(a, integrator, solver, rtol, tmp):
        code, err, wall, off, reached = run(o.kanesim, a, integrator, solver, rtol, o.timeout, tmp)
        if code not in (0, 2):
            print("  [%s %s %s] %s" % (integrator, solver, rtol, err[-200:]), file=sys.stderr)
        return "%s, %.2f s" % (outcome(code, err, off, reached), wall)

    with tempfile.TemporaryDirectory() as tmp:
        print_grid(o, tmp, "", cell)


if __name__ == "__main__":
    main()
