#!/usr/bin/env python3
"""Imported URDF robots against Pinocchio, live (issue 40, "Tests"): the `kanesim` command
against Pinocchio 4.1.0 reading the same file, in the bench venv (pin is not a test dependency;
tests/import/import_dynamics_test.cpp checks 4 frozen states per robot in CI).

For each robot (UR5, Panda, Solo12 and Talos with free-flyer bases, example-robot-data 6.0.0):
  - accelerations at STATES random states: `kanesim run ROBOT.urdf --set J.q.start=...` (every
    joint's start q and u; the row at t = 0 holds `J.a` from the solved equations) against
    `pin.aba`, the largest difference relative to max(1, max |a|);
  - every URDF link's world pose at those states (`LINK.frame_a.r[k]`, `.R[i,j]`) against
    `pin.framesForwardKinematics`;
  - one second of motion from one more random state: `kanesim run` at rtol = atol = 1e-12
    (rows every 0.1 s) against SciPy's DOP853 on `pin.aba` at 1e-13 (its distance to a 1e-12
    run is printed: what the reference itself is worth); Talos with its <dynamics friction>
    set to 0 (see without_friction; damping kept), every other file as it is.
States, coordinate conventions and the <dynamics> force law are those of
bench/reference/urdf_robots.py (imported from there). Panda's <mimic> is taken out of the file
both tools read, as Pinocchio ignores it (mimic joints: tests/import/mimic_test.cpp), and kanesim
runs with `--limits ignore` (Pinocchio's dynamics have no end stops).

    sh bench/setup_venv.sh
    bench/.venv/bin/python bench/urdf_check.py [--states 20] [--kanesim build/cli/kanesim] [--robots ur5,talos]

Exit 1 when a check exceeds its bound (accelerations 1e-12 relative, poses 1e-12, trajectories
1e-9 plus 10x the reference's own 1e-12/1e-13 spread).
"""
import argparse
import csv
import io
import os
import re
import subprocess
import sys
import tempfile

import numpy as np
import pinocchio as pin
from scipy.integrate import solve_ivp

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
sys.path.insert(0, os.path.join(HERE, "reference"))
import urdf_robots as ur  # noqa: E402  (random_state, accelerations: kanesim's conventions)

ACCEL_TOL, POSE_TOL = 1e-12, 1e-12


def robot_files():
    erd = ur.erd_dir()
    data = os.path.join(ROOT, "tests", "import", "data")
    talos = os.path.join(erd, "talos_data", "robots", "talos_reduced.urdf") if erd else None
    return [("ur5", os.path.join(data, "ur5_robot.urdf"), False), ("panda", os.path.join(data, "panda.urdf"), False),
            ("solo12", os.path.join(data, "solo12.urdf"), True), ("talos", talos, True)]


def robot_options(description, **defaults):
    """The command line of this script and bench/urdf_race.py: --kanesim, --robots and, per
    script, options with their defaults and types (states=20, reps=21, integrator="auto")."""
    ap = argparse.ArgumentParser(description=description.split("\n\n")[0])
    for name, value in defaults.items():
        ap.add_argument("--" + name, type=type(value), default=value)
    ap.add_argument("--kanesim", default=os.path.join(ROOT, "build", "cli", "kanesim"))
    ap.add_argument("--robots", default="ur5,panda,solo12,talos")
    return ap.parse_args()


def installed_robots(wanted, missing):
    """(index, name, path, floating) of robot_files() named in `wanted` (comma-separated), the index
    counting every robot (the seeds use it); `missing` formats the line printed for one not installed."""
    for i, (name, path, floating) in enumerate(robot_files()):
        if name not in wanted.split(","):
            continue
        if path is None or not os.path.exists(path):
            print(missing.format(name=name))
            continue
        yield i, name, path, floating


def pin_model(urdf, floating):
    return pin.buildModelFromUrdf(urdf, pin.JointModelFreeFlyer()) if floating else pin.buildModelFromUrdf(urdf)


