"""The work-precision problems (bench/README.md states them in words) and their references.

A problem is a mechanism, a horizon T and a reference q_ref(T). Error of a run is
max over joints |q(T) - q_ref(T)|; the joint order is the tree order j[1..N] (chain),
shoulder, elbow (double pendulum), crank_pivot, crank_coupler, rocker_pivot (four-bar) in
every tool. The rolling disk's "joint" is its free joint: centre x, y, z (m) and the
quaternion w, x, y, z of R_WB, compared up to the quaternion's sign.
"""
import csv
import os

import numpy as np

import fourbar_geometry

HERE = os.path.dirname(os.path.abspath(__file__))
BENCH = os.path.dirname(HERE)
ROOT = os.path.dirname(BENCH)
TESTS_DATA = os.path.join(ROOT, "tests", "data")
BENCH_DATA = os.path.join(BENCH, "data")


class Problem:
    def __init__(self, kind, n, T):
        self.kind = kind          # "pendulum", "chain", "fourbar" or "disk"
        self.n = {"pendulum": 2, "fourbar": 3, "disk": 7}.get(kind, n)
        self.T = T
        self.m = 1.0
        self.g = 9.81
        if kind == "fourbar":
            self.name = "fourbar_T%g" % T
            self.mech = os.path.join(ROOT, "examples", "fourbar.mech")
            self.sets = []
            self.q_names = ["crank_pivot.q", "crank_coupler.q", "rocker_pivot.q"]
            return
        if kind == "disk":
            # The example's steady turn disturbed by a lean rate (bench/README.md).
            self.name = "rolling_disk_T%g" % T
            self.mech = os.path.join(BENCH, "models", "rolling_disk_wobble.mech")
            self.sets = []
            self.q_names = ["free.q[%d]" % i for i in range(1, 8)]
            return
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
        self.q_names = (["shoulder.q", "elbow.q"] if kind == "pendulum"
                        else ["j[%d].q" % i for i in range(1, self.n + 1)])

    @property
    def title(self):
        if self.kind == "fourbar":
            return "four-bar (closed loop), T = %g s" % self.T
        if self.kind == "disk":
            return "rolling disk (wobbling), T = %g s" % self.T
        if self.kind == "pendulum":
            return "double pendulum, T = %g s" % self.T
        return "chain N = %d, T = %g s" % (self.n, self.T)

    def ref_path(self):
        if self.kind in ("fourbar", "disk"):
            return os.path.join(BENCH_DATA, "%s_ref.csv" % ("fourbar" if self.kind == "fourbar" else "rolling_disk"))
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
        cols = [head.index(nm) for nm in self.q_names]
        for r in rows[1:]:
            if abs(float(r[0]) - self.T) < 1e-9:
                return np.array([float(r[c]) for c in cols])
        raise KeyError("no row at t = %g in %s" % (self.T, self.ref_path()))

    def error(self, q):
        q, ref = np.asarray(q, dtype=float), self.q_ref()
        if self.kind == "disk":  # q and -q are the same rotation
            flip = np.concatenate([q[:3], -q[3:]])
            return float(min(np.max(np.abs(q - ref)), np.max(np.abs(flip - ref))))
        return float(np.max(np.abs(q - ref)))

    # Trust limit of the reference at T (bench/reference/README.md, the .md reports):
    # errors below this are not measurable against a double-precision reference.
    def trust_floor(self):
        if self.kind in ("fourbar", "disk"):
            # references converged to all 17 digits (bench/data/*_ref.md); the floor is
            # double round-off of q of size ~10 (four-bar crank angle) or ~1 (disk)
            return 1e-13 if self.kind == "disk" else 1e-12
        if self.kind == "pendulum":
            return 3e-12 if self.T <= 2 else 1e-4
        return 1e-11 if self.T <= 1 else (1e-7 if self.n <= 10 else 3e-8)


DISK_LEAN_RATE = "0.5"  # rad/s; rolling_disk_wobble.mech and reference/rolling_disk.py agree


def all_problems(quick=False, which=None):
    """which: None (all) or a list of name prefixes ("fourbar", "rolling_disk", "chain5_", ...)."""
    if quick:
        ps = [Problem("pendulum", 2, 2.0), Problem("chain", 5, 1.0), Problem("chain", 20, 1.0),
              Problem("fourbar", 3, 2.0), Problem("disk", 7, 2.0)]
    else:
        ps = [Problem("pendulum", 2, 2.0), Problem("pendulum", 2, 10.0)]
        for n in (5, 10, 20, 50, 100):
            for T in (1.0, 5.0):
                ps.append(Problem("chain", n, T))
        ps += [Problem("fourbar", 3, 2.0), Problem("fourbar", 3, 10.0),
               Problem("disk", 7, 2.0), Problem("disk", 7, 10.0)]
    if which:
        ps = [p for p in ps if any(p.name.startswith(w) for w in which)]
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


# --------------------------------------------------------------------------- closed loop, rolling
def ref_row0(p):
    """q and u of the reference at t = 0 (the consistent start every tool is given)."""
    with open(p.ref_path()) as fh:
        rows = list(csv.reader(fh))
    head, r0 = rows[0], [float(x) for x in rows[1]]
    return {h: v for h, v in zip(head, r0)}


def fourbar_start(p):
    r = ref_row0(p)
    q = [r["crank_pivot.q"], r["crank_coupler.q"], r["rocker_pivot.q"]]
    u = [r["crank_pivot.u"], r["crank_coupler.u"], r["rocker_pivot.u"]]
    return q, u


