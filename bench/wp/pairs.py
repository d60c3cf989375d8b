#!/usr/bin/env python3
"""Many back-to-back pairs of the decisive points of a work-precision run.

run.py re-times each level's decisive kanesim DOP853 point and decisive Pinocchio C++ point
four times each (retime_decisive). Four rounds can all fall in one of the shared machine's
slow stretches, and in those kanesim's run slows by up to ~2.3x while Pinocchio's slows by
less (bench/README.md, "Timing rules"). This script answers "what is the ratio, usually?"
for chosen rows: it runs the same two driver calls (the same points, the same median of up
to 9 runs in process) PAIRS times, alternating which goes first, and prints the distribution
of the per-pair ratio kanesim / Pinocchio (median, 10th and 90th percentile, worst) and how
many pairs came out at or below 0.5.

    bench/.venv/bin/python bench/wp/pairs.py --kanesim-driver build-w/bench/kanesim_driver \\
        --pin-driver build-w/bench/pin_driver [--rows chain5_T1:1e-09,double_pendulum_T2:1e-06]
        [--pairs 100] [--budget 90] [--out bench/results/pairs.json]

--rows picks problem:level entries of results.json's "retimed" (default: the rows whose
re-timed ratio was above 0.5). Each row stops after PAIRS pairs or BUDGET seconds.
"""
import argparse
import json
import os
import statistics
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import run as R  # noqa: E402
from problems import BENCH, all_problems  # noqa: E402
from readings import retimed_ratio  # noqa: E402


def pick_rows(retimed, wanted):
    """[(problem, level, rec)] for the wanted rows, each decisive pair once."""
    out, seen = [], set()
    for prob, recs in retimed.items():
        for rec in recs:
            key = (prob, rec["kanesim"], rec["kanesim_param"], rec["peer"], rec["peer_param"])
            if key in seen:
                continue
            if wanted is None:
                r = retimed_ratio(rec)
                if r is None or r <= 0.5:
                    continue
            elif (prob, rec["level"]) not in wanted:
                continue
            seen.add(key)
            out.append((prob, rec["level"], rec))
    return out


def quantile(xs, q):
    s = sorted(xs)
    return s[min(len(s) - 1, int(q * len(s)))]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kanesim-driver", required=True)
    ap.add_argument("--pin-driver", required=True)
    ap.add_argument("--results", default=os.path.join(BENCH, "results", "results.json"))
    ap.add_argument("--rows", default="", help="problem:level,... (default: re-timed ratios above 0.5)")
    ap.add_argument("--pairs", type=int, default=100)
    ap.add_argument("--budget", type=float, default=90.0, help="seconds per row")
    ap.add_argument("--out", default="")
    args = ap.parse_args()

    with open(args.results) as fh:
        res = json.load(fh)
    wanted = None
    if args.rows:
        wanted = set()
        for item in args.rows.split(","):
            prob, lv = item.rsplit(":", 1)
            wanted.add((prob, float(lv)))
    problems = {p.name: p for p in all_problems()}
    rows = pick_rows(res.get("retimed", {}), wanted)
    if not rows:
        print("no rows to re-time", file=sys.stderr)
        return 1
    report = []
    print("| problem | error ≤ | pairs | run's re-timed ratio | median | 10th–90th percentile | worst | pairs ≤ 0.5 |")
    print("|---|---|---|---|---|---|---|---|")
    for prob, level, rec in rows:
        p = problems[prob]
        # The run functions of run.py's own series, by label (as retime_decisive takes them).
        sweep = R.Sweep(R.CPP_REPS, 0.0)
        fns = {x["label"]: x["fn"] for x in
               R.kanesim_dop853_series(args, p, sweep, []) + R.pin_cpp_series(args, p, sweep, [])}
        run_k = lambda: fns[rec["kanesim"]](rec["kanesim_param"])  # noqa: E731
        run_p = lambda: fns[rec["peer"]](rec["peer_param"])  # noqa: E731
        ratios, kt, pt = [], [], []
        start = time.time()
        for i in range(args.pairs):
            sides = ("k", "p") if i % 2 == 0 else ("p", "k")
            got = {side: (run_k if side == "k" else run_p)() for side in sides}
            if not (got["k"]["ok"] and got["p"]["ok"]):
                print("  pair %d failed: %s" % (i, got), file=sys.stderr)
                break
            kt.append(got["k"]["time"])
            pt.append(got["p"]["time"])
            ratios.append(kt[-1] / pt[-1])
            if time.time() - start > args.budget:
                break
        if not ratios:
            continue
        rec_out = dict(problem=prob, level=level, kanesim=rec["kanesim"], kanesim_param=rec["kanesim_param"],
                       peer=rec["peer"], peer_param=rec["peer_param"], run_ratio=retimed_ratio(rec),
                       kanesim_times=kt, peer_times=pt, ratios=ratios)
        report.append(rec_out)
        print("| %s | %g | %d | %.2f | %.3f | %.3f–%.3f | %.3f | %d of %d |" % (
            p.title, level, len(ratios), rec_out["run_ratio"], statistics.median(ratios),
            quantile(ratios, 0.1), quantile(ratios, 0.9), max(ratios),
            sum(r <= 0.5 for r in ratios), len(ratios)), flush=True)
    if args.out:
        with open(args.out, "w") as fh:
            json.dump(dict(machine=R.machine_info(), rows=report), fh, indent=1)
    return 0


if __name__ == "__main__":
    sys.exit(main())
