#!/usr/bin/env bash
# The CMake configuration that scripts/demo.sh and scripts/test.sh share, so that the test
# command builds on the demo's build/ without compiling any object again: the same generator,
# build type and compiler launcher (ccache when present; scripts/setup.sh installs it).
# Usage: scripts/configure.sh BUILD_DIR [extra cmake -D options]
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=$1
shift
launcher=()
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
cmake -S . -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@"