def edited_copy(path, tmp, prefix, pattern, replacement):
    """path itself when re.sub(pattern, replacement) leaves its text as it is, else the edited
    copy tmp/<prefix><name>."""
    text = open(path).read()
    edited = re.sub(pattern, replacement, text)
    if edited == text:
        return path
    out = os.path.join(tmp, prefix + os.path.basename(path))
    with open(out, "w") as f:
        f.write(edited)
    return out


def without_mimic(path, tmp):
    """The URDF as both tools read it here: <mimic .../> removed (Pinocchio's default reading)."""
    return edited_copy(path, tmp, "", r"<mimic\b[^>]*/>", "")


def without_friction(path, tmp):
    """A copy with <dynamics friction> zero (damping kept), for the 1 s trajectories: URDF's
    constant friction is imported as tanh(u / 1e-3), which makes Talos (friction 1 N m on every
    joint) too stiff for an explicit reference at 1e-13 (kanesim's DOP853 gives up after 100 000
    steps at 0.7 s at rtol 1e-6)."""
    return edited_copy(path, tmp, "nofriction_", r'(<dynamics\b[^>]*\bfriction=")[^"]*(")', r"\g<1>0\g<2>")


def link_signals(kanesim, urdf, floating, tmp):
    """URDF link name -> kanesim frame signal prefix, from the model `kanesim import` writes."""
    mech = os.path.join(tmp, "robot.mech")
    subprocess.run([kanesim, "import", urdf, "-o", mech, "--limits", "ignore"] + (["--floating"] if floating else []), check=True,
                   stderr=subprocess.DEVNULL)
    text = open(mech).read()
    links = {m.group(1): None for m in re.finditer(r"// link '([^']+)' \(.*\): the world frame", text)}
    for m in re.finditer(r"\n\s+(Body|BodyShape|Frame) (\w+)\b[^\"]*?\"link '([^']+)'", text):
        links[m.group(3)] = m.group(2) if m.group(1) == "Frame" else m.group(2) + ".frame_a"
    return links


def fmt_value(v):
    return "%.17g" % v[0] if len(v) == 1 else "{" + ",".join("%.17g" % x for x in v) + "}"


def start_args(kq, ku):
    """`--set J.q.start=... --set J.u.start=...` for every joint of the state (kq, ku)."""
    args = []
    for name in kq:
        args += ["--set", f"{name}.q.start={fmt_value(kq[name])}", "--set", f"{name}.u.start={fmt_value(ku[name])}"]
    return args


def read_columns(csv_text):
    """The rows of `kanesim run`'s CSV as {column: np.array}."""
    rows = list(csv.reader(io.StringIO(csv_text)))
    head, body = rows[0], np.array([[float(x) for x in r] for r in rows[1:]])
    return {h: body[:, i] for i, h in enumerate(head)}


def run_kanesim(kanesim, urdf, floating, kq, ku, stop, interval, tol, outputs):
    """Rows of `kanesim run` from the state (kq, ku), as {column: np.array}."""
    cmd = [kanesim, "run", urdf, "--stop-time", repr(stop), "--interval", repr(interval), "--rtol", repr(tol),
           "--atol", repr(tol), "--energy-check", "off", "--limits", "ignore"] + (["--floating"] if floating else [])
    cmd += start_args(kq, ku)
    for o in outputs:
        cmd += ["--output", o]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"kanesim failed ({p.returncode}):\n{p.stderr[-3000:]}")
    return read_columns(p.stdout)


def joint_columns(name, n, kind):
    return [f"{name}.{kind}"] if n == 1 else [f"{name}.{kind}[{k + 1}]" for k in range(n)]


