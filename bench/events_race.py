#!/usr/bin/env python3
"""Event-rich runs (issue 41, "Benchmarks"): time against the error in event times, against
closed forms, for kanesim's exact events, MuJoCo's soft contact (the same models in MJCF) and,
for the friction oscillator, kanesim's regularized (tanh) friction on the same model.

Problems (models in bench/models/, MJCF written here):
  ball      bounce_ball.mech: point mass dropped from h = 1 m, restitution e = 0.5, g = 9.81,
            2 s. Impacts t1 = sqrt(2h/g), t(k+1) = t(k) + 2 e^k t1; rest at t_inf = t1 (1+e)/(1-e).
  stop      stop_pendulum.mech: uniform rod (1 kg, 1 m) released horizontal onto an end stop
            0.3 rad before hanging, e = 0.5, 3 s: impact and flight times from elliptic
            integrals (mpmath, 60 digits), rest at their accumulation point.
  coulomb   coulomb_oscillator.mech: 1 kg on k = 4 pi^2 N/m, Coulomb force F = 0.00245 k,
            released at 1 m, 110 s: turning points at n/2 s with amplitude 1 - 2nF/k, sticks for
            good at the 204th (t = 102 s, x = 0.0004 m); ~100 cycles.
  chain     stop_chain.mech: 5 uniform rods (1 kg, 0.5 m) on hinges, released horizontal; the 4
            joints between links stop at +-0.4 rad, e = 0.5, 1.5 s: 15 impacts. No closed form:
            the reference is kanesim's DOP853 at rtol = atol = 1e-12, checked by DOP853 at 1e-14
            and CVODE-BDF at 1e-12 (the same 15 impacts within 6e-13 s and 7e-11 s; the script
            prints both). An impact is matched by joint, side and count (the 3rd impact of j[2] on
            q_max with the 3rd): a missed impact shifts the later ones of its joint and side.
Error of a run: the largest abs(t_sim - t_exact) over the events both have (the first 8 impacts
of the ball and the stop, every turning point of the oscillator) and the rest/stick time
(kanesim only: MuJoCo's soft contact has none), in seconds. kanesim: its events log
(`run --stats`); MuJoCo: the step where the gap (or the speed) changes sign, interpolated
linearly. Time: kanesim's `integrate` phase (`--stats`, the median of 3 processes, output
excluded); MuJoCo's `mj_step(m, d, n)` over the horizon (median of 3; compile excluded).
MuJoCo: default Euler integrator, timestep h; contact and limit softness solref = (10h/zeta,
zeta): a natural frequency of 0.1/h, ~30 steps a contact (at 0.5/h, 6 steps, the rebound
changed from bounce to bounce with the phase of the first step; at (2h, zeta) the ball left at
3.8x its impact speed at h = 1e-3), the damping ratio zeta calibrated per h so that the ball's
first rebound is e times its impact speed (0.26 at h = 1e-3, 0.25 at 1e-4; a linear
spring-damper's would be 0.2155); friction solref (2h, 1); solimp 0.99/0.99 so the constraint
follows that reference.

    bench/.venv/bin/python bench/events_race.py [--kanesim build/cli/kanesim] [--problems ball,stop,coulomb,chain]
"""
import argparse
import functools
import math
import os
import re
import statistics
import subprocess
import sys
import time

import mpmath as mp
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MODELS = os.path.join(HERE, "models")
G, E = 9.81, 0.5
RTOLS = [1e-4, 1e-6, 1e-8, 1e-10, 1e-12]
FIRST = 8  # impacts compared with MuJoCo


# ---------------------------------------------------------------- closed forms

def ball_exact():
    t1 = math.sqrt(2 * 1.0 / G)
    ts = [t1]
    for k in range(1, 60):
        ts.append(ts[-1] + 2 * E ** k * t1)
    return ts, t1 * (1 + E) / (1 - E)


