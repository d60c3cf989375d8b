#!/usr/bin/env python3
"""Overconstrained linkages over their whole motion (issue 38 §1; docs/benchmarks.md
"Overconstrained linkages"; docs/constraints.md "Redundant or singular").

Three linkages whose Gruebler count is below their mobility, every redundant row redundant at
every configuration (tests/stress/models/): the orthogonal Bricard 6R, the Bennett 4R and the
Sarrus linkage, each over 10 s, every integrator, both forms of the loop equations and rtol
1e-4 ... 1e-12. Per run: the outcome, the CPU time of `kanesim run` (user + system of the
child), the time reached, the energy error max |E - E0| / E0 over the rows (no friction), and
an error against something independent of kanesim:
  bricard  max |j1.q - reference| over the rows, the reference being the reduced
           one-coordinate model of bench/reference/bricard.py (energy integral by mpmath
           quadrature; tests/stress/data/bricard_ref.csv);
  bennett  Bennett's closed form (1914) tan(th1/2) tan(th2/2) = sin((b+a)/2) / sin((b-a)/2)
           for the twists a = alpha, b = beta, written bounded:
           |sin(th1/2) sin(th2/2) - K cos(th1/2) cos(th2/2)| / sqrt(1 + K^2), and th3 = -th1;
  sarrus   the plate's straight line: max over the rows of its mass centre's distance from
           the start's vertical line and of its rotation's deviation from the identity.

Outcomes: OK exit 0 to 10 s with the error and the energy error within min(3e4 rtol, 1e-2)
(tests/stress/overconstrained_test.cpp: 3e4 rtol, as the parallelogram tests); S exit 2 at
time t (said) with the rows before it within the bound; WRONG otherwise (exit 0 beyond the
bound is a silent wrong answer; exit 2 after rows beyond it too).

Usage: bench/overconstrained.py [KANESIM] [--models bricard,bennett,sarrus]
       [--rtol 1e-4,1e-6,...] [--integrator dop853,...] [--solver dense,sparse]
"""
import argparse
import bisect
import csv
import math
import os
import resource
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
MODELS = os.path.join(ROOT, "tests", "stress", "models")
REF = os.path.join(ROOT, "tests", "stress", "data", "bricard_ref.csv")

def read_csv(path):
    """Header and numeric rows of the CSV at `path` (none if the run wrote none); removed."""
    if not os.path.exists(path):
        return [], []
    with open(path, newline="") as f:
        lines = [r for r in csv.reader(f) if r]
    os.remove(path)
    if not lines:
        return [], []
    return lines[0], [[float(x) for x in r] for r in lines[1:]]


def run(kanesim, model, integ, solver, rtol, outputs):
    fd, out = tempfile.mkstemp(suffix=".csv")
    os.close(fd)
    args = [kanesim, "run", os.path.join(MODELS, model + ".mech"), "--integrator", integ, "--solver", solver,
            "--rtol", rtol, "-o", out]
    for o in outputs:
        args += ["--output", o]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    p = subprocess.run(args, capture_output=True, text=True)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    head, rows = read_csv(out)
    return p.returncode, cpu, head, rows, p.stderr.strip().splitlines()[-1:] or [""]


def column(head, rows, name):
    k = head.index(name)
    return [r[k] for r in rows]


def energy_error(head, rows):
    e = [a + b for a, b in zip(column(head, rows, "kinetic_energy"), column(head, rows, "potential_energy"))]
    return max(abs(x - e[0]) for x in e) / abs(e[0])


def bricard_error(head, rows, ref):
    t, x = column(head, rows, "time"), column(head, rows, "j1.q")
    err = 0.0
    for ti, xi in zip(t, x):
        k = bisect.bisect_left(ref[0], ti - 1e-9)
        if k < len(ref[0]) and abs(ref[0][k] - ti) < 1e-9:
            err = max(err, abs(math.remainder(xi - ref[1][k], 2 * math.pi)))
    return err


