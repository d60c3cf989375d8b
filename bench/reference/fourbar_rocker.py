#!/usr/bin/env python3
"""Independent reference for a non-Grashof four-bar whose links all rock (issue 38 §1,
turning points): examples/fourbar.mech with a = 0.55, b = 0.5, c = 0.45, d = 0.7 m
(s + l = 1.15 > p + q = 1.05: no link turns over), theta0 = 1.2 rad, omega0 = 8 rad/s.

Model (stated in full; this script reads no .mech file and no kanesim code):
  in the x-y plane, absolute link angles p1 (crank, pivot at the origin), p2 (coupler, from
  the crank's tip), p3 (rocker, pivot at (d, 0)); uniform thin rods of mass m1 = 0.5,
  m2 = 1.0, m3 = 0.8 kg; gravity 9.81 m/s^2 along -y; no friction. The loop closes the
  coupler's tip on the rocker's:
    Phi(p) = [a cos p1 + b cos p2 - d - c cos p3,  a sin p1 + b sin p2 - c sin p3] = 0.   (1)
  Lagrange's equations with multipliers, in the absolute angles (no partition of the
  speeds, so nothing here has a turning point):
    M(p) p'' + h(p, p') + dV/dp + J^T lam = 0,   J p'' = -J' p'   (J = dPhi/dp)           (2)
    M = [[m1 a^2/3 + m2 a^2, m2 a b/2 cos(p1 - p2), 0], [., m2 b^2/3, 0], [0, 0, m3 c^2/3]],
    h = m2 a b/2 sin(p1 - p2) [p2'^2, -p1'^2, 0],
    V = g (m1 a/2 sin p1 + m2 (a sin p1 + b/2 sin p2) + m3 c/2 sin p3).
  Integrated by the classical Runge-Kutta method (written here; NumPy only), 400 steps of
  2.5e-5 s between the output times 0.01 s apart; after each output time the state is put back
  on (1) and on J p' = 0 by Gauss-Newton (minimum-norm steps), which moves it by the drift
  only (reported).
  Start: p1 = 1.2, p1' = 8; p2, p3 by Newton on (1) from p2 = -1.47, p3 = 3.11 (the branch
  kanesim's assembly finds from the example's start values), p2', p3' from J p' = 0.

Outputs: tests/stress/data/fourbar_rocker_ref.csv with time and kanesim's joint angles
  crank_pivot.q = p1, crank_coupler.q = p2 - p1, rocker_pivot.q = p3 (unwrapped, from
  the start's values mod 2 pi taken in (-pi, pi]) at t = 0, 0.01, ..., 10; checks printed:
  the energy error over the rows, the largest projection correction, and the same
  reference with steps twice as long (how far the two are apart: 16 times the error of
  this one).

Run:  /usr/bin/python3 bench/reference/fourbar_rocker.py   (a few minutes)
"""
import math
import os
import sys

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "..", "..", "tests", "stress", "data", "fourbar_rocker_ref.csv")

a, b, c, d = 0.55, 0.5, 0.45, 0.7
m1, m2, m3, g = 0.5, 1.0, 0.8, 9.81


def phi(p):
    return np.array([a * math.cos(p[0]) + b * math.cos(p[1]) - d - c * math.cos(p[2]),
                     a * math.sin(p[0]) + b * math.sin(p[1]) - c * math.sin(p[2])])


def jac(p):
    return np.array([[-a * math.sin(p[0]), -b * math.sin(p[1]), c * math.sin(p[2])],
                     [a * math.cos(p[0]), b * math.cos(p[1]), -c * math.cos(p[2])]])


def energy(p, w):
    M = mass(p)
    V = g * (m1 * a / 2 * math.sin(p[0]) + m2 * (a * math.sin(p[0]) + b / 2 * math.sin(p[1])) +
             m3 * c / 2 * math.sin(p[2]))
    return 0.5 * w @ M @ w + V


def mass(p):
    k = m2 * a * b / 2 * math.cos(p[0] - p[1])
    return np.array([[m1 * a * a / 3 + m2 * a * a, k, 0.0], [k, m2 * b * b / 3, 0.0], [0.0, 0.0, m3 * c * c / 3]])


