"""Work-precision runs (issue 6): kanesim and its peers on the problems of problems.py, in
one run on one machine. Writes bench/results/results.json; report.py turns it into plots
and tables. Called by bench/run_work_precision.sh, which builds what this needs.

    bench/.venv/bin/python bench/wp/run.py --kanesim build-w/cli/kanesim --pin-driver DRIVER
        [--kanesim-driver build-w/bench/kanesim_driver]
        [--rhs-bench build-w/bench/rhs_chain] [--quick] [--only kanesim,pin,scipy,mujoco,exudyn,baseline,sympy,rhs]
        [--problems fourbar,rolling_disk]   (name prefixes; other problems' results are kept)

Timing: wall time of the integration only (kanesim: the `integrate` phase of --stats;
peers: around their integrate call, model construction excluded), median of REPS runs.
The two C++ programs, bench/kanesim_driver.cpp and bench/pin/pin_driver.cpp, are timed the
same way: compiled once, integrated CPP_REPS times in one process, the median. Without
--kanesim-driver, kanesim is timed by `kanesim run` instead, one cold integration per
process (start-up and first-touch costs included, ~20 us on this machine).
A sweep over tolerances (or time steps) goes from loose to tight and stops after the first
run that takes longer than RUN_BUDGET seconds, so the whole benchmark fits on 2 cores.
"""
import argparse
import json
import os
import platform
import re
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import fourbar_geometry  # noqa: E402
import problems as P  # noqa: E402
from readings import LEVELS, READINGS, best_of  # noqa: E402
from problems import BENCH, ROOT, Problem, all_problems, mjcf, pin_model  # noqa: E402

RTOLS = [1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10, 1e-11, 1e-12]
RTOLS_QUICK = [1e-3, 1e-6, 1e-9, 1e-12]
# Repetitions inside the C++ drivers (pin_driver, kanesim_driver; median): both are timed
# the same way, warm and in process, up to this many times or 1 s of runs. The shared
# machine's speed wanders by up to 1.6x between identical runs seconds apart (four-bar,
# session 7): 9 runs give a steadier median than 5, at a few ms per point.
CPP_REPS = 9


# PairedSweep (kanesim DOP853 beside Pinocchio C++): rounds per tolerance, each a driver
# call (itself the median of CPP_REPS runs); a series takes further rounds only while one
# run of it is cheaper than PAIRED_CHEAP seconds.
PAIRED_ROUNDS = 3
PAIRED_CHEAP = 0.02
# retime_decisive: rounds per side for the two points that decide a level.
RETIME_ROUNDS = 4


def cpp_reps(sweep):
    return CPP_REPS if sweep.reps > 1 else 1  # --quick: one run
# Three tolerances per decade for the candidates for "best" (kanesim DOP853, Pinocchio C++,
# SciPy + pin.aba): the time to reach a level is that of the cheapest point at or below
# it, so a one-per-decade grid overstates it by up to 10^(1/8) = 1.33x for an 8th-order
# method (one decade of tolerance); three per decade, by up to 1.10x.
RTOLS_FINE = [10.0 ** (-k / 3.0) for k in range(9, 37)]          # 1e-3 ... 1e-12
PIN_RTOLS_FINE = RTOLS_FINE + [10.0 ** (-k / 3.0) for k in range(37, 40)]  # ... 1e-13
MJ_STEPS = [1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5]
CONSTRAINED = ("fourbar", "disk")   # loops and rolling contacts: not trees
# Pinocchio on the four-bar: constraintDynamics (Baumgarte, proximal; fourbar_geometry.PIN_LOOP)
PIN_LOOP_CPP = "pinocchio-constraintDynamics C++ DOP853"
PIN_LOOP_SCIPY = "scipy DOP853 + pin.constraintDynamics"
# Why a peer does not run a problem (written to results.json's notes and the report).
NOT_RUN = {
    ("pin", "disk"): "Pinocchio C++ / SciPy + pin.aba: no rolling (non-holonomic) constraint in Pinocchio",
}


class Sweep:
    """Runs fn(param) for each param, REPS times while a run is cheap; stops after a
    run slower than the budget. fn returns dict(time=..., q=..., ok=bool, ...)."""

    def __init__(self, reps, budget):
        self.reps, self.budget = reps, budget

    def run(self, problem, params, fn, label, go_on_after_failure=False):
        """go_on_after_failure: record a failed run and try the next parameter (used where a
        loose tolerance can fail while tighter ones work, as kanesim's flat-disk check)."""
        pts = []
        for prm in params:
            runs = []
            for k in range(self.reps):
                r = fn(prm)
                runs.append(r)
                if not r.get("ok", True) or r["time"] > self.budget / 4:
                    break
            r = runs[-1]
            if not r.get("ok", True):
                pts.append(dict(param=prm, ok=False, message=r.get("message", "")))
                print("  %-28s %-8g FAILED %s" % (label, prm, r.get("message", "")[:80]), flush=True)
                if go_on_after_failure:
                    continue
                break
            t = statistics.median(x["time"] for x in runs)
            err = problem.error(r["q"])
            extra = {k: v for k, v in r.items() if k not in ("q", "time", "ok")}
            pts.append(dict(param=prm, ok=True, time=t, error=err, reps=len(runs), **extra))
            print("  %-28s %-8g time %.4g s  error %.3g" % (label, prm, t, err), flush=True)
            if t > self.budget:
                break
        return pts


