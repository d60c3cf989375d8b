#!/usr/bin/env python3
"""Random stress sweeps of models with events (issue 41): the sweeps that found the folded
chain's cascade, the tossed cubes' missed landings and the friction chain's hang and energy
gains (docs/events.md). Each trial draws a model's parameters, runs every integrator at
rtol 1e-8 and reports what must not happen:

  FAIL     exit code other than 0 (with the last line of stderr)
  TIMEOUT  a run longer than --timeout seconds
  ERISE    (e < 1, friction, robots) the energy T + V rising between two rows by more than
           1e-7 max(1, |E|); "instant" is the largest rise across an event (two rows at
           one time), which no impact may have; a rise between rows is integration error
  EDRIFT   (chain, e = 1, no friction) the energy's change over the run beyond 1e-5
  STOPVIOL (chain, friction, robot) an output row with a joint past its end stop (j[k].q
           outside [-bend, bend], a robot joint outside its drawn <limit>) by more than 1e-9
           (an impact missed, a silent wrong answer)
  NOTFLAT, SPIN  (cube) not at rest flat on a face after 4 s (e < 0.8), or the vertical
           spin changed (the frictionless floor cannot change it)

    python3 bench/event_sweeps.py chain|cube|friction|robot SEED TRIALS [--kanesim BUILD/cli/kanesim]
                                  [--timeout S] [--stop-time S] [--robots panda,ur5_robot,solo12,talos]
                                  [--floating]

The models: bench/models/stop_chain.mech, tests/stress/models/tossed_cube.mech,
tests/stress/models/friction_stop_chain.mech; robot: Panda, UR5 or Solo12 (fixed base) from
tests/import/data, run as URDF with every joint's exact friction, damping and limits redrawn
(limits shrunk about their middle to 1, 0.3 or 0.1 of their range; starts inside them, speeds
+-2 rad/s); --robots adds Talos (32 moving joints) from the bench venv, --floating frees the
base. Prints "bad N" (FAIL + TIMEOUT + STOPVIOL) at the end.
"""
import argparse
import csv
import os
import random
import subprocess
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODELS = {
    "chain": "bench/models/stop_chain.mech",
    "cube": "tests/stress/models/tossed_cube.mech",
    "friction": "tests/stress/models/friction_stop_chain.mech",
    "robot": "tests/import/data",  # one of ROBOTS, its URDF rewritten per trial (robot_urdf)
}
ROBOTS = ["panda", "ur5_robot", "solo12"]
# Talos (32 moving joints, example-robot-data 6.0.0's talos_reduced.urdf) from the bench venv
# (bench/setup_venv.sh), only when named in --robots.
TALOS = "bench/.venv/lib/python3.11/site-packages/cmeel.prefix/share/example-robot-data/robots/talos_data/robots/talos_reduced.urdf"


def robot_file(robot):
    if robot == "talos":
        return os.path.join(ROOT, TALOS)
    return os.path.join(ROOT, MODELS["robot"], robot + ".urdf")


def robot_urdf(robot, p, rng):
    """A robot's URDF with every revolute or prismatic joint's <dynamics> and <limit> redrawn:
    exact Coulomb friction p["fric"], damping p["damp"], the limits shrunk about their middle by
    p["shrink"]. Returns the text, the moving joints' names with their limits, and the starts:
    q inside the limits, u in +-2 (a mimic follower is set by its leader)."""
    import xml.etree.ElementTree as ET
    tree = ET.parse(robot_file(robot))
    joints, starts = [], {}
    for j in tree.getroot().iter("joint"):
        if j.get("type") not in ("revolute", "prismatic"):
            continue
        for d in j.findall("dynamics"):
            j.remove(d)
        ET.SubElement(j, "dynamics", damping=repr(p["damp"]), friction=repr(p["fric"]))
        lim = j.find("limit")
        lo, hi = float(lim.get("lower")), float(lim.get("upper"))
        mid, half = (lo + hi) / 2, (hi - lo) / 2 * p["shrink"]
        lim.set("lower", repr(mid - half))
        lim.set("upper", repr(mid + half))
        joints.append((j.get("name"), mid - half, mid + half))
        if j.find("mimic") is None:
            starts[j.get("name") + ".q.start"] = rng.uniform(mid - 0.9 * half, mid + 0.9 * half)
            starts[j.get("name") + ".u.start"] = rng.uniform(-2, 2) * (1 if j.get("type") == "revolute" else 0.05)
    return ET.tostring(tree.getroot(), encoding="unicode"), joints, starts


