#!/usr/bin/env python3
"""The single parallelogram's change-point matrix with the energy checked (issue 20;
docs/benchmarks.md "Change points").

bench/change_points.py checks that the rows stay on the branch (rocker angle = crank angle);
rows can stay on it while their speed leaves the motion (multiplier form, CVODE-BDF, a = 0.6,
rtol 1e-6 grew the energy 43x after t = 9.74 with every row on the branch). Here every row is
also checked against the lumped energy (1/2) J w^2 + G sin(theta) of the crank with the
coupler translating (any a: J = (m_crank + m_rocker) a^2/3 + m_coupler a^2,
G = g ((m_crank + m_rocker) a/2 + m_coupler a); bench/change_point_chains.py's
lumped_energy_error with one loop and the rods' mean mass), relative to the first row's.

A cell is WRONG when its rows are off the branch (1e-3 rad, or the speeds 1e-2 rad/s apart) or
their energy is off by more than max(1e3 rtol, 1e-6), whatever the exit code; else "ok" (exit
0 to 20 s) or "S t" (exit 2 at t, the rows before it right). Each cell shows the max relative
energy error of its rows.

Usage: bench/change_point_energy.py [KANESIM] [--a 0.5,0.6] [--integrators ...] [--rtols ...]
       [--forms reduced,multiplier]   (exit 1 if a cell is WRONG)
"""
import argparse
import math
import os
import subprocess
import sys
import tempfile

from change_point_chains import lumped_constants, lumped_energy_error  # beside this script
from change_points import FORMS, INTEGRATORS, MODEL, ROOT, RTOLS, read_rows

M_CRANK, M_ROCKER, M_COUPLER = 0.5, 0.8, 1.0  # tests/stress/models/parallelogram.mech


def run(kanesim, a, integrator, solver, rtol, timeout, tmp):
    out = os.path.join(tmp, "p.csv")
    args = [kanesim, "run", MODEL, "--set", "a=%s" % a, "--stop-time", "20", "--interval", "0.01",
            "--rtol", rtol, "--integrator", integrator, "--solver", solver,
            "--output", "crank_pivot.q", "--output", "crank_pivot.u",
            "--output", "rocker_pivot.q", "--output", "rocker_pivot.u", "-o", out]
    try:
        p = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
        code, err = p.returncode, p.stderr.strip()
    except subprocess.TimeoutExpired:
        code, err = None, "timeout"
    rows = read_rows(out)
    if not rows:
        return code, err, float("nan"), float("nan"), float("nan"), float("nan")
    J, G = lumped_constants(1, a=float(a), m_rod=(M_CRANK + M_ROCKER) / 2, m_c=M_COUPLER)
    energy = lumped_energy_error(J, G, [r[1] for r in rows], [r[2] for r in rows])
    off = max(abs(math.remainder(r[3] - r[1], 2 * math.pi)) for r in rows)
    woff = max(abs(r[4] - r[2]) for r in rows)
    return code, err, rows[-1][0], energy, off, woff


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("kanesim", nargs="?", default=os.path.join(ROOT, "build/cli/kanesim"))
    ap.add_argument("--a", default="0.5,0.6")
    ap.add_argument("--timeout", type=float, default=120)
    ap.add_argument("--integrators", default=",".join(INTEGRATORS))
    ap.add_argument("--rtols", default=",".join(RTOLS))
    ap.add_argument("--forms", default="reduced,multiplier")
    o = ap.parse_args()
    forms = [f for f in FORMS if f[0] in o.forms.split(",")]
    rtols = o.rtols.split(",")
    wrong = 0
    with tempfile.TemporaryDirectory() as tmp:
        for a in o.a.split(","):
            for form, solver in forms:
                print("\n### a = %s, %s form (--solver %s), 20 s: outcome, max energy error / E\n" % (a, form, solver))
                print("| integrator | " + " | ".join(rtols) + " |")
                print("|---|" + "---|" * len(rtols))
                for integrator in o.integrators.split(","):
                    cells = []
                    for rtol in rtols:
                        code, err, reached, energy, off, woff = run(o.kanesim, a, integrator, solver, rtol, o.timeout, tmp)
                        bad = not (off < 1e-3 and woff < 1e-2 and energy <= max(1e3 * float(rtol), 1e-6))
                        if code == 0 and not (abs(reached - 20.0) < 1e-9):
                            bad = True
                        if bad:
                            what = "WRONG (exit %s)" % code
                            wrong += 1
                        elif code == 0:
                            what = "ok"
                        elif code == 2:
                            what = "S %.3f" % reached
                        else:
                            what = "exit %s" % code
                        cells.append("%s %.1e" % (what, energy))
                        if os.environ.get("VERBOSE") and code != 0:
                            print("  [%s %s %s] %s" % (integrator, solver, rtol, err[-200:]), file=sys.stderr)
                    print("| %s | %s |" % (integrator, " | ".join(cells)), flush=True)
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
