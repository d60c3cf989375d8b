#!/usr/bin/env python3
"""Random stress sweeps of models with events (issue 41): the sweeps that found the folded
chain's cascade, the tossed cubes' missed landings and the friction chain's hang and energy
gains (docs/events.md). Each trial draws a model's parameters, runs every integrator at
rtol 1e-8 and reports what must not happen:

  FAIL     exit code other than 0 (with the last line of stderr)
  TIMEOUT  a run longer than --timeout seconds
  ERISE    (e < 1, or friction) the energy T + V rising between two rows by more than
           1e-7 max(1, |E|); "instant" is the largest rise across an event (two rows at
           one time), which no impact may have; a rise between rows is integration error
  EDRIFT   (chain, e = 1, no friction) the energy's change over the run beyond 1e-5
  STOPVIOL (chain, friction) an output row with a joint past its end stop: j[k].q outside
           [-bend, bend] by more than 1e-9 (an impact missed, a silent wrong answer)
  NOTFLAT, SPIN  (cube) not at rest flat on a face after 4 s (e < 0.8), or the vertical
           spin changed (the frictionless floor cannot change it)

    python3 bench/event_sweeps.py chain|cube|friction SEED TRIALS [--kanesim BUILD/cli/kanesim]

The models: bench/models/stop_chain.mech, tests/stress/models/tossed_cube.mech,
tests/stress/models/friction_stop_chain.mech. Prints "bad N" (FAIL + TIMEOUT + STOPVIOL) at
the end.
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
}


def draw(kind, rng):
    """One trial's parameters (--set NAME=VALUE), by kind."""
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
    a = ap.parse_args()
    rng = random.Random(a.seed)
    model = os.path.join(ROOT, MODELS[a.kind])
    integrators = ["dop853", "cvode", "ida", "arkode"] if a.kind == "cube" else \
        ["dop853", "cvode", "cvode-bdf", "ida", "arkode"]
    stop = "4" if a.kind == "cube" else "3"
    if a.kind == "cube":
        outputs = ["free.q[2]", "free.frame_b.w[2]"]
    else:
        outputs = ["kinetic_energy", "potential_energy"]
    stop_tol = 1e-9  # a row's joint past its stop by more than this: an impact was missed
    bad = 0
    out = os.path.join(tempfile.gettempdir(), "event_sweeps_%d.csv" % os.getpid())
    for trial in range(a.trials):
        p, starts = draw(a.kind, rng)
        sets = sum([["--set", f"{k}={v!r}"] for k, v in {**p, **starts}.items()], [])
        stopped = [] if a.kind == "cube" else ["j[%d].q" % k for k in range(1, p["N"])]
        for how in integrators:
            cmd = [a.kanesim, "run", model, "--integrator", how, "--stop-time", stop, "--rtol", "1e-8", "-o", out]
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
            worst = max([(abs(float(x[c])) - p["bend"], c, float(x["time"])) for x in rows for c in stopped]
                        or [(0.0, "", 0.0)])
            if worst[0] > stop_tol:
                print("STOPVIOL", trial, how, worst[1], "past its stop by", worst[0], "at t", worst[2], p, starts,
                      flush=True)
                bad += 1
            E = [float(x["kinetic_energy"]) + float(x["potential_energy"]) for x in rows]
            scale = max(1.0, max(abs(x) for x in E))
            rise = max(E[i + 1] - E[i] for i in range(len(E) - 1))
            instant = max([E[i + 1] - E[i] for i in range(len(E) - 1) if t[i + 1] == t[i]] or [0.0])
            if (p["e"] < 1 or a.kind == "friction") and rise > 1e-7 * scale:
                print("ERISE", trial, how, rise, "instant", instant, p, starts, flush=True)
            if a.kind == "chain" and p["e"] == 1 and abs(E[-1] - E[0]) > 1e-5 * scale:
                print("EDRIFT", trial, how, E[-1] - E[0], p, starts, flush=True)
    if os.path.exists(out):
        os.remove(out)
    print("bad", bad)


if __name__ == "__main__":
    main()