def rhs(_t, y):
    p, w = y[:3], y[3:]
    M, J = mass(p), jac(p)
    s = m2 * a * b / 2 * math.sin(p[0] - p[1])
    h = np.array([s * w[1] ** 2, -s * w[0] ** 2, 0.0])
    dV = g * np.array([(m1 / 2 + m2) * a * math.cos(p[0]), m2 * b / 2 * math.cos(p[1]), m3 * c / 2 * math.cos(p[2])])
    # J' p' = d/dt (J) p': each column's derivative times its own speed.
    Jdw = np.array([-a * math.cos(p[0]) * w[0] ** 2 - b * math.cos(p[1]) * w[1] ** 2 + c * math.cos(p[2]) * w[2] ** 2,
                    -a * math.sin(p[0]) * w[0] ** 2 - b * math.sin(p[1]) * w[1] ** 2 + c * math.sin(p[2]) * w[2] ** 2])
    K = np.zeros((5, 5))
    K[:3, :3], K[:3, 3:], K[3:, :3] = M, J.T, J
    sol = np.linalg.solve(K, np.concatenate([-h - dV, -Jdw]))
    return np.concatenate([w, sol[:3]])


def project(y):
    """Back onto (1) and J p' = 0 by minimum-norm Gauss-Newton; returns the state and the move."""
    p, w = y[:3].copy(), y[3:].copy()
    for _ in range(20):
        r = phi(p)
        if np.max(np.abs(r)) < 1e-15:
            break
        J = jac(p)
        p -= J.T @ np.linalg.solve(J @ J.T, r)
    J = jac(p)
    w -= J.T @ np.linalg.solve(J @ J.T, J @ w)
    z = np.concatenate([p, w])
    return z, float(np.max(np.abs(z - y)))


def start():
    p = np.array([1.2, -1.47, 3.11])
    for _ in range(50):  # Newton on p2, p3 with p1 held
        J = jac(p)[:, 1:]
        p[1:] -= np.linalg.solve(J, phi(p))
    J = jac(p)
    w = np.array([8.0, 0.0, 0.0])
    w[1:] = np.linalg.solve(J[:, 1:], -J[:, 0] * w[0])
    return np.concatenate([p, w])


def rk4(y, h, n):
    for _ in range(n):
        k1 = rhs(0, y)
        k2 = rhs(0, y + h / 2 * k1)
        k3 = rhs(0, y + h / 2 * k2)
        k4 = rhs(0, y + h * k3)
        y = y + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return y


def integrate(steps):
    y = start()
    rows, moved = [np.concatenate([[0.0], y])], 0.0
    for k in range(1000):
        y, m = project(rk4(y, 0.01 / steps, steps))
        moved = max(moved, m)
        rows.append(np.concatenate([[(k + 1) * 0.01], y]))
    return np.array(rows), moved


def main():
    rows, moved = integrate(400)
    check, _ = integrate(200)
    e = [energy(r[1:4], r[4:7]) for r in rows]
    print("energy error (relative to E0) %.2g, largest projection move %.2g, step 5e-5 vs 2.5e-5 %.2g rad" %
          (max(abs(x - e[0]) for x in e) / abs(e[0]), moved, np.max(np.abs(rows[:, 1:4] - check[:, 1:4]))))
    p0 = rows[0, 1:4]
    shift = [math.remainder(p0[0], 2 * math.pi) - p0[0], math.remainder(p0[1] - p0[0], 2 * math.pi) - (p0[1] - p0[0]),
             math.remainder(p0[2], 2 * math.pi) - p0[2]]
    with open(OUT, "w") as f:
        f.write("time,crank_pivot.q,crank_coupler.q,rocker_pivot.q\n")
        for r in rows:
            f.write("%.2f,%.17g,%.17g,%.17g\n" % (r[0], r[1] + shift[0], r[2] - r[1] + shift[1], r[3] + shift[2]))
    print("wrote", os.path.normpath(OUT))
    return 0


if __name__ == "__main__":
    sys.exit(main())
