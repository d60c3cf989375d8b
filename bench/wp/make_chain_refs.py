"""References for the chains the committed ones do not cover (N = 10, 50, 100), made the
same way as bench/reference/chain_pinocchio.py: Pinocchio's aba + SciPy DOP853 stepping
exactly onto each output time, the CSV from rtol = atol = 1e-13, its error estimated
against a 1e-14 run (SciPy raises rtol 1e-14 to 2.22e-14). As a check of this script,
N = 5 is recomputed and compared with the committed tests/data/chain5_ref.csv.

    bench/.venv/bin/python bench/wp/make_chain_refs.py [N ...]
Writes bench/data/chain<N>_ref.csv (t = 0, 0.5, ..., 5; columns as tests/data/chain5_ref.csv)
and bench/data/chain_refs.md (the measured self-consistency). ~1-2 min for 10, 50, 100.
"""
import os
import sys
import time

import numpy as np
import pinocchio as pin
from scipy.integrate import DOP853

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from problems import BENCH_DATA, TESTS_DATA, Problem, pin_model  # noqa: E402

TS = np.linspace(0.0, 5.0, 11)


def integrate(model, q0, tol):
    data = model.createData()
    n = model.nq
    zero = np.zeros(n)

    def f(t, y):
        return np.concatenate([y[n:], pin.aba(model, data, y[:n], y[n:], zero)])

    y = np.concatenate([np.full(n, q0), np.zeros(n)])
    out = [y.copy()]
    nfev = 0
    for a, b in zip(TS[:-1], TS[1:]):
        s = DOP853(f, a, y, b, rtol=tol, atol=tol)
        while s.status == "running":
            s.step()
        if s.status == "failed":
            raise RuntimeError("DOP853 failed")
        nfev += s.nfev
        y = s.y.copy()
        out.append(y.copy())
    return np.array(out), nfev


def main():
    ns = [int(a) for a in sys.argv[1:]] or [10, 50, 100]
    os.makedirs(BENCH_DATA, exist_ok=True)
    report = ["# Chain references for N = %s" % ", ".join(map(str, ns)), "",
              "Made by `bench/wp/make_chain_refs.py` (Pinocchio %s aba + SciPy DOP853, stepping onto "
              "t = 0, 0.5, ..., 5). CSV = the 1e-13 run; error estimate = |q(1e-13) - q(1e-14)|, "
              "max over joints." % pin.__version__, "",
              "| N | est. error q at t=1 | at t=3 | at t=5 | RHS evals (1e-13) | wall (s) |",
              "|---|---|---|---|---|---|"]
    for n in [5] + ns:
        p = Problem("chain", n, 5.0)
        model = pin_model(p)
        t0 = time.perf_counter()
        y13, nfev = integrate(model, p.q0, 1e-13)
        wall = time.perf_counter() - t0
        y14, _ = integrate(model, p.q0, 1e-14)
        est = np.max(np.abs(y13[:, :n] - y14[:, :n]), axis=1)
        if n == 5 and 5 not in ns:
            import csv
            with open(os.path.join(TESTS_DATA, "chain5_ref.csv")) as fh:
                rows = [r for r in csv.reader(fh)][1:]
            committed = {round(float(r[0]), 6): np.array([float(x) for x in r[1:6]]) for r in rows}
            d = [np.max(np.abs(committed[round(t, 6)] - y13[k, :5])) for k, t in enumerate(TS)]
            report.append("")
            line = ("Check: N = 5 recomputed here vs the committed tests/data/chain5_ref.csv: max |dq| "
                    "%.1e at t = 1, %.1e at t = 5." % (d[2], d[10]))
            print(line)
            report.insert(5, line)
            report.insert(6, "")
            continue
        path = os.path.join(BENCH_DATA, "chain%d_ref.csv" % n)
        head = ["time"] + ["j[%d].q" % i for i in range(1, n + 1)] + ["j[%d].u" % i for i in range(1, n + 1)]
        with open(path, "w") as fh:
            fh.write(",".join(head) + "\n")
            for t, y in zip(TS, y13):
                fh.write(",".join(["%.17g" % t] + ["%.17g" % v for v in y]) + "\n")
        row = "| %d | %.1e | %.1e | %.1e | %d | %.1f |" % (n, est[2], est[6], est[10], nfev, wall)
        print(row)
        report.append(row)
    report += ["", "Trust: as for the committed chains (bench/reference/README.md), the chains amplify "
               "initial errors by ~1e7 by t = 5 s, so q(5) is trustworthy only to about the estimate above "
               "(and never better than ~1e-9); q(1) to ~1e-12."]
    with open(os.path.join(BENCH_DATA, "chain_refs.md"), "w") as fh:
        fh.write("\n".join(report) + "\n")


if __name__ == "__main__":
    main()