class PairedSweep:
    """The candidates for "best" on one grid, side by side: at each parameter every series
    still going runs once per round, the rounds alternate the order (A B C, C B A, A B C),
    and a series' time at the point is the median of its rounds. So the two sides of a
    ratio are timed seconds apart, in the same stretch of the machine's load, instead of
    one sweep after the other. A series takes further rounds only while one of its runs
    is cheaper than `cheap` seconds (the long runs are timed over many steps already and
    would cost minutes). series: list of dict(label, fn, params, go_on_after_failure)."""

    def __init__(self, rounds, budget, cheap):
        self.rounds, self.budget, self.cheap = rounds, budget, cheap

    def run(self, problem, series):
        grid = sorted({prm for s in series for prm in s["params"]}, reverse=True)  # loose -> tight
        pts = {s["label"]: [] for s in series}
        alive = {s["label"]: True for s in series}
        for prm in grid:
            live = [s for s in series if alive[s["label"]] and prm in s["params"]]
            runs = {s["label"]: [] for s in live}
            for k in range(self.rounds):
                order = live if k % 2 == 0 else live[::-1]
                for s in order:
                    done = runs[s["label"]]
                    if done and (not done[-1].get("ok", True) or done[-1]["time"] > self.cheap):
                        continue  # failed, or too dear for another round
                    done.append(s["fn"](prm))
            for s in live:
                lab, done = s["label"], runs[s["label"]]
                r = done[-1]
                if not r.get("ok", True):
                    pts[lab].append(dict(param=prm, ok=False, message=r.get("message", "")))
                    print("  %-28s %-8g FAILED %s" % (lab, prm, r.get("message", "")[:80]), flush=True)
                    if not s.get("go_on_after_failure"):
                        alive[lab] = False
                    continue
                t = statistics.median(x["time"] for x in done)
                err = problem.error(r["q"])
                extra = {key: v for key, v in r.items() if key not in ("q", "time", "ok")}
                pts[lab].append(dict(param=prm, ok=True, time=t, error=err, rounds=len(done),
                                     round_times=[x["time"] for x in done], **extra))
                print("  %-28s %-8g time %.4g s  error %.3g  (%d rounds)" % (lab, prm, t, err, len(done)), flush=True)
                if t > self.budget:
                    alive[lab] = False
        return pts


# --------------------------------------------------------------------------- kanesim
def kanesim_driver_run(driver, p, integrator, solver, rtol, reps, projection="eval"):
    """bench/kanesim_driver.cpp: compiled once, integrated REPS times in one process, the
    median of the integrate phase (timed as pin_driver times Pinocchio: warm, in process)."""
    cmd = [driver, p.mech, repr(p.T), repr(rtol), integrator, solver, projection, str(reps)] + list(p.sets)
    pr = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if pr.returncode != 0:
        return dict(ok=False, time=0.0, message="exit %d: %s" % (pr.returncode, pr.stderr.strip()[-200:]))
    kv = dict(tok.split("=", 1) for tok in pr.stdout.split())
    names, last = kv["names"].split(","), [float(x) for x in kv["last"].split(",")]
    q = [last[names.index(nm)] for nm in p.q_names]
    return dict(ok=True, time=float(kv["wall"]), q=q, rhs=int(kv["rhs"]), steps=int(kv["steps"]))


def kanesim_run(exe, p, integrator, solver, rtol, out_csv, extra=()):
    cmd = [exe, "run", p.mech, "-o", out_csv, "--rtol", repr(rtol), "--atol", repr(rtol),
           "--integrator", integrator, "--solver", solver, "--stop-time", repr(p.T),
           "--interval", repr(p.T), "--stats"] + [a for s in p.sets for a in ("--set", s)] + list(extra)
    pr = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    stats = {}
    for key, pat in (("integrate", r"integrate\s+([0-9.eE+-]+)"), ("compile", r"compile\s+([0-9.eE+-]+)"),
                     ("load", r"load \+ elaborate\s+([0-9.eE+-]+)"), ("rhs", r"right-hand sides\s+(\d+)"),
                     ("rhs_jac", r"\(\+ (\d+) for difference"), ("steps", r"steps\s+(\d+)")):
        m = re.search(pat, pr.stderr)
        if m:
            stats[key] = float(m.group(1))
    if pr.returncode != 0:
        return dict(ok=False, time=0.0, message="exit %d: %s" % (pr.returncode, pr.stderr.strip()[-200:]))
    with open(out_csv) as fh:
        lines = fh.read().split("\n")
    head = lines[0].split(",")
    last = [float(x) for x in lines[-2].split(",")] if lines[-1] == "" else [float(x) for x in lines[-1].split(",")]
    q = [last[head.index(nm)] for nm in p.q_names]
    return dict(ok=True, time=stats.get("integrate", 0.0), q=q, load=stats.get("load"),
                compile=stats.get("compile"), rhs=stats.get("rhs"), rhs_jac=stats.get("rhs_jac"),
                steps=stats.get("steps"))


