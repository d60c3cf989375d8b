#!/usr/bin/env bash
# Installs the Python module into a virtual environment with pip, reusing the objects of
# the CMake build in build/ through ccache (the README's test command runs it after that
# build; the python.installed test then runs pytest on what pip installed).
# Usage: scripts/pip_install.sh [VENV]     (default build/pyvenv; BUILD_DIR as scripts/test.sh)
# The venv sees the system's packages (--system-site-packages: NumPy, pytest and pandas from
# Debian). pip builds in build-py/ (pyproject.toml); with the compilers and compiler launcher
# of build/ the command lines are the same, so ccache serves every object build/ compiled.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${BUILD_DIR:-build}
venv=${1:-$build_dir/pyvenv}
python=/usr/bin/python3
[ -x "$python" ] || python=python3
[ -x "$venv/bin/python" ] || "$python" -m venv --system-site-packages "$venv"
settings=()
cache_value() { sed -n "s/^$1:[A-Z]*=//p" "$build_dir/CMakeCache.txt" 2>/dev/null | head -1; }
for var in CMAKE_C_COMPILER CMAKE_CXX_COMPILER CMAKE_C_COMPILER_LAUNCHER CMAKE_CXX_COMPILER_LAUNCHER; do
  value=$(cache_value "$var")
  [ -n "$value" ] && settings+=("--config-settings=cmake.define.$var=$value")
done
start=$SECONDS
"$venv/bin/python" -m pip install --quiet --disable-pip-version-check "${settings[@]}" .
echo "pip_install: kanesim installed into $venv in $((SECONDS - start)) s"
