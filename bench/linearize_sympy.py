"""kanesim linearize against sympy's symbolic linearizer on the same non-holonomic model.

The model: a thin uniform disk (radius a, mass m) rolling without slipping on horizontal
ground, linearized about upright rolling at speed v (issue 23, docs/benchmarks.md
"Linearization"). kanesim: examples/rolling_disk_upright.mech. sympy: the formulation below,
written for this benchmark with sympy.physics.mechanics (Kane's method with dependent speeds
and velocity constraints, then KanesMethod.linearize, which runs sympy's Linearizer).

Both give 5 coordinates and 3 speeds (8 states); compared: the eigenvalues, against each other
and against the closed form of the lean mode, lambda^2 = (4 g / a - 12 (v / a)^2) / 5.

    bench/.venv/bin/python bench/linearize_sympy.py [--kanesim build/cli/kanesim] [--v 0.5,2]

Timed: sympy's formulation (KanesMethod), its linearization (symbolic A and B at the operating
point) and the numeric evaluation, against the wall time of `kanesim linearize` (a process,
load and compile included).
"""
import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time

import numpy as np
import sympy as sm
import sympy.physics.mechanics as me

G, A_RADIUS, MASS = 9.81, 0.3, 1.5  # as in examples/rolling_disk_upright.mech


def sympy_model():
    """Kane's equations of the rolling disk, dependent speeds eliminated by the constraints."""
    yaw, lean, spin, x, y = me.dynamicsymbols("yaw lean spin x y")
    w1, w2, w3, v1, v2, v3 = me.dynamicsymbols("w1 w2 w3 v1 v2 v3")
    g, m, r = sm.symbols("g m r", positive=True)

    N = me.ReferenceFrame("N")                      # ground, z up
    Y = N.orientnew("Y", "Axis", [yaw, N.z])        # heading
    L = Y.orientnew("L", "Axis", [lean, Y.x])       # lean about the rolling direction
    D = L.orientnew("D", "Axis", [spin, L.y])       # the disk spins about L.y
    # Speeds: the disk's angular velocity (w) and its centre's velocity (v), both in L.
    D.set_ang_vel(N, w1 * L.x + w2 * L.y + w3 * L.z)
    ang = (Y.ang_vel_in(N) + L.ang_vel_in(Y) + D.ang_vel_in(L)).express(L)
    kd = [(ang - D.ang_vel_in(N)).dot(e) for e in (L.x, L.y, L.z)]

    centre = me.Point("centre")
    centre.set_vel(N, v1 * L.x + v2 * L.y + v3 * L.z)
    # The geometric contact point (on the ground, below the centre) moves with
    # v_centre - (angular velocity of L) x (r L.z); its ground coordinates are x, y.
    contact_vel = centre.vel(N) - L.ang_vel_in(N).cross(r * L.z)
    kd += [x.diff() - contact_vel.dot(N.x), y.diff() - contact_vel.dot(N.y)]
    # Rolling without slipping: the disk's material point at the contact is at rest.
    material = centre.vel(N) + D.ang_vel_in(N).cross(-r * L.z)
    constraints = [material.dot(e) for e in (L.x, L.y, L.z)]

    disk = me.RigidBody("disk", centre, D, m, (me.inertia(L, m * r**2 / 4, m * r**2 / 2, m * r**2 / 4), centre))
    loads = [(centre, -m * g * N.z)]
    km = me.KanesMethod(N, q_ind=[yaw, lean, spin, x, y], u_ind=[w1, w2, w3], kd_eqs=kd,
                        u_dependent=[v1, v2, v3], velocity_constraints=constraints)
    km.kanes_equations([disk], loads)
    return km, (yaw, lean, spin, x, y), (w1, w2, w3, v1, v2, v3), (g, m, r)


