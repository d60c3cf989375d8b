"""The four-bar of examples/fourbar.mech in numbers, once for the bench's peers.

Crank-rocker in the x-y plane (bench/README.md, "Constrained problems"): crank a on a z hinge
at the origin, coupler b on a z hinge at the crank tip A, rocker c on a z hinge at O4 = (d, 0);
the loop closes at B, the coupler tip = the rocker tip. Uniform thin rods along their body x,
mass centre at L/2, moment m L^2 / 12 about z. Joint coordinates as kanesim's:
q = (crank_pivot.q, crank_coupler.q, rocker_pivot.q) = (theta1, theta2 - theta1, theta3) with
theta_k the absolute angles, u = dq/dt.

Used by problems.py (MuJoCo's MJCF), exudyn_constrained.py (bodies) and run.py (Pinocchio
model, loop residual). The reference (bench/reference/fourbar.py) keeps its own exact-rational
copy of these numbers on purpose: it judges these peers and shares no code with them.
"""
import numpy as np

FOURBAR = dict(a=0.2, b=0.6, c=0.5, d=0.6, m=(0.5, 1.0, 0.8))
G = 9.81  # m/s^2, along -y

# Pinocchio's constraintDynamics settings for the loop (run.py; bench/README.md says why):
# Baumgarte gains of Pinocchio's own four-bar example (examples/simulation-closed-kinematic-
# chains.py: Kp = 10, Kd = 2 sqrt(Kp), critically damped), proximal mu 1e-10 as that example
# (the point constraint's z row is identically zero in a planar loop: mu > 0 regularises it),
# proximal accuracy 1e-12 and at most 10 iterations (3 are taken).
PIN_LOOP = dict(kp=10.0, kd=2.0 * float(np.sqrt(10.0)), mu=1e-10, accuracy=1e-12, max_iter=10)


def unit(t):
    return np.array([np.cos(t), np.sin(t)])


def perp(t):
    """d unit(t) / dt."""
    return np.array([-np.sin(t), np.cos(t)])


def absolute(q, u):
    """Absolute angles (theta1, theta2, theta3) and their rates from the joint coordinates."""
    return [q[0], q[0] + q[1], q[2]], [u[0], u[0] + u[1], u[2]]


def bodies(q, u):
    """Per rod (crank, coupler, rocker): mass-centre position and velocity (x, y), angle, rate."""
    a, b, c, d = (FOURBAR[k] for k in "abcd")
    th, w = absolute(q, u)
    A, vA = a * unit(th[0]), a * w[0] * perp(th[0])
    com = [a / 2 * unit(th[0]), A + b / 2 * unit(th[1]), np.array([d, 0.0]) + c / 2 * unit(th[2])]
    vel = [a / 2 * w[0] * perp(th[0]), vA + b / 2 * w[1] * perp(th[1]), c / 2 * w[2] * perp(th[2])]
    return [(com[k], vel[k], th[k], w[k]) for k in range(3)]


def loop_gap(q, u):
    """Loop-closure residual: |B_coupler - B_rocker| (m) and |v_B,coupler - v_B,rocker| (m/s),
    zero on the exact motion; what a redundant-coordinate tool drifts by."""
    a, b, c, d = (FOURBAR[k] for k in "abcd")
    th, w = absolute(q, u)
    B1 = a * unit(th[0]) + b * unit(th[1])
    B2 = np.array([d, 0.0]) + c * unit(th[2])
    v1 = a * w[0] * perp(th[0]) + b * w[1] * perp(th[1])
    v2 = c * w[2] * perp(th[2])
    return float(np.linalg.norm(B1 - B2)), float(np.linalg.norm(v1 - v2))


def pin_loop(settings=PIN_LOOP):
    """Pinocchio model of the four-bar (a tree: crank -> coupler, and the rocker on the world)
    and the loop as a RigidConstraintModel CONTACT_3D (LOCAL) between the coupler tip and the
    rocker tip, with Baumgarte gains. Returns (model, constraint models, proximal settings);
    bench/pin/pin_driver.cpp (MakeFourbar) builds the same in C++."""
    import pinocchio as pin
    fb = FOURBAR
    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, -G, 0.0]), np.zeros(3))
    at = lambda x: pin.SE3(np.eye(3), np.array([x, 0.0, 0.0]))  # noqa: E731

    def rod(m, L):
        return pin.Inertia(m, np.array([L / 2, 0.0, 0.0]), np.diag([0.0, m * L * L / 12, m * L * L / 12]))

    crank = model.addJoint(0, pin.JointModelRZ(), at(0.0), "crank_pivot")
    model.appendBodyToJoint(crank, rod(fb["m"][0], fb["a"]), pin.SE3.Identity())
    coupler = model.addJoint(crank, pin.JointModelRZ(), at(fb["a"]), "crank_coupler")
    model.appendBodyToJoint(coupler, rod(fb["m"][1], fb["b"]), pin.SE3.Identity())
    rocker = model.addJoint(0, pin.JointModelRZ(), at(fb["d"]), "rocker_pivot")
    model.appendBodyToJoint(rocker, rod(fb["m"][2], fb["c"]), pin.SE3.Identity())
    loop = pin.RigidConstraintModel(pin.ContactType.CONTACT_3D, model, coupler, at(fb["b"]), rocker, at(fb["c"]),
                                    pin.ReferenceFrame.LOCAL)
    loop.setBaumgarteCorrectorParameters(pin.BaumgarteCorrectorParameters(settings["kp"], settings["kd"]))
    models = pin.StdVec_RigidConstraintModel()
    models.append(loop)
    prox = pin.ProximalSettings(settings["accuracy"], settings["accuracy"], settings["mu"], settings["max_iter"])
    return model, models, prox
