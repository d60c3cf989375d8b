#!/usr/bin/env bash
# The CMake configuration that scripts/demo.sh and scripts/test.sh share, so that the test
# command builds on the demo's build/ without compiling any object again: the same generator,
# build type and compiler launcher (ccache when present; scripts/setup.sh installs it).
# Usage: scripts/configure.sh demo|test BUILD_DIR [extra cmake -D options]
#   demo: the command and the modules it opens only (the test libraries may not be installed)
#   test: the tests and benchmarks too; every object the demo compiled keeps its command line
set -euo pipefail
cd "$(dirname "$0")/.."
case "${1:-}" in
  demo) targets=(-DKANESIM_BUILD_TESTS=OFF -DKANESIM_BUILD_BENCH=OFF) ;;
  test) targets=(-DKANESIM_BUILD_TESTS=ON -DKANESIM_BUILD_BENCH=ON) ;;
  *) echo "usage: scripts/configure.sh demo|test BUILD_DIR [cmake options]" >&2; exit 2 ;;
esac
build_dir=$2
shift 2
launcher=()
if command -v ccache >/dev/null 2>&1; then
  # The test programs' precompiled headers (tests/CMakeLists.txt) are cached only with this
  # sloppiness (ccache's manual, "Precompiled headers"); ccache 4.7 takes it from the
  # environment only.
  ccache_launcher="env;CCACHE_SLOPPINESS=pch_defines,time_macros;ccache"
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER="$ccache_launcher" -DCMAKE_CXX_COMPILER_LAUNCHER="$ccache_launcher")
fi
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "${targets[@]}" "$@"