def draw(kind, rng, robots=ROBOTS):
    """One trial's parameters (--set NAME=VALUE), by kind."""
    if kind == "robot":
        return dict(robot=rng.choice(robots), fric=rng.choice([0.0, 0.1, 0.5, 2.0]),
                    damp=rng.choice([0.0, 0.01, 0.3]), shrink=rng.choice([1.0, 0.3, 0.1])), {}
    if kind == "cube":
        p = dict(e=rng.choice([0, 0.2, 0.5, 0.8]), h=rng.uniform(0.3, 1.0), th=rng.uniform(0, 3.1),
                 ax=rng.uniform(-1, 1), ay=rng.uniform(-1, 1), az=rng.uniform(-1, 1), wx=rng.uniform(-8, 8),
                 wy=rng.uniform(-8, 8), wz=rng.uniform(-8, 8), vx=rng.uniform(-1, 1))
        return p, {}
    p = dict(N=rng.randint(2, 8 if kind == "chain" else 6), e=rng.choice([0, 0.3, 0.7, 1.0]),
             bend=round(rng.uniform(0.05, 1.0), 6))
    if kind == "friction":
        p.update(mu=rng.choice([0.05, 0.2, 0.5, 1.0]), r=rng.choice([0.01, 0.05, 0.2]),
                 tq=rng.choice([0.0, 0.0, 0.1, 0.5]))
    return p, {"j1.q.start": rng.uniform(-1.5, 1.5)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("kind", choices=sorted(MODELS))
    ap.add_argument("seed", type=int)
    ap.add_argument("trials", type=int)
    ap.add_argument("--kanesim", default=os.path.join(ROOT, "build", "cli", "kanesim"))
    ap.add_argument("--timeout", type=float, default=60.0)
    ap.add_argument("--stop-time", default=None, help="seconds simulated (default 4 for cubes, 3 otherwise)")
    ap.add_argument("--robots", default=",".join(ROBOTS),
                    help="robot: the robots drawn from (default %(default)s; also talos, from bench/.venv)")
    ap.add_argument("--floating", action="store_true", help="robot: a free-flying base (kanesim run --floating)")
    a = ap.parse_args()
    robots = a.robots.split(",")
    for r in robots:
        if not os.path.exists(robot_file(r)):
            ap.error("no URDF for robot '%s' (%s)" % (r, robot_file(r)))
    rng = random.Random(a.seed)
    model = os.path.join(ROOT, MODELS[a.kind])
    integrators = ["dop853", "cvode", "ida", "arkode"] if a.kind == "cube" else \
        ["dop853", "cvode", "cvode-bdf", "ida", "arkode"]
    stop = a.stop_time or ("4" if a.kind == "cube" else "3")
    if a.kind == "cube":
        outputs = ["free.q[2]", "free.frame_b.w[2]"]
    else:
        outputs = ["kinetic_energy", "potential_energy"]
    stop_tol = 1e-9  # a row's joint past its stop by more than this: an impact was missed
    bad = 0
    out = os.path.join(tempfile.gettempdir(), "event_sweeps_%d.csv" % os.getpid())
    urdf = os.path.join(tempfile.gettempdir(), "event_sweeps_%d.urdf" % os.getpid())
    for trial in range(a.trials):
        p, starts = draw(a.kind, rng, robots)
        limits = {}
        if a.kind == "robot":
            text, joints, starts = robot_urdf(p["robot"], p, rng)
            with open(urdf, "w") as f:
                f.write(text)
            model = urdf
            limits = {name + ".q": (lo, hi) for name, lo, hi in joints}
            sets = sum([["--set", f"{k}={v!r}"] for k, v in starts.items()], [])
        else:
            sets = sum([["--set", f"{k}={v!r}"] for k, v in {**p, **starts}.items()], [])
            if a.kind != "cube":
                limits = {"j[%d].q" % k: (-p["bend"], p["bend"]) for k in range(1, p["N"])}
        stopped = list(limits)
        for how in integrators:
            cmd = [a.kanesim, "run", model, "--integrator", how, "--stop-time", stop, "--rtol", "1e-8", "-o", out]
            if a.floating and a.kind == "robot":
                cmd.append("--floating")
            for o in outputs + stopped:
                cmd += ["--output", o]
            try:
                r = subprocess.run(cmd + sets, capture_output=True, text=True, timeout=a.timeout)
            except subprocess.TimeoutExpired:
                print("TIMEOUT", trial, how, p, starts, flush=True)
                bad += 1
                continue
            if r.returncode:
                last = (r.stderr.strip().splitlines() or [""])[-1][:250]
                print("FAIL", trial, how, r.returncode, last, p, starts, flush=True)
                bad += 1
                continue
            rows = list(csv.DictReader(open(out)))
            t = [float(x["time"]) for x in rows]
            if a.kind == "cube":
                y = float(rows[-1]["free.q[2]"])
                w0 = float(rows[0]["free.frame_b.w[2]"])
                spin = max(abs(float(x["free.frame_b.w[2]"]) - w0) for x in rows)
                if abs(y - 0.1) > 1e-5 and p["e"] < 0.8:
                    print("NOTFLAT", trial, how, y, p, flush=True)
                if spin > 1e-5:
                    print("SPIN", trial, how, spin, p, flush=True)
                continue
            worst = max([(max(limits[c][0] - float(x[c]), float(x[c]) - limits[c][1]), c, float(x["time"]))
                         for x in rows for c in stopped] or [(0.0, "", 0.0)])
            if worst[0] > stop_tol:
                print("STOPVIOL", trial, how, worst[1], "past its stop by", worst[0], "at t", worst[2], p, starts,
                      flush=True)
                bad += 1
            E = [float(x["kinetic_energy"]) + float(x["potential_energy"]) for x in rows]
            scale = max(1.0, max(abs(x) for x in E))
            rise = max(E[i + 1] - E[i] for i in range(len(E) - 1))
            instant = max([E[i + 1] - E[i] for i in range(len(E) - 1) if t[i + 1] == t[i]] or [0.0])
            if (a.kind in ("friction", "robot") or p["e"] < 1) and rise > 1e-7 * scale:
                print("ERISE", trial, how, rise, "instant", instant, p, starts, flush=True)
            if a.kind == "chain" and p["e"] == 1 and abs(E[-1] - E[0]) > 1e-5 * scale:
                print("EDRIFT", trial, how, E[-1] - E[0], p, starts, flush=True)
    for f in (out, urdf):
        if os.path.exists(f):
            os.remove(f)
    print("bad", bad)


if __name__ == "__main__":
    main()