def check_states(kanesim, name, urdf, floating, model, rng, states, tmp):
    data = model.createData()
    links = link_signals(kanesim, urdf, floating, tmp)
    frames = {f.name: i for i, f in enumerate(model.frames) if f.type == pin.FrameType.BODY}
    common = sorted(set(links) & set(frames))
    worst_a, worst_p = 0.0, 0.0
    moving = [ln for ln in common if links[ln]]  # the others are the world frame itself
    outs = ["*.a", "*.a[*]"] + [f"{links[ln]}.r[*]" for ln in moving] + [f"{links[ln]}.R[*]" for ln in moving]
    for _ in range(states):
        q, v, kq, ku = ur.random_state(model, rng)
        tau = -model.damping * v - model.friction * np.tanh(v / 1e-3)
        ka = ur.accelerations(model, q, v, pin.aba(model, data, q, v, tau))
        row = run_kanesim(kanesim, urdf, floating, kq, ku, 1e-6, 1e-6, 1e-10, outs)
        scale = max([1.0] + [abs(x) for a in ka.values() for x in a])
        for jn, a in ka.items():
            got = [row[c][0] for c in joint_columns(jn, len(a), "a")]
            worst_a = max(worst_a, max(abs(g - w) for g, w in zip(got, a)) / scale)
        pin.framesForwardKinematics(model, data, q)
        for ln in common:
            M = data.oMf[frames[ln]]
            if links[ln]:
                got = [row[f"{links[ln]}.r[{k}]"][0] for k in (1, 2, 3)]
                got += [row[f"{links[ln]}.R[{i},{j}]"][0] for i in (1, 2, 3) for j in (1, 2, 3)]
            else:
                got = [0.0] * 3 + list(np.eye(3).reshape(-1))
            want = list(M.translation) + list(M.rotation.reshape(-1))
            worst_p = max(worst_p, max(abs(g - w) for g, w in zip(got, want)))
    missing = sorted(set(frames) - set(links))
    return worst_a, worst_p, len(common), missing


def to_kanesim(model, y):
    """Pinocchio's state (q, v) -> kanesim's q and u per joint (urdf_robots.random_state's mapping)."""
    q, v = y[:model.nq], y[model.nq:]
    kq, ku = {}, {}
    for j in range(1, model.njoints):
        jm, name = model.joints[j], model.names[j]
        iq, iv = jm.idx_q, jm.idx_v
        if jm.shortname() == "JointModelFreeFlyer":
            x, y_, z, w = q[iq + 3:iq + 7]
            R = pin.Quaternion(w, x, y_, z).toRotationMatrix()
            kq[name] = list(q[iq:iq + 3]) + [w, x, y_, z]
            ku[name] = list(R @ v[iv:iv + 3]) + list(v[iv + 3:iv + 6])
        elif jm.nq == 1 and jm.nv == 1:
            kq[name], ku[name] = [q[iq]], [v[iv]]
        else:
            sys.exit(f"{name}: {jm.shortname()} not handled in trajectories")
    return kq, ku


def reference_motion(model, q0, v0, times, tol):
    """SciPy DOP853 on aba; a free-flyer's quaternion (x, y, z, w) moves by q' = q (0, w_local) / 2."""
    data = model.createData()

    free = [(model.joints[j].idx_q, model.joints[j].idx_v) for j in range(1, model.njoints)
            if model.joints[j].shortname() == "JointModelFreeFlyer"]
    one_q = np.array([model.joints[j].idx_q for j in range(1, model.njoints) if model.joints[j].nq == 1], dtype=int)
    one_v = np.array([model.joints[j].idx_v for j in range(1, model.njoints) if model.joints[j].nq == 1], dtype=int)
    assert len(one_q) + 7 * len(free) == model.nq, "trajectories only for 1-coordinate joints and free-flyers"

    def f(_t, y):
        q, v = y[:model.nq].copy(), y[model.nq:]
        dq = np.empty(model.nq)
        dq[one_q] = v[one_v]
        for iq, iv in free:
            quat = q[iq + 3:iq + 7] / np.linalg.norm(q[iq + 3:iq + 7])
            q[iq + 3:iq + 7] = quat
            x, y_, z, w = quat
            R = pin.Quaternion(w, x, y_, z).toRotationMatrix()
            wx, wy, wz = v[iv + 3:iv + 6]
            dq[iq:iq + 3] = R @ v[iv:iv + 3]
            dq[iq + 3:iq + 7] = 0.5 * np.array([w * wx + y_ * wz - z * wy, w * wy + z * wx - x * wz,
                                                w * wz + x * wy - y_ * wx, -x * wx - y_ * wy - z * wz])
        tau = -model.damping * v - model.friction * np.tanh(v / 1e-3)
        return np.concatenate([dq, pin.aba(model, data, q, v, tau)])

    sol = solve_ivp(f, (times[0], times[-1]), np.concatenate([q0, v0]), method="DOP853", t_eval=times, rtol=tol,
                    atol=tol)
    return sol.y.T