@functools.lru_cache(maxsize=None)
def stop_exact():
    """Impact times of the rod on its stop (angle from hanging theta; start pi/2, stop 0.3)."""
    mp.mp.dps = 60
    Om = mp.sqrt(3 * G / 2)  # m g (L/2) / (m L^2 / 3), L = 1
    th0, ths = mp.pi / 2, mp.mpf("0.3")

    def rise_time(amp):  # from ths up to the turning angle amp (and, by symmetry, back)
        k = mp.sin(amp / 2)
        phi = mp.asin(mp.sin(ths / 2) / k)
        return (mp.ellipk(k ** 2) - mp.ellipf(phi, k ** 2)) / Om

    ts = [rise_time(th0)]
    w = mp.sqrt(2 * Om ** 2 * (mp.cos(ths) - mp.cos(th0)))  # speed at the stop
    while True:
        w *= E
        amp = mp.acos(mp.cos(ths) - w ** 2 / (2 * Om ** 2))
        flight = 2 * rise_time(amp)
        ts.append(ts[-1] + flight)
        if flight < mp.mpf("1e-22"):  # far below double precision; w^2 still resolved at 60 digits
            break
    # what is left is geometric (flight ~ speed): sum it
    return [float(t) for t in ts[:60]], float(ts[-1] + flight * E / (1 - E))


def coulomb_exact():
    return [0.5 * n for n in range(1, 205)], 102.0


# ---------------------------------------------------------------- kanesim

def kanesim_run(kanesim, model, stop, rtol, sets=(), integrator=None):
    cmd = [kanesim, "run", os.path.join(MODELS, model), "--stop-time", str(stop), "--interval", str(stop),
           "--rtol", repr(rtol), "--atol", repr(rtol), "--stats"]
    if integrator:
        cmd += ["--integrator", integrator]
    for s in sets:
        cmd += ["--set", s]
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        return None
    events = [(float(m.group(1)), m.group(2)) for m in re.finditer(r"^\s+t = (\S+)\s+(\S+: .*)$", p.stderr, re.M)]
    integ = float(re.search(r"^\s+integrate\s+(\S+)", p.stderr, re.M).group(1))
    rhs = int(re.search(r"^\s+right-hand sides\s+(\d+)", p.stderr, re.M).group(1))
    return events, integ, rhs, p.stdout


def kanesim_errors(problem, events):
    if problem == "coulomb":
        turns = [t for t, what in events if "reverses" in what or "sticks" in what]
        stick = [t for t, what in events if "sticks" in what]
        ts, rest = coulomb_exact()
        got_rest = stick[0] if stick else float("nan")
    else:
        turns = [t for t, what in events if "impact" in what]
        rests = [t for t, what in events if "rests" in what]
        ts, rest = ball_exact() if problem == "ball" else stop_exact()
        got_rest = rests[0] if rests else float("nan")
    n = min(len(turns), len(ts))
    first = max(abs(a - b) for a, b in zip(turns[:FIRST], ts[:FIRST]))
    every = max(abs(a - b) for a, b in zip(turns[:n], ts[:n]))
    return first, every, abs(got_rest - rest), n


# ---------------------------------------------------------------- MuJoCo

def zeta_for(e):
    return -math.log(e) / math.sqrt(math.pi ** 2 + math.log(e) ** 2)


@functools.lru_cache(maxsize=None)
def calibrated_zeta(h):
    """The damping ratio at which MuJoCo's ball at step h rebounds from its first impact with e
    (secant on the measured ratio; natural frequency kept at 0.5/h)."""
    import mujoco

    def ratio(z):
        m = mujoco.MjModel.from_xml_string(mjcf("ball", h, z))
        d = mujoco.MjData(m)
        d.qpos[0] = 1.0
        vmin = vmax = 0.0
        while d.time < 0.6:  # the first impact at 0.45 s
            mujoco.mj_step(m, d)
            vmin, vmax = min(vmin, d.qvel[0]), max(vmax, d.qvel[0])
        return float(vmax / -vmin)

    z0, z1 = zeta_for(E), zeta_for(E) * 1.2
    r0, r1 = ratio(z0) - E, ratio(z1) - E
    for _ in range(12):
        if abs(r1) < 1e-4 or r1 == r0:
            break
        z0, z1, r0 = z1, max(0.02, min(0.9, z1 - r1 * (z1 - z0) / (r1 - r0))), r1
        r1 = ratio(z1) - E
    return z1


