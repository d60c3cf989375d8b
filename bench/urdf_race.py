#!/usr/bin/env python3
"""The race of issue 40: a whole `kanesim run ROBOT.urdf` over 1 s at final error <= 1e-6
against MuJoCo's URDF compile + RK4 simulation to the same error, UR5, Panda, Solo12 and Talos
side by side, medians of fresh processes (docs/benchmarks.md, "URDF robots: the race").

1. The race file of each robot (bench/results/race/ROBOT.urdf), read by both tools: the
   example-robot-data URDF without <visual>/<collision> (MuJoCo would compile the collision
   meshes; kanesim ignores them), <limit> widened to +-1e6 (kanesim's importer does not model
   stops, MuJoCo would), without <mimic> (MuJoCo makes it soft, kanesim exact), <dynamics
   friction> 0 (kanesim: exact stick-slip; MuJoCo: frictionloss, a soft constraint);
   Solo12 and Talos get a `floating` root_joint from a `world` link. <dynamics> damping kept.
2. One random start (bench/reference/urdf_robots.py's random_state, fixed seed), the reference
   q(1 s) from SciPy's DOP853 on Pinocchio's aba at 1e-13 (spread to a 1e-12 run printed).
   Error = max over every coordinate (a free base's position and quaternion too) of abs(q(1) - q_ref).
3. The setting each tool needs: kanesim's loosest rtol = atol (three per decade) from which on
   every tighter one stays <= 1e-6; MuJoCo's fewest RK4 steps (grid of ~1.19x) from which on
   every finer grid point stays <= 1e-6 (the "stays below" reading of bench/wp/readings.py).
4. The race: REPS fresh processes each, alternated: `kanesim run RACE.urdf --set <start>
   --stop-time 1 --interval 1 --rtol R --atol R --stats` and `mujoco_urdf_driver RACE.urdf N
   STATE` (C, against the mujoco wheel's libmujoco: compile, set the state, N mj_step, print
   qpos). Medians of the process wall time and CPU time, and of the phases each reports.

    bench/.venv/bin/python bench/urdf_race.py [--reps 21] [--kanesim build/cli/kanesim] [--robots ur5,talos]
        [--integrator auto|dop853|...]  (kanesim's --integrator; auto: DOP853, handing a stiff run to CVODE-BDF)
        [--baseline OTHER/kanesim]      (a second kanesim, e.g. main's, timed in the same rotation at the
                                         same setting; its rows must equal the first one's)
"""
import glob
import json
import os
import re
import resource
import statistics
import subprocess
import sys
import time
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

HERE = os.path.dirname(os.path.abspath(__file__))
OUT = os.path.join(HERE, "results", "race")
sys.path.insert(0, HERE)
sys.path.insert(0, os.path.join(HERE, "reference"))
import urdf_check as uc  # noqa: E402
import urdf_robots as ur  # noqa: E402

TARGET = 1e-6
RTOLS = [10 ** (-k / 3) for k in range(9, 37)]  # 1e-3 ... 1e-12, three per decade
STEPS = sorted({int(round(20 * 1.19 ** k)) for k in range(0, 60)})  # 20 ... ~600 000 RK4 steps


def race_urdf(name, src, floating):
    """The file both tools read (see the docstring), written to bench/results/race/NAME.urdf."""
    tree = ET.parse(src)
    robot = tree.getroot()
    for el in list(robot):
        if el.tag in ("transmission", "gazebo"):
            robot.remove(el)
        elif el.tag == "link":
            for c in [c for c in el if c.tag in ("visual", "collision")]:
                el.remove(c)
        elif el.tag == "joint":
            for c in [c for c in el if c.tag in ("mimic", "safety_controller", "calibration")]:
                el.remove(c)
            for c in el.findall("dynamics"):  # exact stick-slip in kanesim, a soft constraint in MuJoCo
                if c.get("friction") is not None:
                    c.set("friction", "0")
            for c in el.findall("limit"):  # a range nothing reaches: no stop in either tool
                c.set("lower", "-1e6")
                c.set("upper", "1e6")
    if floating:
        children = {j.find("child").get("link") for j in robot.findall("joint")}
        root = next(l.get("name") for l in robot.findall("link") if l.get("name") not in children)
        ET.SubElement(robot, "link", name="world")
        j = ET.SubElement(robot, "joint", name="root_joint", type="floating")
        ET.SubElement(j, "parent", link="world")
        ET.SubElement(j, "child", link=root)
    os.makedirs(OUT, exist_ok=True)
    with open(os.path.join(OUT, ".gitignore"), "w") as f:
        f.write("*\n")  # generated files, never committed
    path = os.path.join(OUT, name + ".urdf")
    tree.write(path)
    return path


