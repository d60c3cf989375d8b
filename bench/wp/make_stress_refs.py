"""Reference for tests/stress/models/mass_ratio_chain.mech: five thin rods (0.5 m) with
masses 1, 1e6, 1e-6, 1e3, 1e-3 kg on revolute joints about z, y, z, y, z (fixed in the
parent), every q = 0.1 at rest, gravity 9.81 along -y. Pinocchio's aba + SciPy DOP853
stepping onto t = 0, 0.5, ..., 2 at rtol = atol = 1e-13, its error estimated against 1e-14.

    bench/.venv/bin/python bench/wp/make_stress_refs.py
Writes tests/stress/data/mass_ratio_ref.csv and prints the estimate (quoted in the test).
"""
import os
import sys

import numpy as np
import pinocchio as pin
from scipy.integrate import DOP853

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
MASSES = [1.0, 1e6, 1e-6, 1e3, 1e-3]
L = 0.5
TS = np.linspace(0.0, 2.0, 5)


def model():
    m = pin.Model()
    m.gravity = pin.Motion(np.array([0.0, -9.81, 0.0]), np.zeros(3))
    parent = 0
    for i, mass in enumerate(MASSES):
        I = mass * L ** 2 / 12
        place = pin.SE3(np.eye(3), np.array([0.0 if i == 0 else L, 0.0, 0.0]))
        joint = pin.JointModelRZ() if i % 2 == 0 else pin.JointModelRY()
        jid = m.addJoint(parent, joint, place, "j%d" % (i + 1))
        m.appendBodyToJoint(jid, pin.Inertia(mass, np.array([L / 2, 0, 0]), np.diag([0.0, I, I])),
                            pin.SE3.Identity())
        parent = jid
    return m


def integrate(m, tol):
    d = m.createData()
    n = m.nq
    z = np.zeros(n)
    f = lambda t, y: np.concatenate([y[n:], pin.aba(m, d, y[:n], y[n:], z)])  # noqa: E731
    y = np.concatenate([np.full(n, 0.1), np.zeros(n)])
    out = [y.copy()]
    for a, b in zip(TS[:-1], TS[1:]):
        s = DOP853(f, a, y, b, rtol=tol, atol=tol)
        while s.status == "running":
            s.step()
        y = s.y.copy()
        out.append(y.copy())
    return np.array(out)


def main():
    m = model()
    y13 = integrate(m, 1e-13)
    y14 = integrate(m, 1e-14)
    est = np.max(np.abs(y13 - y14), axis=1)
    print("estimated error of q,u per row:", " ".join("%.1e" % e for e in est))
    n = len(MASSES)
    path = os.path.join(ROOT, "tests", "stress", "data", "mass_ratio_ref.csv")
    with open(path, "w") as fh:
        fh.write(",".join(["time"] + ["j[%d].q" % i for i in range(1, n + 1)] +
                          ["j[%d].u" % i for i in range(1, n + 1)]) + "\n")
        for t, y in zip(TS, y13):
            fh.write(",".join(["%.17g" % t] + ["%.17g" % v for v in y]) + "\n")
    print("wrote", path)


if __name__ == "__main__":
    sys.exit(main())
