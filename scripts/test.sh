#!/usr/bin/env bash
# Builds kanesim and runs the whole test suite (the README's test command).
# Usage: scripts/test.sh [extra cmake -D options]
#   BUILD_DIR=build-asan scripts/test.sh -DKANESIM_SANITIZE=ON   (another build directory)
#   JOBS=2 scripts/test.sh                                         (parallelism; default: all cores)
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${BUILD_DIR:-build}
scripts/setup.sh  # installs only what is missing (a no-op on a prepared machine)
jobs=${JOBS:-$(nproc)}
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "$@"
cmake --build "$build_dir" -j"$jobs"
ctest --test-dir "$build_dir" --output-on-failure -j"$jobs"