def mjcf(problem, h, z=None):
    z = calibrated_zeta(h) if z is None else z
    ref = f'"{10 * h / z!r} {z!r}"'  # natural frequency 1/(tau z) = 0.1/h: ~30 steps a contact
    imp = '"0.99 0.99 0.001"'
    if problem == "ball":  # a point: a tiny sphere whose bottom is the frame origin raised by r
        body = ('<body name="ball" pos="0 0 0"><joint name="lift" type="slide" axis="0 0 1"/>'
                '<geom type="sphere" size="0.001" pos="0 0 0.001" mass="1" condim="1" '
                f'solref={ref} solimp={imp}/></body>')
        return (f'<mujoco><option timestep="{h!r}" gravity="0 0 -{G}"/><worldbody>'
                f'<geom type="plane" size="5 5 0.1" condim="1" solref={ref} solimp={imp}/>{body}</worldbody></mujoco>')
    if problem == "stop":  # rod along x, hinge z, gravity -y, limit at 0.3 - pi/2
        lo = 0.3 - math.pi / 2
        return (f'<mujoco><compiler angle="radian"/><option timestep="{h!r}" gravity="0 -{G} 0"/><worldbody>'
                f'<body name="rod"><joint name="pivot" type="hinge" axis="0 0 1" range="{lo!r} 100" limited="true" '
                f'solreflimit={ref} solimplimit={imp}/>'
                f'<inertial pos="0.5 0 0" mass="1" diaginertia="{1e-12 / 12!r} {1 / 12!r} {1 / 12!r}"/></body>'
                '</worldbody></mujoco>')
    k = 4 * math.pi ** 2  # coulomb: slide with joint stiffness and frictionloss F (MuJoCo's dry friction)
    return (f'<mujoco><option timestep="{h!r}" gravity="0 0 0"/><worldbody><body name="box">'
            f'<joint name="slide" type="slide" axis="1 0 0" stiffness="{k!r}" frictionloss="{0.00245 * k!r}" '
            f'solreffriction="{2 * h!r} 1" solimpfriction={imp}/>'
            '<inertial pos="0 0 0" mass="1" diaginertia="1 1 1"/></body></worldbody></mujoco>')


def mujoco_run(problem, h, stop):
    import mujoco
    from mujoco import rollout
    m = mujoco.MjModel.from_xml_string(mjcf(problem, h))
    d = mujoco.MjData(m)
    n = int(round(stop / h))
    q0 = {"ball": 1.0, "stop": 0.0, "coulomb": 1.0}[problem]

    def reset():
        mujoco.mj_resetData(m, d)
        d.qpos[0] = q0

    times = []
    for _ in range(3 if n <= 100000 else 1):
        reset()
        t0 = time.perf_counter()
        mujoco.mj_step(m, d, n)
        times.append(time.perf_counter() - t0)
    reset()
    spec = mujoco.mjtState.mjSTATE_QPOS | mujoco.mjtState.mjSTATE_QVEL
    x0 = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, x0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    traj = []
    chunk = 200000
    state = x0
    for start in range(0, n, chunk):  # in pieces: a 110 s run at 1e-5 is 11 million states
        st, _ = rollout.rollout(m, d, state[None, :], nstep=min(chunk, n - start))
        traj.append(st[0, :, 1:3].copy())  # time, qpos, qvel (FULLPHYSICS: time first)
        state = st[0, -1]
    y = np.vstack(traj)
    t = (np.arange(len(y)) + 1) * h
    pos, vel = y[:, 0], y[:, 1]
    del spec
    if problem == "coulomb":
        sig = vel  # turning points: the speed changes sign
        cross = np.nonzero((sig[:-1] != 0) & (np.sign(sig[:-1]) != np.sign(sig[1:])) & (sig[1:] != 0))[0]
    else:
        sig = pos - (0.0 if problem == "ball" else 0.3 - math.pi / 2)  # the gap
        cross = np.nonzero((sig[:-1] > 0) & (sig[1:] <= 0))[0]
    ev = [t[i] + h * sig[i] / (sig[i] - sig[i + 1]) for i in cross]
    return ev, statistics.median(times), n