def sympy_eigenvalues(v_values):
    t0 = time.perf_counter()
    km, q, u, (g, m, r) = sympy_model()
    t1 = time.perf_counter()
    # Upright rolling along Y.x at speed v: spin rate w2 = -v / r... the sign follows from
    # the constraint v_centre = -w x (-r L.z) = w2 r L.x, so v1 = w2 r; take w2 = v / r.
    vs = sm.Symbol("v", positive=True)
    op = {q[0]: 0, q[1]: 0, q[2]: 0, q[3]: 0, q[4]: 0,
          u[0]: 0, u[1]: vs / r, u[2]: 0, u[3]: vs, u[4]: 0, u[5]: 0}
    qd_op = {qi.diff(): 0 for qi in q}
    qd_op[q[2].diff()] = vs / r
    qd_op[q[3].diff()] = vs
    ud_op = {ui.diff(): 0 for ui in u}
    A, _B, _r = km.linearize(op_point=[op, qd_op, ud_op], A_and_B=True, simplify=False)
    t2 = time.perf_counter()
    out = {}
    for v in v_values:
        An = np.array(A.subs({g: G, m: MASS, r: A_RADIUS, vs: v}).evalf(), dtype=float)
        out[v] = np.linalg.eigvals(An)
    t3 = time.perf_counter()
    return out, {"formulate_s": t1 - t0, "linearize_s": t2 - t1, "evaluate_s": t3 - t2}, A.shape


def kanesim_eigenvalues(binary, v_values):
    out, walls = {}, []
    with tempfile.TemporaryDirectory() as tmp:
        for v in v_values:
            path = os.path.join(tmp, f"disk_{v}.json")
            t0 = time.perf_counter()
            subprocess.run([binary, "linearize", "examples/rolling_disk_upright.mech", "--set", f"v={v}", "-o", path],
                           check=True, capture_output=True)
            walls.append(time.perf_counter() - t0)
            with open(path) as f:
                ev = json.load(f)["eigenvalues"]
            out[v] = np.array([complex(re, im) for re, im in ev])
    return out, walls


def closed_form(v):
    lam2 = (4 * G / A_RADIUS - 12 * (v / A_RADIUS) ** 2) / 5
    return math.sqrt(lam2) if lam2 >= 0 else 1j * math.sqrt(-lam2)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kanesim", default="build/cli/kanesim")
    ap.add_argument("--v", default="0.5,2")
    args = ap.parse_args()
    v_values = [float(s) for s in args.v.split(",")]

    k_eigs, k_walls = kanesim_eigenvalues(args.kanesim, v_values)
    s_eigs, s_times, shape = sympy_eigenvalues(v_values)
    print(f"sympy {sm.__version__}: A is {shape[0]}x{shape[1]}; formulate {s_times['formulate_s']:.2f} s, "
          f"linearize {s_times['linearize_s']:.2f} s, evaluate {s_times['evaluate_s']:.2f} s")
    print(f"kanesim linearize (process, load, compile, linearize, eigenvalues): "
          f"{', '.join(f'{w * 1000:.1f} ms' for w in k_walls)}")
    worst = 0.0
    for v in v_values:
        ks = sorted(k_eigs[v], key=lambda z: (round(z.real, 9), round(z.imag, 9)))
        ss = sorted(s_eigs[v], key=lambda z: (round(z.real, 9), round(z.imag, 9)))
        diff = max(min(abs(k - s) for s in ss) for k in ks)
        worst = max(worst, diff)
        lean = closed_form(v)
        k_lean = max(abs(z) for z in ks)
        print(f"v = {v}: kanesim {np.round(ks, 10)}")
        print(f"        sympy   {np.round(ss, 10)}")
        print(f"        largest |eigenvalue| gap {diff:.2e}; lean mode closed form {lean:.10f}, "
              f"kanesim |lambda|max {k_lean:.10f}")
    print(f"worst eigenvalue difference kanesim - sympy: {worst:.2e}")
    return 0 if worst < 1e-6 else 1


if __name__ == "__main__":
    sys.exit(main())