FOURBAR = fourbar_geometry.FOURBAR  # lengths and masses: defined once, fourbar_geometry.py
DISK = dict(a=0.3, m=1.5, theta=0.2, rc=1.0)


def disk_start():
    """free.q and free.u of bench/models/rolling_disk_wobble.mech at t = 0 (its start formulas)."""
    a, m, th, rc, g = DISK["a"], DISK["m"], DISK["theta"], DISK["rc"], 9.81
    Om = np.sqrt(g * np.sin(th) / (np.cos(th) * (a * np.sin(th) / 4 + 1.5 * rc)))
    V = Om * rc
    s = -V / a - Om * np.sin(th)
    q = [0.0, a * np.cos(th), -a * np.sin(th), np.cos(th / 2), -np.sin(th / 2), 0.0, 0.0]
    lr = float(DISK_LEAN_RATE)
    u = [V, a * lr * np.sin(th), a * lr * np.cos(th), lr, Om * np.cos(th), Om * np.sin(th) + s]
    return q, u


def quat_to_mat(q):
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def mat_to_quat(R):
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method)."""
    tr = np.trace(R)
    if tr > 0:
        s = 2 * np.sqrt(1 + tr)
        return np.array([s / 4, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s])
    i = int(np.argmax(np.diag(R)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2 * np.sqrt(1 + R[i, i] - R[j, j] - R[k, k])
    q = np.zeros(4)
    q[0] = (R[k, j] - R[j, k]) / s
    q[1 + i] = s / 4
    q[1 + j] = (R[j, i] + R[i, j]) / s
    q[1 + k] = (R[k, i] + R[i, k]) / s
    return q


def mjcf_fourbar(p, solref=None, solimp=None):
    """The four-bar in MuJoCo: crank and coupler a hinge chain from the world, the rocker a
    hinge on the world at (d, 0, 0), the loop closed by an equality `connect` at the coupler
    tip. Bodies are placed at the assembled start and `ref` makes qpos the joint angles.
    MuJoCo's equality constraints are soft: solref/solimp (None: MuJoCo's defaults) set how
    soft; MJ_STIFF_LOOP is the stiffest setting that stayed stable in our tests."""
    fb = FOURBAR
    (q1, q2, q3), _ = fourbar_start(p)
    I = [m * L ** 2 / 12 for m, L in zip(fb["m"], (fb["a"], fb["b"], fb["c"]))]
    inert = lambda k, L: '<inertial pos="%r 0 0" mass="%r" diaginertia="%r %r %r"/>' % (  # noqa: E731
        L / 2, fb["m"][k], I[k] * 1e-12, I[k], I[k])
    sr = (' solref="%s"' % solref if solref else "") + (' solimp="%s"' % solimp if solimp else "")
    return "\n".join([
        '<mujoco model="fourbar">', '  <compiler angle="radian"/>',
        '  <option gravity="0 -9.81 0" timestep="0.001"><flag contact="disable"/></option>',
        '  <worldbody>',
        '    <body name="crank" euler="0 0 %r">' % q1,
        '      <joint name="crank_pivot" type="hinge" axis="0 0 1" ref="%r"/>' % q1,
        '      ' + inert(0, fb["a"]),
        '      <body name="coupler" pos="%r 0 0" euler="0 0 %r">' % (fb["a"], q2),
        '        <joint name="crank_coupler" type="hinge" axis="0 0 1" ref="%r"/>' % q2,
        '        ' + inert(1, fb["b"]),
        '      </body>', '    </body>',
        '    <body name="rocker" pos="%r 0 0" euler="0 0 %r">' % (fb["d"], q3),
        '      <joint name="rocker_pivot" type="hinge" axis="0 0 1" ref="%r"/>' % q3,
        '      ' + inert(2, fb["c"]),
        '    </body>', '  </worldbody>',
        '  <equality><connect body1="coupler" body2="rocker" anchor="%r 0 0"%s/></equality>' % (fb["b"], sr),
        '</mujoco>'])


MJ_STIFF_LOOP = dict(solref="0.002 1", solimp="0.9999 0.9999 0.001")


def mjcf_disk(p, solref=None):
    """The disk in MuJoCo: a free body with a thin cylinder (radius a, half-width 1 mm)
    touching a plane whose normal is +y, by *frictional soft contact* (elliptic cone,
    impratio 100, friction 1, condim 3: no torsional or rolling friction, as the ideal
    rolling constraint allows pivoting). No-slip rolling is approximated, not imposed."""
    a, m = DISK["a"], DISK["m"]
    A, B = m * a * a / 2, m * a * a / 4
    sr = ' solref="%s"' % solref if solref else ""
    return "\n".join([
        '<mujoco model="rolling_disk">',
        '  <option gravity="0 -9.81 0" timestep="0.001" cone="elliptic" impratio="100"/>',
        '  <worldbody>',
        '    <geom name="ground" type="plane" size="0 0 1" zaxis="0 1 0" friction="1 0 0" condim="3"%s/>' % sr,
        '    <body name="disk">', '      <freejoint name="free"/>',
        '      <inertial pos="0 0 0" mass="%r" diaginertia="%r %r %r"/>' % (m, B, B, A),
        '      <geom type="cylinder" size="%r 0.001" friction="1 0 0" condim="3"%s/>' % (a, sr),
        '    </body>', '  </worldbody>', '</mujoco>'])
