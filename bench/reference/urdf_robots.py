#!/usr/bin/env python3
"""Independent reference for `kanesim import` (issue 40): Pinocchio's reading of the same URDF
files, with its articulated-body algorithm and frame kinematics, at random states.

For each robot: Pinocchio builds the model from the URDF (a free-flyer root for the legged
robots; mimic joints left independent, as kanesim imports them), then at STATES random
states (fixed seed) computes
  ddq = aba(q, v, tau_dyn)  with tau_dyn = -damping * v - friction * tanh(v / 1e-3)
        (the URDF's <dynamics>, as kanesim imports it; zero applied torque otherwise),
  every body frame's world pose (framesForwardKinematics).
Gravity is Pinocchio's default, 9.81 m/s^2 along -z, as kanesim's importer writes it.

Everything is written in kanesim's coordinates (docs/stdlib.md, "Conventions"):
  revolute/prismatic  q, u = dq/dt                  (a continuous joint's (cos, sin) -> angle)
  free (root_joint or a floating joint)  q = {x, y, z, qw, qx, qy, qz} (R_ab),
      u = {velocity of b's origin resolved in a, angular velocity resolved in b}
      (Pinocchio's v = (v_local, w_local):  u_lin = R v_local, du_lin/dt = R (a_local + w x v_local))
  planar  q = {x, y, phi}, u = rates (Pinocchio's v is in the moving frame: the same change)

Trajectories (the fixed-base arms UR5 and Panda): from one more random state, q' = v,
v' = aba(q, v, tau_dyn) integrated by SciPy's DOP853 at rtol = atol = 1e-13 over 1 s, written
at t = 0, 0.1, ..., 1 (tests/import/data/<robot>_traj.csv: time, JOINT.q..., JOINT.u...); a
second run at 1e-12 bounds its error (printed).

Output: tests/import/data/<robot>_ref.txt, lines
  robot NAME / urdf FILE / floating 0|1 / states N
  state K
  q JOINT v...  u JOINT v...  a JOINT v...      (per joint, kanesim's convention)
  pose FRAME px py pz R11 R12 R13 R21 ... R33    (per URDF link; R_WF row by row)
  end
numbers with 17 significant digits.

Run:  bench/.venv/bin/python bench/reference/urdf_robots.py     (a few seconds)
      (example-robot-data 6.0.0 in bench/.venv: sh bench/setup_venv.sh)
"""
import os
import sys

import numpy as np
import pinocchio as pin

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
DATA = os.path.join(ROOT, "tests", "import", "data")
STATES = 4
SEED = 40


def erd_dir():
    """example-robot-data's robots folder in bench/.venv (the PyPI package ships the URDFs)."""
    import glob
    found = glob.glob(os.path.join(ROOT, "bench", ".venv", "lib", "python3*", "site-packages", "cmeel.prefix",
                                   "share", "example-robot-data", "robots"))
    return found[0] if found else None


# (name, URDF path, free-flyer root). The copies in tests/import/data are the package's files
# unchanged (their licences allow it: docs/import.md); Talos's file is CC BY-NC-ND and is not
# copied, so its test runs only where example-robot-data is installed.
def robots():
    erd = erd_dir()
    return [
        ("ur5", os.path.join(DATA, "ur5_robot.urdf"), False),
        ("panda", os.path.join(DATA, "panda.urdf"), False),
        ("solo12", os.path.join(DATA, "solo12.urdf"), True),
        ("talos", os.path.join(erd, "talos_data", "robots", "talos_reduced.urdf") if erd else None, True),
        ("every_joint", os.path.join(DATA, "every_joint.urdf"), False),
    ]


def quat_wxyz(R):
    q = pin.Quaternion(R)
    q.normalize()
    return [q.w, q.x, q.y, q.z]


def random_state(model, rng):
    """q, v in Pinocchio's convention, and the same state in kanesim's (per joint name)."""
    q = np.zeros(model.nq)
    v = rng.uniform(-2.0, 2.0, model.nv)
    kq, ku = {}, {}
    for j in range(1, model.njoints):
        jm, name = model.joints[j], model.names[j]
        iq, iv, sn = jm.idx_q, jm.idx_v, jm.shortname()
        vj = v[iv:iv + jm.nv]
        if sn == "JointModelFreeFlyer":
            p = rng.uniform(-1.0, 1.0, 3)
            quat = rng.normal(size=4)
            quat /= np.linalg.norm(quat)  # (x, y, z, w)
            q[iq:iq + 7] = np.concatenate([p, quat])
            R = pin.Quaternion(quat[3], quat[0], quat[1], quat[2]).toRotationMatrix()
            kq[name] = list(p) + [quat[3], quat[0], quat[1], quat[2]]
            ku[name] = list(R @ vj[:3]) + list(vj[3:])
        elif sn == "JointModelPlanar":
            x, y, th = rng.uniform(-1.0, 1.0, 3)
            q[iq:iq + 4] = [x, y, np.cos(th), np.sin(th)]
            c, s = np.cos(th), np.sin(th)
            kq[name] = [x, y, th]
            ku[name] = [c * vj[0] - s * vj[1], s * vj[0] + c * vj[1], vj[2]]
        elif jm.nq == 2 and jm.nv == 1:  # continuous: (cos, sin)
            th = rng.uniform(-np.pi, np.pi)
            q[iq:iq + 2] = [np.cos(th), np.sin(th)]
            kq[name], ku[name] = [th], [vj[0]]
        elif jm.nq == 1 and jm.nv == 1:
            lo, hi = model.lowerPositionLimit[iq], model.upperPositionLimit[iq]
            lo, hi = (lo, hi) if np.isfinite(lo) and np.isfinite(hi) and hi > lo else (-np.pi, np.pi)
            q[iq] = rng.uniform(lo, hi)
            kq[name], ku[name] = [q[iq]], [vj[0]]
        else:
            sys.exit(f"joint {name}: {sn} is not converted")
    return q, v, kq, ku