def kanesim_measure(args, sweep):
    """measure(p, integrator, solver, rtol, extra) -> one timed point of kanesim."""
    if args.kanesim_driver:  # in-process repetitions (the driver's median)
        def measure(p, integ, solver, r, extra=()):
            proj = "step" if "step" in extra else "eval"
            return kanesim_driver_run(args.kanesim_driver, p, integ, solver, r, cpp_reps(sweep), proj)
    else:  # `kanesim run`, one cold integration per process
        tmp = tempfile.mkdtemp(prefix="wp_kanesim_")

        def measure(p, integ, solver, r, extra=()):
            return kanesim_run(args.kanesim, p, integ, solver, r, os.path.join(tmp, "out.csv"), extra)
    return measure


def kanesim_dop853_series(args, p, sweep, fine):
    """kanesim's DOP853 series of problem p (the candidates for its best), for PairedSweep."""
    measure = kanesim_measure(args, sweep)
    constrained = p.kind in CONSTRAINED
    out = []
    for solver in ("dense",) if constrained else ("dense", "recursive"):
        out.append(dict(label="kanesim dop853 %s" % solver, params=fine, go_on_after_failure=constrained,
                        fn=lambda r, solver=solver: measure(p, "dop853", solver, r)))
    if constrained:  # DOP853 projecting once per accepted step (`--projection step`)
        out.append(dict(label="kanesim dop853 dense step-projection", params=fine, go_on_after_failure=True,
                        fn=lambda r: measure(p, "dop853", "dense", r, ("--projection", "step"))))
    return out


def pin_cpp_series(args, p, sweep, pin_rtols):
    """Pinocchio C++'s series of problem p (DOP853 with aba, or constraintDynamics on the
    four-bar with and without Baumgarte), for PairedSweep; [] where Pinocchio cannot run it."""
    reps = cpp_reps(sweep)
    if p.kind == "fourbar":
        no_bg = dict(fourbar_geometry.PIN_LOOP, kp=0.0, kd=0.0)
        return [dict(label=label, params=pin_rtols, fn=lambda r, loop=loop: pin_cpp_run(args.pin_driver, p, r, reps, loop))
                for label, loop in ((PIN_LOOP_CPP, fourbar_geometry.PIN_LOOP), (PIN_LOOP_CPP + " no Baumgarte", no_bg))]
    if p.kind in CONSTRAINED:
        return []
    return [dict(label="pinocchio-aba C++ DOP853", params=pin_rtols,
                 fn=lambda r: pin_cpp_run(args.pin_driver, p, r, reps))]


def retime_decisive(p, series, pts, rounds):
    """The sweep's point that decides a level is timed in one stretch of the machine's load,
    its rival's in another: the shared machine's speed wanders by up to 1.6x for seconds
    to minutes, and a ratio can turn on which tool's decisive point met a slow stretch
    (the four-bar over 2 s at 1e-3 in session 10). So, per level and reading
    (readings.py), the decisive kanesim point and the decisive Pinocchio C++ point are
    timed again back to back, `rounds` times each in the order K P P K K P P K ...; the
    report gives the ratio of the medians beside the sweep's. Each pair is timed once
    however many levels and readings pick it."""
    fns = {s["label"]: s["fn"] for s in series}
    out, done = [], {}
    for lv in LEVELS:
        if lv < p.trust_floor():
            continue
        for reading in READINGS:
            _, kt, kp = best_of(pts, lv, reading, True)
            _, qt, qp = best_of(pts, lv, reading, False)
            if kp is None or qp is None:
                continue
            key = (kt, kp["param"], qt, qp["param"])
            if key not in done:
                times = {kt: [], qt: []}
                for i in range(rounds):
                    for side in ((kt, kp), (qt, qp)) if i % 2 == 0 else ((qt, qp), (kt, kp)):
                        r = fns[side[0]](side[1]["param"])
                        times[side[0]].append(r["time"] if r.get("ok", True) else None)
                done[key] = dict(kanesim=kt, kanesim_param=kp["param"], kanesim_times=times[kt],
                                 peer=qt, peer_param=qp["param"], peer_times=times[qt])
                print("  side by side at %g (%s): %s %s / %s %s" % (
                    lv, reading, kt, " ".join("%.4g" % t for t in times[kt] if t),
                    qt, " ".join("%.4g" % t for t in times[qt] if t)), flush=True)
            out.append(dict(level=lv, reading=reading, **done[key]))
    return out