def bennett_error(head, rows, alpha=math.pi / 3, beta=2 * math.pi / 9):
    K = math.sin((beta + alpha) / 2) / math.sin((beta - alpha) / 2)
    th1, th2, th3 = column(head, rows, "j1.q"), column(head, rows, "j2.q"), column(head, rows, "j3.q")
    err = 0.0
    for a, b, c in zip(th1, th2, th3):
        rel = abs(math.sin(a / 2) * math.sin(b / 2) - K * math.cos(a / 2) * math.cos(b / 2)) / math.sqrt(1 + K * K)
        err = max(err, rel, abs(math.remainder(a + c, 2 * math.pi)))
    return err


def sarrus_error(head, rows):
    x, y = column(head, rows, "plate.r[1]"), column(head, rows, "plate.r[2]")
    err = max(max(abs(v - x[0]) for v in x), max(abs(v - y[0]) for v in y))
    for i, j in ((1, 1), (2, 2), (3, 3), (1, 2), (1, 3), (2, 3), (2, 1), (3, 1), (3, 2)):
        v = column(head, rows, "plate.R[%d,%d]" % (i, j))
        err = max(err, max(abs(r - (1.0 if i == j else 0.0)) for r in v))
    return err


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("kanesim", nargs="?", default=os.path.join(ROOT, "build", "cli", "kanesim"))
    ap.add_argument("--models", default="bricard,bennett,sarrus")
    ap.add_argument("--rtol", default="1e-4,1e-6,1e-8,1e-10,1e-12")
    ap.add_argument("--integrator", default="dop853,cvode,cvode-bdf,ida,arkode")
    ap.add_argument("--solver", default="dense,sparse")
    a = ap.parse_args()
    ref = [[], []]
    with open(REF) as f:
        next(f)
        for ln in f:
            t, x, _ = (float(v) for v in ln.split(","))
            ref[0].append(t)
            ref[1].append(x)
    outputs = {
        "bricard": ["j1.q", "j2.q", "kinetic_energy", "potential_energy"],
        "bennett": ["j1.q", "j2.q", "j3.q", "kinetic_energy", "potential_energy"],
        "sarrus": ["plate.r[1]", "plate.r[2]", "kinetic_energy", "potential_energy"] +
                  ["plate.R[%d,%d]" % (i, j) for i in (1, 2, 3) for j in (1, 2, 3)],
    }
    print("%-8s %-6s %-9s %-6s %-7s %6s %7s %9s %9s  %s" % ("model", "form", "integ", "rtol", "outcome", "t_end", "cpu_s",
                                                           "error", "energy", "message"))
    counts = {"OK": 0, "S": 0, "WRONG": 0}
    for model in a.models.split(","):
        for solver in a.solver.split(","):
            for integ in a.integrator.split(","):
                for rtol in a.rtol.split(","):
                    code, cpu, head, rows, msg = run(a.kanesim, model, integ, solver, rtol, outputs[model])
                    t_end = rows[-1][0] if rows else float("nan")
                    err = e_err = float("nan")
                    if rows:
                        e_err = energy_error(head, rows)
                        err = {"bricard": lambda: bricard_error(head, rows, ref), "bennett": lambda: bennett_error(head, rows),
                               "sarrus": lambda: sarrus_error(head, rows)}[model]()
                    r = float(rtol)
                    bound = min(3e4 * r, 1e-2)
                    within = err <= bound and e_err <= bound
                    if code == 0 and abs(t_end - 10) < 1e-9 and within:
                        outcome = "OK"
                    elif code == 2 and within:
                        outcome = "S"
                    else:
                        outcome = "WRONG"
                    counts[outcome] += 1
                    print("%-8s %-6s %-9s %-6s %-7s %6.3f %7.2f %9.2g %9.2g  %s" % (
                        model, solver, integ, rtol, outcome, t_end, cpu, err, e_err,
                        msg[0][:90] if code != 0 else ""), flush=True)
    print("OK %d, S %d, WRONG %d" % (counts["OK"], counts["S"], counts["WRONG"]))
    return 0 if counts["WRONG"] == 0 else 1


if __name__ == "__main__":
    sys.exit(main())
