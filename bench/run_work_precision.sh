#!/bin/sh
# The work-precision benchmark of issue 6 in one command (see bench/README.md):
#   bench/run_work_precision.sh [--quick] [--only kanesim,pin,scipy,mujoco,exudyn,baseline,sympy,rhs]
#                               [--problems fourbar,rolling_disk]   (name prefixes)
# 1. bench/.venv (pinned packages), 2. kanesim Release build in $BUILD_DIR (default build-w),
# 3. the Pinocchio C++ driver against the pin wheel's headers, 4. missing chain, four-bar and
# rolling-disk references,
# 5. every run (bench/wp/run.py -> bench/results/results.json), 6. plots and tables
# (bench/wp/report.py -> docs/benchmarks/; --quick: bench/results/quick/). Full run ~16 min
# on 2 cores under load, --quick ~4-5 min including the build check.
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(dirname "$HERE")
BUILD_DIR=${BUILD_DIR:-$ROOT/build-w}
PY="$HERE/.venv/bin/python"

sh "$HERE/setup_venv.sh"

cmake -S "$ROOT" -B "$BUILD_DIR" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
cmake --build "$BUILD_DIR" -j2 --target kanesim kanesim_driver rhs_chain

# Pinocchio's aba is header-only C++ templates: compile the driver with the same -O3 as
# kanesim's Release build (no -march=native for either). The defines are those of the
# wheel's pinocchioTargets.cmake (boost::variant needs more than 20 joint types).
CMEEL=$("$PY" -c 'import cmeel, os; print(os.path.join(os.path.dirname(cmeel.__file__), "..", "cmeel.prefix"))' 2>/dev/null ||
        echo "$HERE/.venv/lib/python3.11/site-packages/cmeel.prefix")
PIN_DRIVER="$BUILD_DIR/bench/pin_driver"
TABLEAU="$ROOT/sim/dop853_tableau.h"  # shared with kanesim's own DOP853
CONTROL="$ROOT/sim/dop853_control.h"  # its step control, shared too
if [ ! -x "$PIN_DRIVER" ] || [ "$HERE/pin/pin_driver.cpp" -nt "$PIN_DRIVER" ] || [ "$TABLEAU" -nt "$PIN_DRIVER" ] || [ "$CONTROL" -nt "$PIN_DRIVER" ]; then
    echo "building $PIN_DRIVER"
    g++ -std=c++17 -O3 -DNDEBUG -DBOOST_MPL_LIMIT_LIST_SIZE=30 -DBOOST_MPL_LIMIT_VECTOR_SIZE=30 \
        -DBOOST_MPL_CFG_NO_PREPROCESSED_HEADERS -DBOOST_FUSION_INVOKE_MAX_ARITY=12 \
        -I"$CMEEL/include" -I/usr/include/eigen3 -I"$ROOT" "$HERE/pin/pin_driver.cpp" -o "$PIN_DRIVER"
fi

for n in 10 50 100; do
    if [ ! -f "$HERE/data/chain${n}_ref.csv" ]; then
        "$PY" "$HERE/wp/make_chain_refs.py" 10 50 100
        break
    fi
done
# The constrained problems' references (mpmath, ~2 min and ~1 min; bench/reference/README.md).
[ -f "$HERE/data/fourbar_ref.csv" ] || "$PY" "$HERE/reference/fourbar.py"
[ -f "$HERE/data/rolling_disk_ref.csv" ] || "$PY" "$HERE/reference/rolling_disk.py"

# --quick writes beside the committed full results, never over them.
RESULTS="$HERE/results/results.json"
DOCS="$ROOT/docs/benchmarks"
case " $* " in
  *" --quick "*) RESULTS="$HERE/results/quick/results.json"; DOCS="$HERE/results/quick" ;;
esac
"$PY" "$HERE/wp/run.py" --kanesim "$BUILD_DIR/cli/kanesim" --kanesim-driver "$BUILD_DIR/bench/kanesim_driver" \
    --pin-driver "$PIN_DRIVER" \
    --rhs-bench "$BUILD_DIR/bench/rhs_chain" --out "$RESULTS" "$@"
"$PY" "$HERE/wp/report.py" --results "$RESULTS" --out "$DOCS"