def reference(name, urdf, original, floating, index):
    """Start state and reference q(1), cached in bench/results/race/NAME_ref.json (Talos's takes minutes)."""
    cache = os.path.join(OUT, name + "_ref.json")
    model = pin.buildModelFromUrdf(urdf)
    if os.path.exists(cache):
        c = json.load(open(cache))
        if c["urdf_mtime"] == os.path.getmtime(urdf):
            return model, c
    rng = np.random.default_rng([4041, index])  # drawn within the original file's joint limits
    drawn = uc.pin_model(original, floating)
    assert list(drawn.names) == list(model.names)
    q0, v0, kq, ku = ur.random_state(drawn, rng)
    times = np.array([0.0, 1.0])
    t0 = time.time()
    y13 = uc.reference_motion(model, q0, v0, times, 1e-13)[-1]
    y12 = uc.reference_motion(model, q0, v0, times, 1e-12)[-1]
    q13, _ = uc.to_kanesim(model, y13)
    q12, _ = uc.to_kanesim(model, y12)
    spread = max(abs(a - b) for j in q13 for a, b in zip(q13[j], q12[j]))
    c = {"urdf_mtime": os.path.getmtime(urdf), "kq": kq, "ku": ku, "q_ref": q13, "spread": spread,
         "seconds": time.time() - t0, "nq": model.nq, "nv": model.nv}
    with open(cache, "w") as f:
        json.dump(c, f)
    return model, c


def kanesim_cmd(kanesim, urdf, c, rtol, stats=False, integrator="auto"):
    cmd = [kanesim, "run", urdf, "--stop-time", "1", "--interval", "1", "--rtol", repr(rtol), "--atol", repr(rtol),
           "--integrator", integrator, "--limits", "ignore"]  # the widened limits: no stop machinery (MuJoCo's are never reached either)
    return cmd + uc.start_args(c["kq"], c["ku"]) + (["--stats"] if stats else [])


def error_of(got, c):
    """got: {joint: [q...]} at 1 s."""
    return max(abs(a - b) for j in c["q_ref"] for a, b in zip(got[j], c["q_ref"][j]))


def kanesim_error(kanesim, urdf, c, rtol, integrator):
    p = subprocess.run(kanesim_cmd(kanesim, urdf, c, rtol, integrator=integrator), capture_output=True, text=True)
    if p.returncode != 0:
        return float("inf")
    cols = uc.read_columns(p.stdout)
    got = {j: [cols[col][-1] for col in uc.joint_columns(j, len(c["q_ref"][j]), "q")] for j in c["q_ref"]}
    return error_of(got, c)


def mujoco_layout(urdf):
    import mujoco
    m = mujoco.MjModel.from_xml_path(urdf)
    return m, {m.joint(i).name: (int(m.jnt_qposadr[i]), int(m.jnt_dofadr[i])) for i in range(m.njnt)}


def mujoco_state(m, layout, c, path):
    """qpos, qvel in MuJoCo's order from kanesim's per-joint start (a free joint: the same convention)."""
    qpos, qvel = np.zeros(m.nq), np.zeros(m.nv)
    for j in c["kq"]:
        a, b = layout[j]
        qpos[a:a + len(c["kq"][j])] = c["kq"][j]
        qvel[b:b + len(c["ku"][j])] = c["ku"][j]
    with open(path, "w") as f:
        f.write(" ".join("%.17g" % x for x in qpos) + "\n" + " ".join("%.17g" % x for x in qvel) + "\n")
    return qpos, qvel


