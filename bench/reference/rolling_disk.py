#!/usr/bin/env python3
"""Independent high-precision reference for bench/models/rolling_disk_wobble.mech
(examples/rolling_disk.mech with a lean-rate disturbance; work-precision, issue 6).

Model (stated in full; this script reads no .mech file and no kanesim code): a thin uniform
disk, radius a = 0.3 m, mass m = 1.5 kg, moments A = m a^2 / 2 (axis), B = m a^2 / 4
(diameter), rolling without slip on the horizontal plane, gravity g = 9.81 m/s^2.

Equations: the classic three-DOF rolling disk (heading psi, lean theta, spin phi) as in
O'Reilly, "The dynamics of rolling disks and sliding disks", Nonlinear Dynamics 10 (1996)
287-305, Sec. 3, and Neimark & Fufaev, "Dynamics of Nonholonomic Systems" (1972), Ch. II, re-derived
here by Newton-Euler in the Resal frame (NOT Kane's method, no constraint matrices):
  Resal frame e1 (horizontal, tangent to the rim at the contact P), e2 (in the disk plane, from
  P to the centre C), e3 (disk axis); vertical K = cos(theta) e2 - sin(theta) e3; frame rate
  Omega_f = theta' e1 + psi' K; disk rate w = Omega_f + phi' e3 = (theta', psi' cos, w3),
  w3 = phi' - psi' sin(theta).  Rolling: v_C = w x (a e2) = -a w3 e1 + a theta' e3.
  Newton m a_C = F - m g K and Euler dH_C/dt = (P - C) x F, H_C = (B theta', B psi' cos, A w3),
  with F eliminated, give
    (B + m a^2) theta'' = -(A + m a^2) psi' w3 cos(theta) - B psi'^2 sin cos + m g a sin(theta)  (1)
    B cos(theta) psi''  = 2 B psi' theta' sin(theta) + A theta' w3                               (2)
    (A + m a^2) w3'     = m a^2 psi' theta' cos(theta)                                           (3)
    phi' = w3 + psi' sin(theta)                                                                  (4)
  and the contact-point kinematics (world Z up, e1 = (cos psi, sin psi, 0)):
    X_C' = -a w3 cos(psi) + a theta' cos(theta) sin(psi),
    Y_C' = -a w3 sin(psi) - a theta' cos(theta) cos(psi),   Z_C = a cos(theta).                   (5)
  Cross-check of (1)-(3): a direct Newton-Euler solve in world axes (9 unknowns: angular and
  linear acceleration, contact force) with the rolling condition differentiated geometrically
  (e2 = normalized vertical part of the disk plane, no Resal angles), at random states.

Mapping to kanesim's example (world y up): x = X, y = Z, z = -Y; the body frame is the Resal
frame turned by the spin phi about e3, so R_WB = Rx(-pi/2) Rz(psi) Rx(pi/2 + theta) Rz(phi)
and the quaternion is the product of the four half-angle quaternions (continuous in time,
equal to kanesim's start quaternion at t = 0).  The example's lean angle is -theta.

Problem (bench/README.md): the example's steady circular rolling (lean 0.2 rad, centre circle
radius 1 m, v = 1.146 m/s, above the critical speed sqrt(g a / 3) = 0.99 m/s) disturbed by a
lean rate LEAN_RATE at t = 0, with the centre velocity that rolling then requires
(v_C = -a w3 e1 + a theta' e3): the disk wobbles about the steady turn (quasi-periodic, it does
not fall; lean between 0.04 and 0.33 rad).  kanesim: bench/models/rolling_disk_wobble.mech.

Integration: the Gragg-Bulirsch-Stoer integrator of double_pendulum.py in mpmath at 30 digits
(local tol 1e-25), repeated at 22 digits / 1e-18 for the accuracy estimate.  Cross-checks:
energy; the undisturbed steady rolling (LEAN_RATE = 0) against its closed form; SciPy DOP853.

Outputs:
  bench/data/rolling_disk_ref.csv  time,free.q[1..7] (centre x, y, z; quaternion w, x, y, z),
                                   lean, heading, spin  at t = 0, 0.1, ..., 10
  bench/data/rolling_disk_ref.md   how it was made, the accuracy estimate, the checks

Run:  bench/.venv/bin/python bench/reference/rolling_disk.py   (about 2-4 min)
"""
import os
import platform
import sys
import time

import mpmath as mp
import numpy as np
import scipy
from scipy.integrate import solve_ivp

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
DATA = os.path.join(ROOT, "bench", "data")
sys.path.insert(0, HERE)
from double_pendulum import GBS  # noqa: E402  (the extrapolation integrator, mpmath)