def run_paired(args, p, sweep, res, fine, pin_rtols):
    """kanesim's DOP853 series and Pinocchio C++ on problem p, side by side (PairedSweep),
    then their decisive points re-timed back to back (retime_decisive)."""
    series = kanesim_dop853_series(args, p, sweep, fine) + pin_cpp_series(args, p, sweep, pin_rtols)
    print("kanesim DOP853 and Pinocchio C++, side by side:", p.title, flush=True)
    paired = PairedSweep(PAIRED_ROUNDS if sweep.reps > 1 else 1, sweep.budget, PAIRED_CHEAP)
    pts = paired.run(p, series)
    for label, series_pts in pts.items():
        res["runs"].setdefault(p.name, {})[label] = series_pts
    res.setdefault("retimed", {})[p.name] = retime_decisive(p, series, pts, RETIME_ROUNDS if sweep.reps > 1 else 1)
    if not pin_cpp_series(args, p, sweep, pin_rtols):
        res["notes"].append("%s: %s" % (p.name, NOT_RUN[("pin", p.kind)]))


def run_kanesim(args, problems, sweep, rtols, res, fine, skip_dop853=False):
    """skip_dop853: the DOP853 series run in run_paired instead."""
    measure = kanesim_measure(args, sweep)
    # The driver repeats in process (its median): then the sweep calls it once per point.
    one = Sweep(1, sweep.budget) if args.kanesim_driver else sweep
    for p in problems:
        print("kanesim:", p.title, flush=True)
        # Loops and contacts: the reduced form (`--solver dense`, the automatic choice for
        # these small scenes; the multiplier form is measured by bench/loop_solvers).
        constrained = p.kind in CONSTRAINED
        integrators = ("ida", "cvode", "cvode-bdf", "arkode") if constrained else ("ida", "cvode", "arkode")
        for integ in integrators:
            # Trees: the recursive path (the automatic choice) and dense; the sparse (KLU)
            # path costs 5-6x recursive per right-hand side at every size (bench/rhs_chain)
            # and is measured there, not in these sweeps.
            for solver in ("dense",) if constrained else ("dense", "recursive"):
                label = "kanesim %s %s" % (integ, solver)
                pts = one.run(p, rtols, lambda r: measure(p, integ, solver, r), label, go_on_after_failure=constrained)
                res["runs"].setdefault(p.name, {})[label] = pts
        if not skip_dop853:  # DOP853 (on loops and contacts also with `--projection step`)
            for s in kanesim_dop853_series(args, p, sweep, fine):
                res["runs"].setdefault(p.name, {})[s["label"]] = one.run(
                    p, s["params"], s["fn"], s["label"], go_on_after_failure=s["go_on_after_failure"])


# --------------------------------------------------------------------------- Pinocchio C++
def pin_cpp_run(driver, p, rtol, reps, loop=None):
    """loop: for the four-bar, the constraintDynamics settings (fourbar_geometry.PIN_LOOP)."""
    cmd = [driver, "integrate", p.kind, str(p.n), repr(p.T), repr(rtol), repr(rtol), str(reps)]
    if p.kind == "fourbar":
        cmd += [",".join(repr(x) for x in v) for v in P.fourbar_start(p)]
        cmd += [repr(float(loop[k])) for k in ("kp", "kd", "mu", "accuracy")] + [str(int(loop["max_iter"]))]
    pr = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    if pr.returncode != 0:
        return dict(ok=False, time=0.0, message=pr.stderr.strip())
    kv = dict(tok.split("=", 1) for tok in pr.stdout.split())
    out = dict(ok=True, time=float(kv["wall"]), q=[float(x) for x in kv["q"].split(",")],
               rhs=int(kv["evals"]), steps=int(kv["steps"]))
    if p.kind == "fourbar":  # loop drift at T, from q(T), u(T) (Pinocchio's own gap beside it)
        out["gap"], out["vgap"] = fourbar_geometry.loop_gap(out["q"], [float(x) for x in kv["u"].split(",")])
        out["pin_gap"] = float(kv["gap"])
    return out


def run_pin_cpp(args, problems, sweep, res, pin_rtols):
    """Pinocchio C++ alone (--only pin without kanesim); run_paired times it beside kanesim."""
    one = Sweep(1, sweep.budget)  # the driver repeats internally (median): one call per tolerance
    for p in problems:
        series = pin_cpp_series(args, p, sweep, pin_rtols)
        if not series:
            res["notes"].append("%s: %s" % (p.name, NOT_RUN[("pin", p.kind)]))
            continue
        print("pinocchio C++:", p.title, flush=True)
        for s in series:
            res["runs"].setdefault(p.name, {})[s["label"]] = one.run(p, s["params"], s["fn"], s["label"])