def mujoco_errors(problem, ev):
    ts = {"ball": ball_exact, "stop": stop_exact, "coulomb": coulomb_exact}[problem]()[0]
    if not ev:
        return float("nan"), float("nan"), 0
    first = max(abs(a - b) for a, b in zip(ev[:FIRST], ts[:FIRST]))
    n = min(len(ev), len(ts))
    every = max(abs(a - b) for a, b in zip(ev[:n], ts[:n]))
    return first, every, n


# ---------------------------------------------------------------- the chain (reference: kanesim at 1e-12)

CHAIN_N, CHAIN_BEND, CHAIN_STOP = 5, 0.4, 1.5


def chain_impacts(events):
    """{(joint, side): [t, ...]} of a kanesim events log."""
    out = {}
    for t, what in events:
        m = re.match(r"(\S+): impact at (q_min|q_max)", what)
        if m:
            out.setdefault((m.group(1), m.group(2)), []).append(t)
    return out


def ordered(impacts):
    """[(t, key, k)]: every impact in time order, k its count on that joint and side."""
    return sorted((t, key, k) for key, ts in impacts.items() for k, t in enumerate(ts))


@functools.lru_cache(maxsize=None)
def chain_reference(kanesim):
    """The impacts of DOP853 at 1e-12, and the largest difference from each check run's."""
    ref = ordered(chain_impacts(kanesim_run(kanesim, "stop_chain.mech", CHAIN_STOP, 1e-12, integrator="dop853")[0]))
    checks = []
    for integ, r in (("dop853", 1e-14), ("cvode-bdf", 1e-12)):
        _, every, n = chain_errors(ref, chain_impacts(kanesim_run(kanesim, "stop_chain.mech", CHAIN_STOP, r,
                                                                  integrator=integ)[0]))
        assert n == len(ref), f"{integ} at {r} lists other impacts than the reference"
        checks.append((integ, r, every))
    return ref, checks


def chain_errors(ref, impacts):
    """Largest |t - t_ref| over the first FIRST and over all reference impacts the run has."""
    errs = [abs(impacts[key][k] - t) if len(impacts.get(key, ())) > k else None for t, key, k in ref]
    got = [x for x in errs if x is not None]
    first = [x for x in errs[:FIRST] if x is not None]
    return (max(first) if first else float("nan")), (max(got) if got else float("nan")), len(got)


def chain_mjcf(h):
    z = calibrated_zeta(h)
    ref, imp = f'"{10 * h / z!r} {z!r}"', '"0.99 0.99 0.001"'
    inertial = f'<inertial pos="0.25 0 0" mass="1" diaginertia="1e-12 {1 / 48!r} {1 / 48!r}"/>'
    body = f'<body name="l1"><joint name="root" type="hinge" axis="0 0 1"/>{inertial}'
    for i in range(1, CHAIN_N):
        body += (f'<body name="l{i + 1}" pos="0.5 0 0"><joint name="j{i}" type="hinge" axis="0 0 1" '
                 f'limited="true" range="{-CHAIN_BEND!r} {CHAIN_BEND!r}" solreflimit={ref} solimplimit={imp}/>'
                 f'{inertial}')
    body += "</body>" * CHAIN_N
    return (f'<mujoco><compiler angle="radian"/><option timestep="{h!r}" gravity="0 -{G} 0"/>'
            f'<worldbody>{body}</worldbody></mujoco>')