A_RAD, MASS, GRAV = "0.3", "1.5", "9.81"
THETA_EX, RC = "0.2", "1.0"        # the example's lean and centre-circle radius
LEAN_RATE = "0.5"                  # the disturbance of the benchmark problem (rad/s)
T_END, N_OUT = 10, 101


def consts(M):
    """(a, m, g, A, B) in the arithmetic module M (mpmath or numpy)."""
    a, m, g = (M.mpf(s) for s in (A_RAD, MASS, GRAV)) if M is mp else (float(A_RAD), float(MASS), float(GRAV))
    return a, m, g, m * a * a / 2, m * a * a / 4


def rhs(y, M):
    """y = [theta, psi, phi, theta', psi', w3, X_C, Y_C] -> dy/dt, eqs. (1)-(5)."""
    a, m, g, A, B = consts(M)
    th, ps, _, thd, psd, w3, _, _ = y
    s, c = M.sin(th), M.cos(th)
    thdd = (-(A + m * a * a) * psd * w3 * c - B * psd * psd * s * c + m * g * a * s) / (B + m * a * a)
    psdd = (2 * B * psd * thd * s + A * thd * w3) / (B * c)
    w3d = m * a * a * psd * thd * c / (A + m * a * a)
    phd = w3 + psd * s
    sp_, cp = M.sin(ps), M.cos(ps)
    xd = -a * w3 * cp + a * thd * c * sp_
    yd = -a * w3 * sp_ - a * thd * c * cp
    return [thd, psd, phd, thdd, psdd, w3d, xd, yd]


def start(lean_rate, M):
    """The example's start: steady turn (theta = -0.2 in this convention) plus a lean rate."""
    a, m, g, A, B = consts(M)
    the = M.mpf(THETA_EX) if M is mp else float(THETA_EX)
    rc = M.mpf(RC) if M is mp else float(RC)
    Om = M.sqrt(g * M.sin(the) / (M.cos(the) * (a * M.sin(the) / 4 + rc * 3 / 2)))
    V = Om * rc
    lr = M.mpf(lean_rate) if M is mp else float(lean_rate)
    return [-the, 0 * the, 0 * the, lr, Om, -V / a, 0 * the, a * M.sin(the)], Om, V


def qmul(p, q):
    return [p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3],
            p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2],
            p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1],
            p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0]]


def kanesim_q(y, M):
    """free.q of kanesim's example: centre (x, y, z) = (X, Z, -Y), quaternion of R_WB."""
    a = consts(M)[0]
    th, ps, ph = y[0], y[1], y[2]
    h = lambda al: (M.cos(al / 2), M.sin(al / 2))  # noqa: E731
    half = M.pi / 2
    cx0, sx0 = h(-half)
    cz1, sz1 = h(ps)
    cx2, sx2 = h(half + th)
    cz3, sz3 = h(ph)
    q = qmul(qmul(qmul([cx0, sx0, 0 * cx0, 0 * cx0], [cz1, 0 * cz1, 0 * cz1, sz1]),
                  [cx2, sx2, 0 * cx2, 0 * cx2]), [cz3, 0 * cz3, 0 * cz3, sz3])
    return [y[6], a * M.cos(th), -y[7]] + q


def energy(y, M):
    a, m, g, A, B = consts(M)
    th, _, _, thd, psd, w3, _, _ = y
    return (m * a * a * (w3 * w3 + thd * thd) + B * thd * thd + B * (psd * M.cos(th)) ** 2 + A * w3 * w3) / 2 \
        + m * g * a * M.cos(th)