# --------------------------------------------------------------------------- SciPy + pin.aba
def run_scipy(args, problems, sweep, rtols, res):
    import pinocchio as pin
    from scipy.integrate import odeint, solve_ivp
    for p in problems:
        if p.kind == "fourbar":
            run_scipy_loop(p, sweep, rtols, res)
        if p.kind in CONSTRAINED:
            continue
        print("scipy + pinocchio:", p.title, flush=True)
        model = pin_model(p)
        data = model.createData()
        n = model.nq
        zero = np.zeros(n)
        y0 = np.concatenate([np.full(n, p.q0), np.zeros(n)])

        def f(t, y):
            return np.concatenate([y[n:], pin.aba(model, data, y[:n], y[n:], zero)])

        def dop(rtol):
            t0 = time.perf_counter()
            s = solve_ivp(f, (0.0, p.T), y0, method="DOP853", rtol=rtol, atol=rtol)
            wall = time.perf_counter() - t0
            return dict(ok=s.success, time=wall, q=s.y[:n, -1], rhs=s.nfev, message=s.message)

        def lsoda(rtol):
            t0 = time.perf_counter()
            y, info = odeint(lambda y, t: f(t, y), y0, [0.0, p.T], rtol=rtol, atol=rtol, full_output=True,
                             mxstep=10 ** 7)
            wall = time.perf_counter() - t0
            return dict(ok=info["message"].startswith("Integration successful"), time=wall, q=y[-1, :n],
                        rhs=int(info["nfe"][-1]), message=info["message"])

        res["runs"].setdefault(p.name, {})["scipy DOP853 + pin.aba"] = sweep.run(p, rtols, dop, "scipy DOP853")
        res["runs"][p.name]["scipy LSODA + pin.aba"] = sweep.run(p, rtols, lsoda, "scipy LSODA (odeint)")


def run_scipy_loop(p, sweep, rtols, res):
    """The four-bar: pin.constraintDynamics (fourbar_geometry.pin_loop) as the right-hand side of
    solve_ivp(method="DOP853"); the loop drift at T is recorded beside the error."""
    import pinocchio as pin
    from scipy.integrate import solve_ivp
    print("scipy + pinocchio constraintDynamics:", p.title, flush=True)
    model, loops, prox = fourbar_geometry.pin_loop()
    data = model.createData()
    datas = pin.StdVec_RigidConstraintData()
    for c in loops:
        datas.append(c.createData())
    pin.initConstraintDynamics(model, data, loops, datas)
    n = model.nv
    zero = np.zeros(n)
    y0 = np.concatenate(P.fourbar_start(p))

    def f(t, y):
        return np.concatenate([y[n:], pin.constraintDynamics(model, data, y[:n], y[n:], zero, loops, datas, prox)])

    def dop(rtol):
        t0 = time.perf_counter()
        s = solve_ivp(f, (0.0, p.T), y0, method="DOP853", rtol=rtol, atol=rtol)
        wall = time.perf_counter() - t0
        gap, vgap = fourbar_geometry.loop_gap(s.y[:n, -1], s.y[n:, -1])
        return dict(ok=s.success, time=wall, q=s.y[:n, -1], rhs=s.nfev, gap=gap, vgap=vgap, message=s.message)

    res["runs"].setdefault(p.name, {})[PIN_LOOP_SCIPY] = sweep.run(p, rtols, dop, PIN_LOOP_SCIPY)


# --------------------------------------------------------------------------- MuJoCo
def run_mujoco(args, problems, sweep, res):
    import mujoco
    kinds = (("Euler", mujoco.mjtIntegrator.mjINT_EULER), ("implicitfast", mujoco.mjtIntegrator.mjINT_IMPLICITFAST),
             ("RK4", mujoco.mjtIntegrator.mjINT_RK4))
    os.makedirs(os.path.join(BENCH, "results", "mjcf"), exist_ok=True)
    for p in problems:
        print("mujoco:", p.title, flush=True)
        if p.kind == "fourbar":
            text = P.mjcf_fourbar(p)
            q0, u0 = P.fourbar_start(p)
        elif p.kind == "disk":
            text = P.mjcf_disk(p)
            q0, u0 = P.disk_start()
        else:
            text = mjcf(p)
            q0, u0 = [p.q0] * p.n, [0.0] * p.n
        with open(os.path.join(BENCH, "results", "mjcf", p.name.split("_T")[0] + ".xml"), "w") as fh:
            fh.write(text + "\n")
        variants = [("", text)]
        if p.kind == "fourbar":  # MuJoCo's default (soft) loop and a stiff one
            variants.append((" stiff loop", P.mjcf_fourbar(p, **P.MJ_STIFF_LOOP)))
        for suffix, text in variants:
            run_mujoco_model(p, sweep, res, kinds, text, q0, u0, suffix)


