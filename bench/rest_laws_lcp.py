"""Do consistent laws exist for the joints at rest where a robot run stopped with exit 2?

A run of a fixed-base URDF robot with constant joint friction (URDF <dynamics friction>, a
constant Coulomb torque B) and end stops can stop with exit 2 at an event: "neither sticking
nor sliding is consistent" or "... accelerates into it without resting on it". This script
reads the run's last CSV row (every joint's .q and .u, written before the exit), takes the
joints with speed exactly 0 as the set at rest R, and solves their laws as ONE box-constrained
linear complementarity problem:

    udot_R = A f + b,   A = (M^-1)_RR,   b = (M^-1 (tau - h))_R,
    f_k in [lo_k, hi_k]:  [-B, B] free joint, [-B, inf) at q_min, (-inf, B] at q_max,
    f_k = lo_k => udot_k >= 0,  f_k = hi_k => udot_k <= 0,  otherwise udot_k = 0,

with M and h (Coriolis, centrifugal and gravity terms) from Pinocchio, tau the moving joints'
damping -d u and sliding friction -B sign(u). A is symmetric positive definite, so this
problem has exactly one solution (Cottle, Pang & Stone, The Linear Complementarity Problem,
1992, for P-matrices; a box of bounds keeps it). Projected Gauss-Seidel converges to it. It
then prints each joint's law and checks the conditions. No solution would mean a wrong
model; a solution means the exit 2 came from the way the laws were searched, not from the
physics.

Limits: fixed base only (no --floating); no <mimic>; a joint counts as at its stop within
--stop-tol of the limit (the event's root leaves it about 1e-9 away).

    bench/.venv/bin/python bench/rest_laws_lcp.py ROBOT.urdf RUN.csv --friction B --damping D
"""
import argparse
import csv
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("urdf")
    ap.add_argument("csv", help="the run's output (kanesim run ... -o RUN.csv, default signals)")
    ap.add_argument("--friction", type=float, required=True, help="every joint's constant friction torque B")
    ap.add_argument("--damping", type=float, default=0.0, help="every joint's damping d")
    ap.add_argument("--stop-tol", type=float, default=1e-6, help="a joint this close to a limit is at its stop")
    a = ap.parse_args()

    model = pin.buildModelFromUrdf(a.urdf)
    data = model.createData()
    row = list(csv.DictReader(open(a.csv)))[-1]
    limits = {}
    for j in ET.parse(a.urdf).getroot().iter("joint"):
        lim = j.find("limit")
        if j.get("type") in ("revolute", "prismatic") and lim is not None:
            limits[j.get("name")] = (float(lim.get("lower")), float(lim.get("upper")))
    names = [model.names[i] for i in range(1, model.njoints)]
    q = np.array([float(row[n + ".q"]) for n in names])
    u = np.array([float(row[n + ".u"]) for n in names])
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    h = pin.nonLinearEffects(model, data, q, u)
    B = a.friction
    tau = -a.damping * u - B * np.sign(u)
    rest = [k for k in range(len(names)) if u[k] == 0.0]
    lo, hi = np.full(len(rest), -B), np.full(len(rest), B)
    for i, k in enumerate(rest):
        lower, upper = limits.get(names[k], (-np.inf, np.inf))
        if abs(q[k] - lower) < a.stop_tol:
            hi[i] = np.inf
        if abs(q[k] - upper) < a.stop_tol:
            lo[i] = -np.inf
    Minv = np.linalg.inv(M)
    A = Minv[np.ix_(rest, rest)]
    b = (Minv @ (tau - h))[rest]
    f = np.zeros(len(rest))
    sweeps = 0
    for sweeps in range(1, 200001):
        before = f.copy()
        for i in range(len(rest)):
            w = b[i] + A[i] @ f - A[i, i] * f[i]
            f[i] = min(hi[i], max(lo[i], -w / A[i, i]))
        if np.max(np.abs(f - before)) < 1e-15:
            break
    udot = A @ f + b
    scale = max(1.0, np.max(np.abs(udot)))
    print("t = %s: %d joints at rest, projected Gauss-Seidel %d sweeps" % (row["time"], len(rest), sweeps))
    bad = 0
    for i, k in enumerate(rest):
        if lo[i] < f[i] < hi[i]:
            law, ok = "held", abs(udot[i]) <= 1e-9 * scale
        elif f[i] == lo[i]:
            law, ok = "slides forwards", udot[i] >= -1e-9 * scale
        else:
            law, ok = "slides backwards", udot[i] <= 1e-9 * scale
        stop = " [q_min]" if hi[i] == np.inf else " [q_max]" if lo[i] == -np.inf else ""
        bad += not ok
        print("  %-22s%-9s f = % .6g in [%g, %g]  %-16s udot = % .3e  %s"
              % (names[k], stop, f[i], lo[i], hi[i], law, udot[i], "ok" if ok else "VIOLATED"))
    print("conditions violated:", bad)
    return 1 if bad else 0


if __name__ == "__main__":
    raise SystemExit(main())
