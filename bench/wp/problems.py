"""The work-precision problems (bench/README.md states them in words) and their references.

A problem is a mechanism, a horizon T and a reference q_ref(T). Error of a run is
max over joints |q(T) - q_ref(T)|; the joint order is the tree order j[1..N] (chain) or
shoulder, elbow (double pendulum) in every tool.
"""
import csv
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
BENCH = os.path.dirname(HERE)
ROOT = os.path.dirname(BENCH)
TESTS_DATA = os.path.join(ROOT, "tests", "data")
BENCH_DATA = os.path.join(BENCH, "data")


class Problem:
    def __init__(self, kind, n, T):
        self.kind = kind          # "pendulum" or "chain"
        self.n = 2 if kind == "pendulum" else n
        self.T = T
        if kind == "pendulum":
            self.name = "double_pendulum_T%g" % T
            self.mech = os.path.join(ROOT, "examples", "double_pendulum.mech")
            self.sets = []
            self.L, self.q0 = 1.0, np.pi / 2
            self.axes = ["z", "z"]
        else:
            self.name = "chain%d_T%g" % (n, T)
            self.mech = os.path.join(ROOT, "examples", "chain.mech")
            self.sets = ["N=%d" % n]
            self.L, self.q0 = 0.5, 0.1
            self.axes = ["z" if i % 2 == 1 else "y" for i in range(1, n + 1)]
        self.m = 1.0
        self.g = 9.81

    @property
    def title(self):
        if self.kind == "pendulum":
            return "double pendulum, T = %g s" % self.T
        return "chain N = %d, T = %g s" % (self.n, self.T)

    def ref_path(self):
        if self.kind == "pendulum":
            return os.path.join(TESTS_DATA, "double_pendulum_ref.csv")
        committed = os.path.join(TESTS_DATA, "chain%d_ref.csv" % self.n)
        if os.path.exists(committed):
            return committed
        return os.path.join(BENCH_DATA, "chain%d_ref.csv" % self.n)

    def q_ref(self):
        """q_ref(T) from the reference CSV (the row whose time is T)."""
        with open(self.ref_path()) as fh:
            rows = list(csv.reader(fh))
        head = rows[0]
        if self.kind == "pendulum":
            cols = [head.index("shoulder.q"), head.index("elbow.q")]
        else:
            cols = [head.index("j[%d].q" % i) for i in range(1, self.n + 1)]
        for r in rows[1:]:
            if abs(float(r[0]) - self.T) < 1e-9:
                return np.array([float(r[c]) for c in cols])
        raise KeyError("no row at t = %g in %s" % (self.T, self.ref_path()))

    def error(self, q):
        return float(np.max(np.abs(np.asarray(q) - self.q_ref())))

    # Trust limit of the reference at T (bench/reference/README.md, the .md reports):
    # errors below this are not measurable against a double-precision reference.
    def trust_floor(self):
        if self.kind == "pendulum":
            return 3e-12 if self.T <= 2 else 1e-4
        return 1e-11 if self.T <= 1 else (1e-7 if self.n <= 10 else 3e-8)


def all_problems(quick=False):
    if quick:
        return [Problem("pendulum", 2, 2.0), Problem("chain", 5, 1.0), Problem("chain", 20, 1.0)]
    ps = [Problem("pendulum", 2, 2.0), Problem("pendulum", 2, 10.0)]
    for n in (5, 10, 20, 50, 100):
        for T in (1.0, 5.0):
            ps.append(Problem("chain", n, T))
    return ps


def mjcf(p):
    """MJCF text for a problem: a hinge per joint in the child body, axes fixed in the
    parent (at q = 0 the child frame equals the parent's, so the axis reads the same), no
    contact, no damping, no armature, no limits. MuJoCo needs a positive-definite body
    inertia: the thin rod's zero axial moment is replaced by 1e-12 of the transverse one."""
    I = p.m * p.L ** 2 / 12
    lines = ['<mujoco model="%s">' % p.name,
             '  <option gravity="0 %r 0" timestep="0.001">' % (-p.g),
             '    <flag contact="disable"/>',
             '  </option>',
             '  <worldbody>']
    indent = "    "
    for i, ax in enumerate(p.axes):
        pos = "0 0 0" if i == 0 else "%r 0 0" % p.L
        axis = "0 0 1" if ax == "z" else "0 1 0"
        lines.append('%s<body name="b%d" pos="%s">' % (indent, i + 1, pos))
        lines.append('%s  <joint name="j%d" type="hinge" axis="%s"/>' % (indent, i + 1, axis))
        lines.append('%s  <inertial pos="%r 0 0" mass="%r" diaginertia="%r %r %r"/>'
                     % (indent, p.L / 2, p.m, I * 1e-12, I, I))
        indent += "  "
    for i in reversed(range(len(p.axes))):
        indent = indent[:-2]
        lines.append("%s</body>" % indent)
    lines += ["  </worldbody>", "</mujoco>"]
    return "\n".join(lines)


def pin_model(p):
    import pinocchio as pin
    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, -p.g, 0.0]), np.zeros(3))
    I = p.m * p.L ** 2 / 12
    inertia = pin.Inertia(p.m, np.array([p.L / 2, 0.0, 0.0]), np.diag([0.0, I, I]))
    parent = 0
    for i, ax in enumerate(p.axes):
        place = pin.SE3(np.eye(3), np.array([0.0 if i == 0 else p.L, 0.0, 0.0]))
        joint = pin.JointModelRZ() if ax == "z" else pin.JointModelRY()
        jid = model.addJoint(parent, joint, place, "j%d" % (i + 1))
        model.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
        parent = jid
    return model