def run_mujoco_model(p, sweep, res, kinds, text, q0, u0, suffix):
    import mujoco
    t0 = time.perf_counter()
    m = mujoco.MjModel.from_xml_string(text)
    load = time.perf_counter() - t0
    d = mujoco.MjData(m)
    for name, integ in kinds:
        m.opt.integrator = integ

        def step(dt):
            m.opt.timestep = dt
            nstep = int(round(p.T / dt))
            mujoco.mj_resetData(m, d)
            d.qpos[:] = q0
            d.qvel[:] = u0
            t0 = time.perf_counter()
            mujoco.mj_step(m, d, nstep)
            wall = time.perf_counter() - t0
            ok = bool(np.all(np.isfinite(d.qpos)))
            return dict(ok=ok, time=wall, q=d.qpos.copy(), steps=nstep, load=load, message="non-finite state")

        label = "mujoco %s%s" % (name, suffix)
        res["runs"].setdefault(p.name, {})[label] = sweep.run(p, MJ_STEPS, step, label)


# --------------------------------------------------------------------------- baseline
def run_baseline(args, problems, sweep, rtols, res):
    """Not a peer: the references' own minimal-coordinate ODEs (the four-bar's one-DOF
    Lagrange equation, the disk's lean/heading/spin equations; bench/reference/) in double
    precision with SciPy DOP853, rtol = atol. What a hand derivation buys on these problems."""
    sys.path.insert(0, os.path.join(BENCH, "reference"))
    from scipy.integrate import solve_ivp
    for p in problems:
        if p.kind not in CONSTRAINED:
            continue
        print("baseline:", p.title, flush=True)
        if p.kind == "fourbar":
            import sympy as sp
            import fourbar as ref
            syms, acc, _, q_joint, _, _ = ref.derive()
            f_acc = sp.lambdify(syms, acc, modules="math", cse=True)
            f_q = sp.lambdify(syms, q_joint, modules="math")
            f = lambda t, y: [y[1], f_acc(y[0], y[1])]  # noqa: E731
            y0 = [float(ref.THETA0), float(ref.OMEGA0)]
            to_q = lambda y: f_q(y[0], y[1])  # noqa: E731
        else:
            import rolling_disk as ref
            f = lambda t, y: ref.rhs(y, np)  # noqa: E731
            y0 = ref.start(ref.LEAN_RATE, np)[0]
            to_q = lambda y: ref.kanesim_q(y, np)  # noqa: E731

        def dop(rtol):
            t0 = time.perf_counter()
            r = solve_ivp(f, (0.0, p.T), y0, method="DOP853", rtol=rtol, atol=rtol)
            wall = time.perf_counter() - t0
            return dict(ok=r.success, time=wall, q=to_q(r.y[:, -1]), rhs=r.nfev, message=r.message)

        label = "baseline: minimal ODE + SciPy DOP853"
        res["runs"].setdefault(p.name, {})[label] = sweep.run(p, rtols, dop, label)


# --------------------------------------------------------------------------- Exudyn
def run_exudyn(args, problems, sweep, rtols, res):
    import exudyn_tree
    import exudyn_constrained
    for p in problems:
        print("exudyn:", p.title, flush=True)
        if p.kind in CONSTRAINED:
            runner = exudyn_constrained.runner(p)
            label = "exudyn %s gen-alpha (fixed step)" % ("Revolute2D" if p.kind == "fourbar" else "RollingDisc")
            res["runs"].setdefault(p.name, {})[label] = sweep.run(p, exudyn_constrained.STEPS, runner.run, label)
            continue
        try:
            runner = exudyn_tree.Runner(p)
        except Exception as e:  # report, do not stop the benchmark
            res["notes"].append("exudyn on %s: %s" % (p.name, e))
            print("  exudyn failed to build:", e)
            continue
        res["runs"].setdefault(p.name, {})["exudyn KinematicTree DOPRI5"] = sweep.run(
            p, rtols, runner.run, "exudyn DOPRI5")