def mujoco_error(m, layout, c, qpos0, qvel0, n):
    import mujoco
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = qpos0, qvel0
    m.opt.integrator = mujoco.mjtIntegrator.mjINT_RK4
    m.opt.timestep = 1.0 / n
    mujoco.mj_step(m, d, n)
    got = {j: list(d.qpos[layout[j][0]:layout[j][0] + len(c["q_ref"][j])]) for j in c["q_ref"]}
    return error_of(got, c)


def stays_below(points):
    """points: [(cost_order, error)] loose -> tight; the loosest from which on all are <= TARGET."""
    pick = None
    for setting, err in reversed(points):
        if err > TARGET:
            break
        pick = (setting, err)
    return pick


def build_driver():
    mj = glob.glob(os.path.join(HERE, ".venv", "lib", "python3*", "site-packages", "mujoco"))[0]
    os.makedirs(OUT, exist_ok=True)  # a fresh clone has no results/race yet
    exe = os.path.join(OUT, "mujoco_urdf_driver")
    lib = glob.glob(os.path.join(mj, "libmujoco.so.*"))[0]
    subprocess.run(["cc", "-O2", "-o", exe, os.path.join(HERE, "mujoco_urdf_driver.c"), "-I", os.path.join(mj, "include"),
                    lib, f"-Wl,-rpath,{mj}"], check=True)
    return exe


def timed(cmd):
    """(wall s, CPU s of the child, stdout, stderr)."""
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    if p.returncode != 0:
        sys.exit(f"{cmd[0]} failed: {p.stderr[-2000:]}")
    return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime), p.stdout, p.stderr


def kanesim_phases(stderr):
    out = {}
    for line in stderr.splitlines():
        m = re.match(r"\s+(load \+ elaborate|compile|integrate|output)\s+([0-9.eE+-]+)\s*$", line)
        if m:
            out[m.group(1)] = float(m.group(2))
        m = re.match(r"\s+(right-hand sides|steps)\s+([0-9]+)", line)
        if m:
            out[m.group(1)] = int(m.group(2))
    return out


