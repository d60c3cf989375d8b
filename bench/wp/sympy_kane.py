"""Time for sympy.physics.mechanics.KanesMethod to derive the equations of motion of the
planar N-link pendulum of bench/models/planar_chain.mech (N thin rods, 1 kg, 0.5 m, on
revolute joints about z, relative angles q_i, u_i = dq_i/dt, gravity 9.81 along -y).

derive: building frames, points, bodies and kanes_equations() (Fr + Fr* = 0);
total:  derive + mass_matrix_full / forcing_full + lambdify to a numeric function, the
        least a user needs before integrating (compare with kanesim's load + compile).

    bench/.venv/bin/python bench/wp/sympy_kane.py 1 2 3 4
"""
import sys
import time

import sympy as sp
from sympy.physics import mechanics as me


def derive_time(n, L=0.5, m=1.0, g=9.81):
    t0 = time.perf_counter()
    q = me.dynamicsymbols("q1:%d" % (n + 1))
    u = me.dynamicsymbols("u1:%d" % (n + 1))
    N = me.ReferenceFrame("N")
    O = me.Point("O")
    O.set_vel(N, 0)
    frames, bodies, loads = [], [], []
    parent, joint = N, O
    Izz = m * L ** 2 / 12
    for i in range(n):
        B = parent.orientnew("B%d" % i, "Axis", [q[i], parent.z])
        B.set_ang_vel(parent, u[i] * parent.z)
        cm = joint.locatenew("C%d" % i, L / 2 * B.x)
        cm.v2pt_theory(joint, N, B)
        inertia = me.inertia(B, 0, Izz, Izz)
        bodies.append(me.RigidBody("R%d" % i, cm, B, m, (inertia, cm)))
        loads.append((cm, -m * g * N.y))
        tip = joint.locatenew("P%d" % i, L * B.x)
        tip.v2pt_theory(joint, N, B)
        frames.append(B)
        parent, joint = B, tip
    kdes = [qi.diff() - ui for qi, ui in zip(q, u)]
    km = me.KanesMethod(N, q_ind=q, u_ind=u, kd_eqs=kdes)
    km.kanes_equations(bodies, loads)
    derive = time.perf_counter() - t0
    Mf = km.mass_matrix_full
    ff = km.forcing_full
    sp.lambdify(list(q) + list(u), [Mf, ff], "numpy")
    total = time.perf_counter() - t0
    return dict(derive=derive, total=total)


if __name__ == "__main__":
    for a in sys.argv[1:] or ["1", "2", "3", "4"]:
        print(a, derive_time(int(a)))