# --------------------------------------------------------------------------- sympy vs kanesim compile
def run_sympy(args, res, quick):
    import sympy_kane
    ns = [1, 2, 3, 4] if quick else [1, 2, 3, 4, 5, 6, 8]
    mech = os.path.join(BENCH, "models", "planar_chain.mech")
    rows = []
    for n in ns:
        ts = sympy_kane.derive_time(n)
        times = []
        for k in range(3):
            pr = subprocess.run([args.kanesim, "run", mech, "--set", "N=%d" % n, "--stop-time", "0.001",
                                 "--interval", "0.001", "--stats", "-o", os.devnull],
                                capture_output=True, text=True, timeout=60)
            lo = float(re.search(r"load \+ elaborate\s+([0-9.eE+-]+)", pr.stderr).group(1))
            co = float(re.search(r"compile\s+([0-9.eE+-]+)", pr.stderr).group(1))
            times.append((lo, co))
        lo = statistics.median(t[0] for t in times)
        co = statistics.median(t[1] for t in times)
        rows.append(dict(n=n, sympy_derive=ts["derive"], sympy_total=ts["total"], kanesim_load=lo,
                         kanesim_compile=co))
        print("  N=%d sympy derive %.3g s (with lambdify %.3g s)  kanesim load %.3g s compile %.3g s"
              % (n, ts["derive"], ts["total"], lo, co), flush=True)
        if ts["total"] > (20 if not quick else 5):
            break
    res["sympy"] = rows


# --------------------------------------------------------------------------- RHS cost vs N
def run_rhs(args, res, quick):
    ns = [5, 10, 20, 50, 100] if quick else [5, 10, 20, 30, 40, 50, 60, 80, 100, 200, 500, 1000]
    pin = {}
    for n in ns:
        pr = subprocess.run([args.pin_driver, "rhs", str(n), "5"], capture_output=True, text=True, timeout=300)
        if pr.returncode != 0:  # N = 1000 was killed (memory) on the 2-core machine
            res["notes"].append("pin_driver rhs %d failed (exit %d)" % (n, pr.returncode))
            continue
        kv = dict(tok.split("=") for tok in pr.stdout.split())
        pin[n] = dict(wall_ns=float(kv["wall_ns"]), cpu_ns=float(kv["cpu_ns"]))
        print("  pinocchio aba N=%d  %.0f ns cpu" % (n, pin[n]["cpu_ns"]), flush=True)
    kane = {}
    if args.rhs_bench and os.path.exists(args.rhs_bench):
        filt = "BM_Rhs(Recursive|Dense|Sparse)/(%s)$" % "|".join(str(n) for n in ns)
        out = os.path.join(tempfile.mkdtemp(), "rhs.json")
        subprocess.run([args.rhs_bench, "--benchmark_filter=" + filt, "--benchmark_min_time=%s" %
                        ("0.05" if quick else "0.2"), "--benchmark_out=" + out, "--benchmark_out_format=json"],
                       capture_output=True, text=True, timeout=900)
        with open(out) as fh:
            for b in json.load(fh)["benchmarks"]:
                m = re.match(r"BM_Rhs(Recursive|Dense|Sparse)/(\d+)$", b["name"])
                if m:
                    unit = {"ns": 1.0, "us": 1e3, "ms": 1e6}[b["time_unit"]]
                    kane.setdefault(int(m.group(2)), {})[m.group(1).lower()] = dict(
                        wall_ns=b["real_time"] * unit, cpu_ns=b["cpu_time"] * unit)
    res["rhs"] = dict(pinocchio=pin, kanesim=kane)