def newton_euler_check(rng):
    """Eqs. (1)-(3) against a direct world-axes Newton-Euler solve with the contact force."""
    a, m, g, A, B = consts(np)
    Z = np.array([0.0, 0.0, 1.0])
    worst = 0.0
    for _ in range(100):
        th, ps = rng.uniform(-1.2, 1.2), rng.uniform(-np.pi, np.pi)
        thd, psd, w3 = rng.uniform(-3, 3, 3)
        e1 = np.array([np.cos(ps), np.sin(ps), 0.0])
        hv = np.array([np.sin(ps), -np.cos(ps), 0.0])
        e2 = np.cos(th) * Z + np.sin(th) * hv
        e3 = -np.sin(th) * Z + np.cos(th) * hv
        w = thd * e1 + psd * np.cos(th) * e2 + w3 * e3
        r = a * e2                                    # C - P
        Iw = B * np.eye(3) + (A - B) * np.outer(e3, e3)
        # geometric rate of e2 = normalize(Z - (Z.e3) e3), e3 material: e3' = w x e3
        e3d = np.cross(w, e3)
        wv = Z - (Z @ e3) * e3
        wvd = -(Z @ e3d) * e3 - (Z @ e3) * e3d
        e2d = (wvd - e2 * (e2 @ wvd)) / np.linalg.norm(wv)
        # unknowns x = [alpha (3), a_C (3), F (3)]
        K = np.zeros((9, 9))
        rhs_ = np.zeros(9)
        K[0:3, 3:6] = m * np.eye(3)
        K[0:3, 6:9] = -np.eye(3)
        rhs_[0:3] = -m * g * Z
        K[3:6, 0:3] = Iw
        K[3:6, 6:9] = np.array([[0, -(-r)[2], (-r)[1]], [(-r)[2], 0, -(-r)[0]], [-(-r)[1], (-r)[0], 0]])
        K[3:6, 6:9] *= -1                             # I alpha - (-r) x F = -w x I w
        rhs_[3:6] = -np.cross(w, Iw @ w)
        # d/dt (v_C + w x (-a e2)) = 0: a_C - alpha x (a e2) - w x (a e2') = 0
        skew_r = np.array([[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]])
        K[6:9, 3:6] = np.eye(3)
        K[6:9, 0:3] = skew_r                          # -alpha x r = r x alpha
        rhs_[6:9] = np.cross(w, a * e2d)
        x = np.linalg.solve(K, rhs_)
        # the reduced equations' alpha = d/dt (theta' e1 + psi' cos e2 + w3 e3)
        y = [th, ps, 0.0, thd, psd, w3, 0.0, 0.0]
        dy = rhs(y, np)
        Of = thd * e1 + psd * (np.cos(th) * e2 - np.sin(th) * e3)
        alpha = dy[3] * e1 + (dy[4] * np.cos(th) - psd * thd * np.sin(th)) * e2 + dy[5] * e3 + np.cross(Of, w)
        worst = max(worst, np.max(np.abs(alpha - x[0:3])) / (1 + np.max(np.abs(x[0:3]))))
    return worst


def run_mp(lean_rate, dps, tol):
    with mp.workdps(dps):
        y0, _, _ = start(lean_rate, mp)
        gbs = GBS(lambda y: rhs(y, mp))
        t_out = [mp.mpf(i) / 10 for i in range(N_OUT)]
        t0 = time.time()
        ys = gbs.integrate(y0, t_out, mp.mpf(tol), h0=mp.mpf("0.05"))
        wall = time.time() - t0
        rows = [kanesim_q(y, mp) + [y[0], y[1], y[2]] for y in ys]
        E = [energy(y, mp) for y in ys]
    return ys, rows, E, dict(nstep=gbs.nstep, nrej=gbs.nrej, nfev=gbs.nfev, wall=wall)


