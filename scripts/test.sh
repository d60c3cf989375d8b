#!/usr/bin/env bash
# Builds kanesim and runs the whole test suite (the README's test command).
# Usage: scripts/test.sh [extra cmake -D options]
#   BUILD_DIR=build-asan scripts/test.sh -DKANESIM_SANITIZE=ON   (another build directory)
#   JOBS=2 scripts/test.sh                                         (parallelism; default: all cores)
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${BUILD_DIR:-build}
scripts/setup.sh test  # installs only what is missing (a no-op on a prepared machine)
jobs=${JOBS:-$(nproc)}
# The demo's configuration (scripts/configure.sh): after scripts/demo.sh nothing compiles twice;
# ccache also lets the pip build below reuse the objects.
scripts/configure.sh test "$build_dir" "$@"
cmake --build "$build_dir" -j"$jobs"
# `pip install .` into $build_dir/pyvenv (Debian's NumPy 1.x) and $build_dir/pyvenv-numpy2
# (the newest NumPy from PyPI) when this build has the Python module (not under the
# sanitizers); ctest's python.installed and python.installed_numpy2 run pytest on them.
if compgen -G "$build_dir/python/kanesim/_kanesim*.so" >/dev/null; then
  BUILD_DIR="$build_dir" scripts/pip_install.sh
fi
# FMPy for the FMU tests (tests/fmi) and pint for lang.units_against_pint, in $build_dir/fmpyvenv.
BUILD_DIR="$build_dir" scripts/fmpy_venv.sh
# KANESIM_CTEST_EXCLUDE: a regular expression of tests not to run (ctest -E; CI's sanitizer
# stage leaves out a few slow repeats of other tests' paths).
ctest --test-dir "$build_dir" --output-on-failure -j"$jobs" ${KANESIM_CTEST_EXCLUDE:+-E "$KANESIM_CTEST_EXCLUDE"}