def machine_info():
    info = dict(platform=platform.platform(), python=platform.python_version())
    try:
        with open("/proc/cpuinfo") as fh:
            info["cpu"] = re.search(r"model name\s*:\s*(.*)", fh.read()).group(1)
    except Exception:
        pass
    info["cores"] = os.cpu_count()
    info["loadavg_start"] = os.getloadavg()
    vers = {}
    for mod in ("numpy", "scipy", "sympy", "pinocchio", "mujoco", "exudyn", "matplotlib"):
        try:
            vers[mod] = __import__(mod).__version__
        except Exception as e:
            vers[mod] = "unavailable (%s)" % e
    info["versions"] = vers
    info["gxx"] = subprocess.run(["g++", "--version"], capture_output=True, text=True).stdout.split("\n")[0]
    try:
        sund = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "libsundials-dev"], capture_output=True,
                              text=True).stdout
        info["sundials"] = sund
    except Exception:
        pass
    # KANESIM_COMMIT: say which source the kanesim binary was built from when it is not HEAD
    info["kanesim_commit"] = os.environ.get("KANESIM_COMMIT") or subprocess.run(
        ["git", "-C", ROOT, "rev-parse", "--short", "HEAD"], capture_output=True, text=True).stdout.strip()
    return info


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--kanesim", required=True)
    ap.add_argument("--pin-driver", required=True)
    ap.add_argument("--kanesim-driver", default="",
                    help="bench/kanesim_driver: time kanesim in process as pin_driver times Pinocchio "
                         "(default: `kanesim run`, one cold integration per process)")
    ap.add_argument("--rhs-bench", default="")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--only", default="kanesim,pin,scipy,mujoco,exudyn,baseline,sympy,rhs")
    ap.add_argument("--problems", default="", help="comma-separated name prefixes (default: all)")
    ap.add_argument("--out", default=os.path.join(BENCH, "results", "results.json"))
    args = ap.parse_args()
    parts = args.only.split(",")
    problems = all_problems(args.quick, args.problems.split(",") if args.problems else None)
    partial = args.only != ap.get_default("only") or bool(args.problems)
    rtols = RTOLS_QUICK if args.quick else RTOLS
    fine = RTOLS_QUICK if args.quick else RTOLS_FINE
    pin_rtols = RTOLS_QUICK + [1e-13] if args.quick else PIN_RTOLS_FINE
    sweep = Sweep(reps=1 if args.quick else 3, budget=1.0 if args.quick else 4.0)
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    res = dict(machine=machine_info(), quick=args.quick, runs={}, notes=[],
               problems={p.name: dict(title=p.title, T=p.T, n=p.n, kind=p.kind, trust_floor=p.trust_floor(),
                                      ref=os.path.relpath(p.ref_path(), ROOT)) for p in problems})
    if os.path.exists(args.out) and partial:
        with open(args.out) as fh:  # partial re-run: keep the other tools' and problems' numbers
            old = json.load(fh)
        new_problems = res["problems"]
        for k in ("runs", "retimed", "sympy", "rhs", "machine", "notes", "problems", "partial_runs"):
            if k in old:
                res[k] = old[k]
        res["problems"].update(new_problems)
        if args.problems:  # the selected problems' runs of the selected tools start afresh
            for p in problems:
                if "kanesim" in parts or "pin" in parts:  # re-timed pairs of stale points
                    res.get("retimed", {}).pop(p.name, None)
                for tool in list(res["runs"].get(p.name, {})):
                    tkey = "pin" if tool.startswith(("pinocchio", "scipy")) else tool.split()[0].rstrip(":")
                    if tkey in parts or (tkey == "pin" and "scipy" in parts):
                        del res["runs"][p.name][tool]
            if "pin" in parts:  # the "not run" notes are written again by run_pin_cpp
                res["notes"] = [n for n in res["notes"] if not any(n.startswith(p.name + ":") for p in problems)]
            if "rhs" in parts:  # run_rhs writes its notes again
                res["notes"] = [n for n in res["notes"] if not n.startswith("pin_driver rhs")]
        res["notes"].append("re-ran %s%s at load average %s" % (
            args.only, " on " + args.problems if args.problems else "", ", ".join("%.1f" % x for x in os.getloadavg())))
    if partial:
        res.setdefault("partial_runs", []).append(dict(
            only=args.only, problems=args.problems, loadavg_start=os.getloadavg(), machine=machine_info()))
    t_start = time.time()
    steps = [("kanesim", lambda: run_kanesim(args, problems, sweep, rtols, res, fine)),
             ("pin", lambda: run_pin_cpp(args, problems, sweep, res, pin_rtols)),
             ("scipy", lambda: run_scipy(args, problems, sweep, fine, res)),
             ("mujoco", lambda: run_mujoco(args, problems, sweep, res)),
             ("exudyn", lambda: run_exudyn(args, problems, sweep, rtols, res)),
             ("baseline", lambda: run_baseline(args, problems, sweep, rtols, res)),
             ("sympy", lambda: run_sympy(args, res, args.quick)),
             ("rhs", lambda: run_rhs(args, res, args.quick))]
    if "kanesim" in parts and "pin" in parts and args.kanesim_driver:
        # kanesim's DOP853 series and the Pinocchio C++ driver (the best peer on most rows)
        # side by side, tolerance by tolerance (PairedSweep): the machine is shared and its
        # speed drifts, so the two sides of a ratio are timed seconds apart. Then kanesim's
        # other integrators, problem by problem.
        secs = res.setdefault("phase_seconds", {})
        secs["kanesim+pin paired"] = secs["kanesim"] = 0.0
        for p in problems:
            t0 = time.time()
            run_paired(args, p, sweep, res, fine, pin_rtols)
            t1 = time.time()
            run_kanesim(args, [p], sweep, rtols, res, fine, skip_dop853=True)
            secs["kanesim+pin paired"] += t1 - t0
            secs["kanesim"] += time.time() - t1
            with open(args.out, "w") as fh:
                json.dump(res, fh, indent=1, default=float)
        parts = [x for x in parts if x not in ("kanesim", "pin")]
    for name, fn in steps:
        if name in parts:
            t0 = time.time()
            fn()
            res.setdefault("phase_seconds", {})[name] = time.time() - t0
            with open(args.out, "w") as fh:
                json.dump(res, fh, indent=1, default=float)
    if partial:
        res["partial_runs"][-1]["loadavg_end"] = os.getloadavg()
        res["partial_runs"][-1]["seconds"] = time.time() - t_start
    else:
        res["machine"]["loadavg_end"] = os.getloadavg()
        res["machine"]["total_seconds"] = time.time() - t_start
    with open(args.out, "w") as fh:
        json.dump(res, fh, indent=1, default=float)
    print("wrote", args.out)


if __name__ == "__main__":
    main()
