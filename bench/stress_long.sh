#!/bin/sh
# Long versions of the stress suite (tests/stress/), with numbers for docs/benchmarks.md:
#   - 5-link chain, 1000 s: energy drift per integrator and tolerance;
#   - the 1e8 N/m spring: IDA against CVODE-Adams and ARKODE (explicit): steps, RHS, wall time;
#   - the double pendulum at 10 s (beyond the predictability horizon): error vs rtol.
# Usage: bench/stress_long.sh [KANESIM]   (default build-w/cli/kanesim). ~3-5 min.
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(dirname "$HERE")
K=${1:-$ROOT/build-w/cli/kanesim}
PY="$HERE/.venv/bin/python"
[ -x "$PY" ] || PY=python3
TMP=$(mktemp -d)

echo "## Energy drift, examples/chain.mech N = 5, 1000 s (max |E - E0|, J)"
echo "| integrator | rtol | max abs(E - E0) | max T | wall (s) |"
echo "|---|---|---|---|---|"
for tol in 1e-6 1e-8 1e-10; do
  for it in ida cvode arkode; do
    s=$(date +%s.%N)
    "$K" run "$ROOT/examples/chain.mech" --set N=5 --stop-time 1000 --interval 10 --rtol $tol --integrator $it \
        --output kinetic_energy --output potential_energy -o "$TMP/e.csv"
    e=$(date +%s.%N)
    "$PY" - "$TMP/e.csv" "$it" "$tol" "$s" "$e" <<'PY'
import csv, sys
rows = list(csv.reader(open(sys.argv[1])))[1:]
E = [float(r[1]) + float(r[2]) for r in rows]
T = [float(r[1]) for r in rows]
print("| %s | %s | %.2e | %.1f | %.1f |" % (sys.argv[2], sys.argv[3], max(abs(x - E[0]) for x in E), max(T),
                                           float(sys.argv[5]) - float(sys.argv[4])))
PY
  done
done

echo
echo "## Stiff spring 1e8 N/m (tests/stress/models/stiff_spring.mech), 10 s, rtol 1e-6"
echo "| integrator | exit | steps | RHS (+ Jacobian RHS) | integrate (s) |"
echo "|---|---|---|---|---|"
for it in ida cvode-bdf cvode arkode; do
  rc=0
  timeout 300 "$K" run "$ROOT/tests/stress/models/stiff_spring.mech" --integrator $it --rtol 1e-6 --stats \
      -o "$TMP/s.csv" 2> "$TMP/s.err" || rc=$?
  steps=$(grep -E '^  steps' "$TMP/s.err" | awk '{print $2}')
  rhs=$(grep -E 'right-hand sides' "$TMP/s.err" | sed 's/.*sides *//')
  integ=$(grep -E '^  integrate' "$TMP/s.err" | awk '{print $2}')
  echo "| $it | $rc | ${steps:-—} | ${rhs:-—} | ${integ:-—} |"
done

echo
echo "## Double pendulum beyond its horizon: error of q at t = 10 s (reference: 40 digits)"
echo "| integrator | rtol 1e-6 | 1e-8 | 1e-10 | 1e-12 |"
echo "|---|---|---|---|---|"
for it in ida cvode arkode; do
  line="| $it |"
  for tol in 1e-6 1e-8 1e-10 1e-12; do
    "$K" run "$ROOT/examples/double_pendulum.mech" --integrator $it --rtol $tol --stop-time 10 --interval 10 \
        -o "$TMP/d.csv"
    err=$("$PY" - "$TMP/d.csv" "$ROOT/tests/data/double_pendulum_ref.csv" <<'PY'
import csv, sys
out = list(csv.reader(open(sys.argv[1])))
ref = list(csv.reader(open(sys.argv[2])))
h, last = out[0], out[-1]
rh, rl = ref[0], ref[-1]
print("%.1e" % max(abs(float(last[h.index(n)]) - float(rl[rh.index(n)])) for n in ("shoulder.q", "elbow.q")))
PY
)
    line="$line $err |"
  done
  echo "$line"
done
rm -rf "$TMP"