def check_trajectory(kanesim, urdf, floating, model, rng):
    q0, v0, kq, ku = ur.random_state(model, rng)
    times = np.linspace(0.0, 1.0, 11)
    ref, ref12 = (reference_motion(model, q0, v0, times, tol) for tol in (1e-13, 1e-12))
    outs = ["*.q", "*.u"] + (["root_joint.q[*]", "root_joint.u[*]"] if floating else [])
    got = run_kanesim(kanesim, urdf, floating, kq, ku, 1.0, 0.1, 1e-12, outs)
    worst_q = worst_u = spread = 0.0
    for r in range(len(times)):
        wq, wu = to_kanesim(model, ref[r])
        sq, su = to_kanesim(model, ref12[r])
        for jn in wq:
            for kind, want, other in (("q", wq[jn], sq[jn]), ("u", wu[jn], su[jn])):
                cols = joint_columns(jn, len(want), kind)
                d = max(abs(got[c][r] - w) for c, w in zip(cols, want))
                spread = max(spread, max(abs(a - b) for a, b in zip(want, other)))
                if kind == "q":
                    worst_q = max(worst_q, d)
                else:
                    worst_u = max(worst_u, d)
    return worst_q, worst_u, spread


def main():
    args = robot_options(__doc__, states=20)
    failed = False
    print("| robot | nq / nv | states | accelerations: max rel. diff | links compared | poses: max diff "
          "| 1 s: max abs(q diff) | max abs(u diff) | reference 1e-13 vs 1e-12 |")
    print("|---|---|---|---|---|---|---|---|---|")
    for i, name, path, floating in installed_robots(args.robots, "| {name} | not installed (sh bench/setup_venv.sh) |"):
        with tempfile.TemporaryDirectory(prefix="kanesim-urdf-check-") as tmp:
            urdf = without_mimic(path, tmp)
            model = pin_model(urdf, floating)
            rng = np.random.default_rng([4040, i])
            wa, wp, nlinks, missing = check_states(args.kanesim, name, urdf, floating, model, rng, args.states, tmp)
            smooth = without_friction(urdf, tmp)
            if smooth != urdf:
                model = pin_model(smooth, floating)
            tq, tu, spread = check_trajectory(args.kanesim, smooth, floating, model, rng)
        bad = wa > ACCEL_TOL or wp > POSE_TOL or max(tq, tu) > 1e-9 + 10 * spread or missing
        failed |= bool(bad)
        print(f"| {name} | {model.nq} / {model.nv} | {args.states} | {wa:.1e} | {nlinks} | {wp:.1e} | {tq:.1e} | {tu:.1e} "
              f"| {spread:.1e} |" + (f" FAILED{' (no kanesim frame: ' + ', '.join(missing) + ')' if missing else ''}"
                                     if bad else ""))
        sys.stdout.flush()
    v = subprocess.run([args.kanesim, "--version"], capture_output=True, text=True).stdout.strip()
    print(f"\npinocchio {pin.__version__}; {v}")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