def main():
    args = uc.robot_options(__doc__, reps=21, integrator="auto", baseline="")
    driver = build_driver()
    rows = []
    for i, name, path, floating in uc.installed_robots(args.robots, "{name}: not installed (sh bench/setup_venv.sh)"):
        urdf = race_urdf(name, path, floating)
        os.makedirs(os.path.join(OUT, "original"), exist_ok=True)
        model, c = reference(name, urdf, uc.without_mimic(path, os.path.join(OUT, "original")), floating, i)
        ks = []
        for r in RTOLS:
            ks.append((r, kanesim_error(args.kanesim, urdf, c, r, args.integrator)))
            if ks[-1][1] < TARGET / 100:
                break
        m, layout = mujoco_layout(urdf)
        state = os.path.join(OUT, name + "_state.txt")
        qpos0, qvel0 = mujoco_state(m, layout, c, state)
        ms = []
        for n in STEPS:
            ms.append((n, mujoco_error(m, layout, c, qpos0, qvel0, n)))
            if ms[-1][1] < TARGET / 100:
                break
        kpick, mpick = stays_below(ks), stays_below(ms)
        print(f"{name}: nq {c['nq']}, nv {c['nv']}; reference spread 1e-13 vs 1e-12 {c['spread']:.1e}; kanesim "
              f"{kpick}; MuJoCo RK4 {mpick}", flush=True)
        if not kpick or not mpick:
            continue
        kc = kanesim_cmd(args.kanesim, urdf, c, kpick[0], stats=True, integrator=args.integrator)
        mc = [driver, urdf, str(mpick[0]), state]
        bc = [args.baseline] + kc[1:] if args.baseline else None
        timed(mc)  # warm the file cache once, untimed
        if bc and timed(bc)[2] != timed(kc)[2]:
            sys.exit(f"{name}: the baseline's rows differ from {args.kanesim}'s")
        kt, mt, bt = [], [], []
        order = (0, 1, 2) if bc else (0, 1)
        for rep in range(args.reps):  # rotated: each one first, second, ... in turn
            k = rep % len(order)
            for which in order[k:] + order[:k]:
                if which == 0:
                    w, cpu, _, err = timed(kc)
                    kt.append((w, cpu, kanesim_phases(err)))
                elif which == 2:
                    w, cpu, _, err = timed(bc)
                    bt.append((w, cpu))
                else:
                    w, cpu, _, err = timed(mc)
                    ph = dict(zip(err.split()[0::2], map(float, err.split()[1::2])))
                    mt.append((w, cpu, ph))
        med = lambda xs: statistics.median(xs)
        row = {"robot": name, "nq": c["nq"], "nv": c["nv"], "rtol": kpick[0], "k_err": kpick[1], "steps": mpick[0],
               "m_err": mpick[1], "k_wall": med([t[0] for t in kt]), "k_cpu": med([t[1] for t in kt]),
               "m_wall": med([t[0] for t in mt]), "m_cpu": med([t[1] for t in mt]),
               "k_load": med([t[2].get("load + elaborate", float("nan")) for t in kt]),
               "k_compile": med([t[2].get("compile", float("nan")) for t in kt]),
               "k_integrate": med([t[2].get("integrate", float("nan")) for t in kt]),
               "m_compile": med([t[2]["compile"] for t in mt]), "m_simulate": med([t[2]["simulate"] for t in mt]),
               "spread": c["spread"], "k_sweep": ks, "m_sweep": ms}
        if bt:
            row.update({"b_wall": med([t[0] for t in bt]), "b_cpu": med([t[1] for t in bt])})
        rows.append(row)
        print(json.dumps({k: v for k, v in row.items() if not k.endswith("sweep")}), flush=True)
    ms_ = lambda s: f"{1000 * s:.2f}"
    print("\n| robot | nq / nv | kanesim rtol (error) | MuJoCo RK4 steps (error) | kanesim process wall / CPU (ms) "
          "| MuJoCo process wall / CPU (ms) | CPU ratio kanesim / MuJoCo | kanesim load + elab., compile, integrate (ms) "
          "| MuJoCo compile, simulate (ms) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['robot']} | {r['nq']} / {r['nv']} | {r['rtol']:.2g} ({r['k_err']:.1e}) | {r['steps']} ({r['m_err']:.1e}) "
              f"| {ms_(r['k_wall'])} / {ms_(r['k_cpu'])} | {ms_(r['m_wall'])} / {ms_(r['m_cpu'])} "
              f"| {r['k_cpu'] / r['m_cpu']:.2f} | {ms_(r['k_load'])}, {ms_(r['k_compile'])}, {ms_(r['k_integrate'])} "
              f"| {ms_(r['m_compile'])}, {ms_(r['m_simulate'])} |")
    v = subprocess.run([args.kanesim, "--version"], capture_output=True, text=True).stdout.strip()
    import mujoco
    if args.baseline:
        print(f"\nBaseline {args.baseline} (same setting, same rows), in the same rotation:\n")
        print("| robot | baseline wall / CPU (ms) | kanesim wall / CPU (ms) | MuJoCo wall / CPU (ms) | CPU ratio baseline / MuJoCo "
              "| CPU ratio kanesim / MuJoCo |")
        print("|---|---|---|---|---|---|")
        for r in rows:
            print(f"| {r['robot']} | {ms_(r['b_wall'])} / {ms_(r['b_cpu'])} | {ms_(r['k_wall'])} / {ms_(r['k_cpu'])} "
                  f"| {ms_(r['m_wall'])} / {ms_(r['m_cpu'])} | {r['b_cpu'] / r['m_cpu']:.2f} | {r['k_cpu'] / r['m_cpu']:.2f} |")
    print(f"\nkanesim --integrator {args.integrator}; {args.reps} fresh processes each, alternated; load average {os.getloadavg()[0]:.1f}; {v}; "
          f"MuJoCo {mujoco.__version__}; Pinocchio {pin.__version__}")
    with open(os.path.join(OUT, f"race_{args.integrator}.json"), "w") as f:
        json.dump(rows, f, indent=1)


if __name__ == "__main__":
    main()
