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
import math
import os
import sys
import tempfile

from change_point_chains import lumped_constants, lumped_energy_error  # beside this script
from change_points import grid_options, print_grid, run_parallelogram

M_CRANK, M_ROCKER, M_COUPLER = 0.5, 0.8, 1.0  # tests/stress/models/parallelogram.mech


def run(kanesim, a, integrator, solver, rtol, timeout, tmp):
    code, err, _, rows = run_parallelogram(kanesim, a, integrator, solver, rtol, timeout, tmp,
                                           ["crank_pivot.q", "crank_pivot.u", "rocker_pivot.q", "rocker_pivot.u"])
    if not rows:
        return code, err, float("nan"), float("nan"), float("nan"), float("nan")
    J, G = lumped_constants(1, a=float(a), m_rod=(M_CRANK + M_ROCKER) / 2, m_c=M_COUPLER)
    energy = lumped_energy_error(J, G, [r[1] for r in rows], [r[2] for r in rows])
    off = max(abs(math.remainder(r[3] - r[1], 2 * math.pi)) for r in rows)
    woff = max(abs(r[4] - r[2]) for r in rows)
    return code, err, rows[-1][0], energy, off, woff


def main():
    o = grid_options()
    wrong = 0

    def cell(a, integrator, solver, rtol, tmp):
        nonlocal wrong
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
        if os.environ.get("VERBOSE") and code != 0:
            print("  [%s %s %s] %s" % (integrator, solver, rtol, err[-200:]), file=sys.stderr)
        return "%s %.1e" % (what, energy)

    with tempfile.TemporaryDirectory() as tmp:
        print_grid(o, tmp, ": outcome, max energy error / E", cell)
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
