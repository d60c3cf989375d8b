#!/usr/bin/env python3
"""Chains of equal-link parallelograms through their change points (issue 20;
docs/benchmarks.md "Change points").

tests/stress/models/parallelogram_chain.mech with N loops over 20 s: every loop of the chain is
singular at the same instant. Per run: the outcome, the CPU time of `kanesim run` (user + system
of the child), the time reached, how far the rows are off the branch (max over the rods of
|rod i - rod 0| mod 2 pi), and the max |rod 0 angle - lumped crank| over the rows, the lumped
crank being the independent one-degree-of-freedom model of the model's header
(theta'' = -(G / J) cos theta, integrated here by classical Runge-Kutta from the first row),
the max over the rows of the lumped energy (1/2) J thetadot^2 + G sin theta against the first
row's (relative; more than max(1e3 rtol, 1e-6) is WRONG: a row whose speed left the motion
by more than the tolerance's reach), and how far the rods' speeds are apart (max over
the rods of |speed i - speed 0|: equal on the branch).

Outcomes: B exit 0 on the branch to 20 s; S exit 2 at time t (the rows before it checked too);
WRONG exit 0 short of 20 s, or rows off the branch (angles more than 1e-3 rad or speeds more than
1e-2 rad/s apart) or off the motion (the energy error above): a silent wrong answer, even
when the run then stops with exit 2.

Usage: bench/change_point_chains.py [KANESIM] [--n 2,10,40] [--rtol 1e-8,1e-10,1e-12]
       [--integrator dop853,...] [--solver auto] [--repeat 1]
"""
import argparse
import math
import os
import resource
import subprocess
import sys
import tempfile

from change_points import read_rows  # bench/change_points.py, beside this script

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODEL = os.path.join(ROOT, "tests/stress/models/parallelogram_chain.mech")


def lumped_constants(n, a=0.6, m_rod=0.5, m_c=1.0, g=9.81):
    """J and G of the lumped crank: n + 1 rods of mass m_rod, n couplers of mass m_c."""
    J = (n + 1) * m_rod * a * a / 3.0 + n * m_c * a * a
    G = g * ((n + 1) * m_rod * a / 2.0 + n * m_c * a)
    return J, G


def lumped_energy_error(J, G, th, w):
    """The lumped energy (1/2) J w^2 + G sin(theta) of every row against the first row's,
    relative: independent of the phase error that grows over 20 s at loose tolerances."""
    e0 = 0.5 * J * w[0] ** 2 + G * math.sin(th[0])
    return max(abs(0.5 * J * wi ** 2 + G * math.sin(qi) - e0) for qi, wi in zip(th, w)) / abs(e0)


def lumped_error(n, t, th, w, a=0.6, m_rod=0.5, m_c=1.0, g=9.81, h_max=2e-5):
    J, G = lumped_constants(n, a, m_rod, m_c, g)
    k = G / J
    x, v, now, err = th[0], w[0], t[0], 0.0
    for ti, qi in zip(t, th):
        while now < ti - 1e-13:
            h = min(h_max, ti - now)
            k1x, k1v = v, -k * math.cos(x)
            k2x, k2v = v + h / 2 * k1v, -k * math.cos(x + h / 2 * k1x)
            k3x, k3v = v + h / 2 * k2v, -k * math.cos(x + h / 2 * k2x)
            k4x, k4v = v + h * k3v, -k * math.cos(x + h * k3x)
            x += h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x)
            v += h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v)
            now += h
        err = max(err, abs(qi - x))
    return err, lumped_energy_error(J, G, th, w)


def run(kanesim, n, rtol, integrator, solver, tmp, timeout):
    out = os.path.join(tmp, "c.csv")
    args = [kanesim, "run", MODEL, "--set", "N=%d" % n, "--stop-time", "20", "--rtol", rtol,
            "--integrator", integrator, "--solver", solver, "--output", "rj0.q", "--output", "rj0.u"]
    for i in range(1, n + 1):
        args += ["--output", "rj[%d].q" % i]
    for i in range(1, n + 1):
        args += ["--output", "rj[%d].u" % i]
    args += ["-o", out]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        p = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
        code, err = p.returncode, p.stderr.strip()
    except subprocess.TimeoutExpired:
        code, err = None, "timeout"
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    rows = read_rows(out)
    if not rows:
        return code, err, cpu, float("nan"), float("nan"), (float("nan"), float("nan")), float("nan")
    t = [r[0] for r in rows]
    th = [r[1] for r in rows]
    w = [r[2] for r in rows]
    off = max(abs(math.remainder(q - r[1], 2 * math.pi)) for r in rows for q in r[3::2])  # rj[i].q, rj[i].u in the model's order
    # Rows whose speeds leave the branch while the angles stay on it (DOP853's rows
    # interpolated across a passage did: docs/benchmarks.md "Rows interpolated ..."): every
    # rod turns at rod 0's speed on the branch.
    woff = max(abs(u - r[2]) for r in rows for u in r[4::2])
    return code, err, cpu, t[-1], off, lumped_error(n, t, th, w), woff


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("kanesim", nargs="?", default=os.path.join(ROOT, "build/cli/kanesim"))
    ap.add_argument("--n", default="2,10,40")
    ap.add_argument("--rtol", default="1e-8,1e-10,1e-12")
    ap.add_argument("--integrator", default="dop853")
    ap.add_argument("--solver", default="auto")
    ap.add_argument("--timeout", type=float, default=120)
    a = ap.parse_args()
    print("| N | integrator | solver | rtol | outcome | CPU | angle error | energy error | off the branch | speeds apart |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    wrong = 0
    with tempfile.TemporaryDirectory() as tmp:
        for n in [int(x) for x in a.n.split(",")]:
            for integ in a.integrator.split(","):
                for rtol in a.rtol.split(","):
                    code, err, cpu, reached, off, (e, we), woff = run(a.kanesim, n, rtol, integ, a.solver, tmp, a.timeout)
                    if off > 1e-3 or woff > 1e-2 or we > max(1e3 * float(rtol), 1e-6) or (code == 0 and abs(reached - 20.0) > 1e-9):
                        outcome = "WRONG"
                        wrong += 1
                    elif code == 0:
                        outcome = "B"
                    elif code == 2:
                        outcome = "S t=%.3f" % reached
                    else:
                        outcome = "exit %s" % code
                    print("| %d | %s | %s | %s | %s | %.2f s | %.2g | %.2g | %.2g | %.2g |" %
                          (n, integ, a.solver, rtol, outcome, cpu, e, we, off, woff), flush=True)
                    if code not in (0,) and os.environ.get("VERBOSE"):
                        print("   ", err.splitlines()[-1] if err else "", file=sys.stderr)
    return 1 if wrong else 0


if __name__ == "__main__":
    sys.exit(main())