def main():
    d_ne = newton_euler_check(np.random.default_rng(6))
    print("eqs. (1)-(3) vs world Newton-Euler with contact force, 100 states: max rel diff %.1e" % d_ne)
    assert d_ne < 1e-12

    # ---- undisturbed steady turn against its closed form
    dps = 30
    _, rows0, _, st0 = run_mp("0", 24, "1e-19")
    with mp.workdps(24):
        y0, Om, V = start("0", mp)
        worst0 = mp.mpf(0)
        for i, r in enumerate(rows0):
            t = mp.mpf(i) / 10
            rc = V / Om
            yc = [rc * mp.sin(Om * t), y0[7] + rc * (1 - mp.cos(Om * t))]
            ph = (y0[5] + Om * mp.sin(y0[0])) * t
            exact = kanesim_q([y0[0], Om * t, ph, 0, Om, y0[5], yc[0], yc[1]], mp)
            worst0 = max(worst0, max(abs(p - q) for p, q in zip(r[:7], exact)))
    print("steady turn vs closed form, 24 digits: max diff %s" % mp.nstr(worst0, 3))

    ys, rows, E, st_a = run_mp(LEAN_RATE, dps, "1e-25")
    print("primary run (30 digits):", st_a)
    ys_b, rows_b, _, st_b = run_mp(LEAN_RATE, 22, "1e-18")
    print("second run (22 digits):", st_b)
    mp.mp.dps = dps
    diff = [max(abs(p - q) for p, q in zip(r1[:7], r2[:7])) for r1, r2 in zip(rows, rows_b)]
    dE = max(abs(e - E[0]) for e in E)
    leans = [-float(y[0]) for y in ys]
    print("E0 = %s J, max |E - E0| = %s; lean min %.4f max %.4f" % (mp.nstr(E[0], 17), mp.nstr(dE, 3),
                                                                     min(leans), max(leans)))

    y0n, _, _ = start(LEAN_RATE, np)
    t_eval = np.arange(N_OUT) / 10.0
    ref = np.array([[float(v) for v in r[:7]] for r in rows])
    dop = {}
    for tol in (1e-11, 1e-13):
        s = solve_ivp(lambda t, y: rhs(y, np), (0, T_END), y0n, method="DOP853", rtol=tol, atol=tol, t_eval=t_eval)
        qn = np.array([kanesim_q(s.y[:, i], np) for i in range(N_OUT)])
        dop[tol] = np.max(np.abs(qn - ref), axis=1)
        print("DOP853 %g: max |q - ref| at 2 s %.1e, at 10 s %.1e" % (tol, dop[tol][20], dop[tol][-1]))

    os.makedirs(DATA, exist_ok=True)
    csv = os.path.join(DATA, "rolling_disk_ref.csv")
    with open(csv, "w") as fh:
        fh.write("time," + ",".join("free.q[%d]" % i for i in range(1, 8)) + ",lean,heading,spin\n")
        for i, r in enumerate(rows):
            vals = [float(x) for x in r]
            vals[7] = -vals[7]  # the example's lean = -theta
            fh.write(",".join("%.17g" % v for v in [float(mp.mpf(i) / 10)] + vals) + "\n")
    print("wrote", csv)

    at = lambda arr, t: arr[int(round(t * 10))]  # noqa: E731
    md = ["# Rolling-disk reference (bench/reference/rolling_disk.py)", "",
          "Made by `bench/reference/rolling_disk.py` (model, equations (1)-(5), mapping to kanesim's",
          "coordinates and start in its docstring): the classic lean/heading/spin equations of the",
          "rolling disk, re-derived by Newton-Euler in the Resal frame, integrated by mpmath",
          "Gragg-Bulirsch-Stoer (order 24). Start: the example's steady turn (lean 0.2 rad, centre",
          "circle 1 m) plus a lean rate of %s rad/s (bench/models/rolling_disk_wobble.mech)." % LEAN_RATE, "",
          "| | value |", "|---|---|",
          "| primary run | %d digits, local tol 1e-25: %d steps, %d RHS, %.1f s |" % (
              dps, st_a["nstep"], st_a["nfev"], st_a["wall"]),
          "| second run | 22 digits, local tol 1e-18: %d steps, %.1f s |" % (st_b["nstep"], st_b["wall"]),
          "| accuracy estimate: max over free.q of abs(primary - second), t = 2 s / 10 s / all rows | %s / %s / %s |" % (
              mp.nstr(at(diff, 2), 2), mp.nstr(at(diff, 10), 2), mp.nstr(max(diff), 2)),
          "| energy E0, max abs(E - E0) over the rows (primary) | %s J, %s J |" % (mp.nstr(E[0], 17), mp.nstr(dE, 2)),
          "| eqs. (1)-(3) against a world-axes Newton-Euler solve with contact force (100 states) | max rel diff %.1e |" % d_ne,
          "| steady turn (no lean rate) against its closed form over 10 s, 24 digits | %s |" % mp.nstr(worst0, 2),
          "| lean over 10 s (wobble about 0.2) | %.4f ... %.4f rad |" % (min(leans), max(leans)),
          "| SciPy DOP853 (double), max abs(q - ref) at 2 s / 10 s, rtol = atol = 1e-11 | %.1e / %.1e |" % (
              at(dop[1e-11], 2), at(dop[1e-11], 10)),
          "| same at 1e-13 | %.1e / %.1e |" % (at(dop[1e-13], 2), at(dop[1e-13], 10)), "",
          "All 17 printed digits are converged; the motion is quasi-periodic (integrable system), so",
          "errors of a double-precision tool grow about linearly with time, not exponentially.", "",
          "Versions: Python %s, mpmath %s, numpy %s, scipy %s." % (
              platform.python_version(), mp.__version__, np.__version__, scipy.__version__), ""]
    with open(os.path.join(DATA, "rolling_disk_ref.md"), "w") as fh:
        fh.write("\n".join(md))
    print("wrote", os.path.join(DATA, "rolling_disk_ref.md"))


if __name__ == "__main__":
    main()