def accelerations(model, q, v, a):
    """Pinocchio's ddq per joint in kanesim's convention."""
    ka = {}
    for j in range(1, model.njoints):
        jm, name = model.joints[j], model.names[j]
        iq, iv, sn = jm.idx_q, jm.idx_v, jm.shortname()
        vj, aj = v[iv:iv + jm.nv], a[iv:iv + jm.nv]
        if sn == "JointModelFreeFlyer":
            x, y, z, w = q[iq + 3:iq + 7]
            R = pin.Quaternion(w, x, y, z).toRotationMatrix()
            ka[name] = list(R @ (aj[:3] + np.cross(vj[3:], vj[:3]))) + list(aj[3:])
        elif sn == "JointModelPlanar":
            c, s = q[iq + 2], q[iq + 3]
            ax, ay = aj[0] - vj[2] * vj[1], aj[1] + vj[2] * vj[0]
            ka[name] = [c * ax - s * ay, s * ax + c * ay, aj[2]]
        else:
            ka[name] = [aj[0]]
    return ka


def write_robot(name, path, floating, rng):
    root = pin.JointModelFreeFlyer() if floating else None
    model = pin.buildModelFromUrdf(path, root) if floating else pin.buildModelFromUrdf(path)
    data = model.createData()
    links = [f.name for f in model.frames if f.type == pin.FrameType.BODY]
    out = [f"robot {name}", f"urdf {os.path.basename(path)}", f"floating {int(floating)}", f"states {STATES}"]
    fmt = lambda xs: " ".join("%.17g" % x for x in xs)
    worst = 0.0
    for k in range(STATES):
        q, v, kq, ku = random_state(model, rng)
        tau = -model.damping * v - model.friction * np.tanh(v / 1e-3)
        a = pin.aba(model, data, q, v, tau)
        # The same accelerations from the mass matrix (CRBA) and the bias (RNEA at a = 0).
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        a2 = np.linalg.solve(M, tau - pin.rnea(model, data, q, v, np.zeros(model.nv)))
        worst = max(worst, np.max(np.abs(a - a2)) / max(1.0, np.max(np.abs(a))))
        ka = accelerations(model, q, v, a)
        pin.framesForwardKinematics(model, data, q)
        out.append(f"state {k}")
        for j in range(1, model.njoints):
            jn = model.names[j]
            out += [f"q {jn} {fmt(kq[jn])}", f"u {jn} {fmt(ku[jn])}", f"a {jn} {fmt(ka[jn])}"]
        for ln in links:
            M_ = data.oMf[model.getFrameId(ln, pin.FrameType.BODY)]
            out.append(f"pose {ln} {fmt(M_.translation)} {fmt(M_.rotation.reshape(-1))}")
        out.append("end")
    target = os.path.join(DATA, f"{name}_ref.txt")
    with open(target, "w") as f:
        f.write("\n".join(out) + "\n")
    print(f"{name}: nq {model.nq}, nv {model.nv}, {len(links)} links; aba vs crba+rnea {worst:.1e}; -> {target}")


def write_trajectory(name, path, rng):
    from scipy.integrate import solve_ivp
    model = pin.buildModelFromUrdf(path)
    data = model.createData()
    assert model.nq == model.nv, "trajectories only for joints whose q is their angle"
    q0, v0, _, _ = random_state(model, rng)
    n = model.nv

    def f(_t, y):
        q, v = y[:n], y[n:]
        tau = -model.damping * v - model.friction * np.tanh(v / 1e-3)
        return np.concatenate([v, pin.aba(model, data, q, v, tau)])

    times = np.linspace(0.0, 1.0, 11)
    runs = [solve_ivp(f, (0.0, 1.0), np.concatenate([q0, v0]), method="DOP853", t_eval=times, rtol=tol, atol=tol).y.T
            for tol in (1e-13, 1e-12)]
    err = np.max(np.abs(runs[0] - runs[1]))
    names = [model.names[j] for j in range(1, model.njoints)]
    header = ",".join(["time"] + [f"{j}.q" for j in names] + [f"{j}.u" for j in names])
    target = os.path.join(DATA, f"{name}_traj.csv")
    with open(target, "w") as fh:
        fh.write(header + "\n")
        for t, row in zip(times, runs[0]):
            fh.write(",".join("%.17g" % x for x in [t, *row]) + "\n")
    print(f"{name}: 1 s trajectory, |1e-13 run - 1e-12 run| {err:.1e}; -> {target}")


def main():
    for i, (name, path, floating) in enumerate(robots()):
        rng = np.random.default_rng([SEED, i])  # each robot its own stream: a skipped one changes no other
        if path is None or not os.path.exists(path):
            print(f"{name}: {path} not found, skipped")
            continue
        write_robot(name, path, floating, rng)
        if name in ("ur5", "panda"):
            write_trajectory(name, path, rng)
    print("pinocchio", pin.__version__)


if __name__ == "__main__":
    main()