def mujoco_chain_run(h):
    """MuJoCo's impacts: the steps where a joint enters its range's end (interpolated linearly)."""
    import mujoco
    from mujoco import rollout
    m = mujoco.MjModel.from_xml_string(chain_mjcf(h))
    d = mujoco.MjData(m)
    n = int(round(CHAIN_STOP / h))
    times = []
    for _ in range(3):
        mujoco.mj_resetData(m, d)
        t0 = time.perf_counter()
        mujoco.mj_step(m, d, n)
        times.append(time.perf_counter() - t0)
    mujoco.mj_resetData(m, d)
    x0 = np.empty(mujoco.mj_stateSize(m, mujoco.mjtState.mjSTATE_FULLPHYSICS))
    mujoco.mj_getState(m, d, x0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    st, _ = rollout.rollout(m, d, x0[None, :], nstep=n)
    q = st[0, :, 2:1 + CHAIN_N]  # FULLPHYSICS: time, then qpos (root first)
    t = (np.arange(len(q)) + 1) * h
    impacts = {}
    for i in range(1, CHAIN_N):
        for side, gap in (("q_min", q[:, i - 1] + CHAIN_BEND), ("q_max", CHAIN_BEND - q[:, i - 1])):
            cross = np.nonzero((gap[:-1] > 0) & (gap[1:] <= 0))[0]
            if len(cross):
                impacts[(f"j[{i}]", side)] = [t[c] + h * gap[c] / (gap[c] - gap[c + 1]) for c in cross]
    return impacts, statistics.median(times), n


def chain_rows(kanesim):
    ref, checks = chain_reference(kanesim)
    k = len(ref)
    for r in RTOLS[:-1]:
        runs = [kanesim_run(kanesim, "stop_chain.mech", CHAIN_STOP, r) for _ in range(3)]
        if runs[0] is None:
            print(f"| chain | kanesim exact | rtol {r:.0e} | failed |")
            continue
        first, every, n = chain_errors(ref, chain_impacts(runs[0][0]))
        extra = sum(1 for _, what in runs[0][0] if "impact" in what) - n
        integ = statistics.median(x[1] for x in runs)
        print(f"| chain | kanesim exact | rtol {r:.0e} | {n}/{k}" + (f" (+{extra})" if extra else "")
              + f" | {first:.1e} | {every:.1e} | — | {1000 * integ:.3f} | {runs[0][2]} |", flush=True)
    for integ, r, every in checks:  # the reference's own error
        print(f"| chain | reference check: kanesim {integ} | rtol {r:.0e} | {k}/{k} | | {every:.1e} | — | | |",
              flush=True)
    for h in (1e-3, 1e-4, 1e-5):
        impacts, secs, n = mujoco_chain_run(h)
        first, every, nm = chain_errors(ref, impacts)
        extra = sum(len(v) for v in impacts.values()) - nm
        print(f"| chain | MuJoCo Euler, soft | h {h:.0e} | {nm}/{k}" + (f" (+{extra})" if extra else "")
              + f" | {first:.1e} | {every:.1e} | — | {1000 * secs:.3f} | {n} steps |", flush=True)


# ---------------------------------------------------------------- table

PROBLEMS = {"ball": ("bounce_ball.mech", 2.0), "stop": ("stop_pendulum.mech", 3.0),
            "coulomb": ("coulomb_oscillator.mech", 110.0), "chain": ("stop_chain.mech", CHAIN_STOP)}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kanesim", default=os.path.join(ROOT, "build", "cli", "kanesim"))
    ap.add_argument("--problems", default="ball,stop,coulomb,chain")
    args = ap.parse_args()
    print("| problem | tool | setting | events matched | error, first 8 (s) | error, all matched (s) "
          "| rest/stick time error (s) | time (ms) | RHS evaluations |")
    print("|---|---|---|---|---|---|---|---|---|")
    for problem in args.problems.split(","):
        if problem == "chain":
            chain_rows(args.kanesim)
            continue
        model, stop = PROBLEMS[problem]
        variants = [("kanesim exact", [])]
        if problem == "coulomb":
            variants.append(("kanesim tanh (friction_v 1e-3)", ["exact=false"]))
        for label, sets in variants:
            for r in RTOLS:
                runs = [kanesim_run(args.kanesim, model, stop, r, sets) for _ in range(3)]
                if runs[0] is None:
                    print(f"| {problem} | {label} | rtol {r:.0e} | failed |")
                    continue
                events, _, rhs, rows = runs[0]
                integ = statistics.median(x[1] for x in runs)
                if sets:  # regularized: no events; turning points from rows
                    first, every, rest_err, n = regularized_errors(args.kanesim, model, stop, r, sets)
                else:
                    first, every, rest_err, n = kanesim_errors(problem, events)
                rest_txt = f"{rest_err:.1e}" if math.isfinite(rest_err) else "never sticks (creeps)"
                print(f"| {problem} | {label} | rtol {r:.0e} | {n} | {first:.1e} | {every:.1e} | {rest_txt} "
                      f"| {1000 * integ:.3f} | {rhs} |", flush=True)
        hs = [1e-3, 1e-4] + ([1e-5] if problem != "coulomb" else [])
        for h in hs:
            ev, secs, n = mujoco_run(problem, h, stop)
            first, every, nm = mujoco_errors(problem, ev)
            print(f"| {problem} | MuJoCo Euler, soft | h {h:.0e} | {nm} | {first:.1e} | {every:.1e} | — "
                  f"| {1000 * secs:.3f} | {n} steps |", flush=True)
    v = subprocess.run([args.kanesim, "--version"], capture_output=True, text=True).stdout.strip()
    import mujoco
    print(f"\nload average {os.getloadavg()[0]:.1f}; {v}; MuJoCo {mujoco.__version__}")


def regularized_errors(kanesim, model, stop, rtol, sets):
    """Turning points of the tanh run: sign changes of u in rows every 2 ms, located by the
    quadratic through three rows; it never sticks (it creeps), so 'stick' is its last one."""
    dt = 0.002
    cmd = [kanesim, "run", os.path.join(MODELS, model), "--stop-time", str(stop), "--interval", str(dt),
           "--rtol", repr(rtol), "--atol", repr(rtol)] + [x for s in sets for x in ("--set", s)]
    p = subprocess.run(cmd, capture_output=True, text=True, check=True)
    data = np.loadtxt(p.stdout.splitlines()[1:], delimiter=",")
    t, u = data[:, 0], data[:, 2]
    idx = np.nonzero((u[:-1] != 0) & (np.sign(u[:-1]) != np.sign(u[1:])))[0]  # not the start at rest
    turns = []
    for i in idx:
        j = min(max(i, 1), len(t) - 2)
        c = np.polyfit(t[j - 1:j + 2] - t[j], u[j - 1:j + 2], 2)
        roots = [x.real + t[j] for x in np.roots(c) if abs(x.imag) < 1e-12 and t[i] - 1e-9 <= x.real + t[j] <= t[i + 1] + 1e-9]
        turns.append(roots[0] if roots else t[i])
    ts, rest = coulomb_exact()
    n = min(len(turns), len(ts))
    first = max(abs(a - b) for a, b in zip(turns[:FIRST], ts[:FIRST]))
    every = max(abs(a - b) for a, b in zip(turns[:n], ts[:n]))
    return first, every, float("inf"), n


if __name__ == "__main__":
    sys.exit(main())
