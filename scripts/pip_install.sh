#!/usr/bin/env bash
# Builds the Python package the way docs/python.md installs it (`pip install .`: pip's
# isolated build with scikit-build-core and pybind11 >= 2.12 from PyPI, pyproject.toml)
# into one wheel, reusing the objects of the CMake build in build/ through ccache, and
# installs that wheel into the virtual environments ctest's python.installed* test:
#   $BUILD_DIR/pyvenv          sees Debian's packages (--system-site-packages): NumPy 1.x, pytest;
#                              pandas from PyPI for that NumPy
#   $BUILD_DIR/pyvenv-numpy2   sees none: the newest NumPy (2.x), pytest and pandas from PyPI
# Usage: scripts/pip_install.sh          both venvs (scripts/test.sh runs this)
#        scripts/pip_install.sh VENV     only VENV, made with --system-site-packages if new
# pip builds in build-py/; with the compilers and compiler launcher of build/ the command
# lines are the same, so ccache serves every object build/ compiled except the module's
# two sources, whose include path is pip's temporary build environment.
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${BUILD_DIR:-build}
python=/usr/bin/python3
[ -x "$python" ] || python=python3
pip_quiet=(--quiet --disable-pip-version-check)
start=$SECONDS

new_venv() {  # VENV [--system-site-packages]
  [ -x "$1/bin/python" ] || "$python" -m venv "${@:2}" "$1"
}

if [ $# -gt 0 ]; then
  venvs=("$1")
  new_venv "$1" --system-site-packages
else
  venvs=("$build_dir/pyvenv" "$build_dir/pyvenv-numpy2")
  new_venv "$build_dir/pyvenv" --system-site-packages
  new_venv "$build_dir/pyvenv-numpy2"
fi

settings=()
cache_value() { sed -n "s/^$1:[A-Z]*=//p" "$build_dir/CMakeCache.txt" 2>/dev/null | head -1; }
for var in CMAKE_C_COMPILER CMAKE_CXX_COMPILER CMAKE_C_COMPILER_LAUNCHER CMAKE_CXX_COMPILER_LAUNCHER; do
  value=$(cache_value "$var")
  # The launcher's last word only (ccache): scripts/configure.sh's env CCACHE_SLOPPINESS=...
  # serves the test programs' precompiled headers, which pip does not build; ccache's keys
  # do not depend on it, so the objects build/ compiled still hit.
  [[ "$var" == *LAUNCHER ]] && value=${value##*;}
  [ -n "$value" ] && settings+=("--config-settings=cmake.define.$var=$value")
done

wheels="$build_dir/wheels"
rm -rf "$wheels"
"${venvs[0]}/bin/python" -m pip wheel "${pip_quiet[@]}" --no-deps "${settings[@]}" -w "$wheels" .
wheel=("$wheels"/kanesim-*.whl)
echo "pip_install: built ${wheel[0]##*/} in $((SECONDS - start)) s"
for venv in "${venvs[@]}"; do
  "$venv/bin/python" -m pip install "${pip_quiet[@]}" --force-reinstall --no-deps "${wheel[0]}"
done
if [ $# -gt 0 ]; then
  # The package's dependency (NumPy), without replacing one the venv already sees.
  "$1/bin/python" -m pip install "${pip_quiet[@]}" "${wheel[0]}"
else
  # What the tests need from PyPI: in the NumPy 2 venv the newest NumPy, pytest and pandas;
  # in Debian's a pandas built for its NumPy (held at Debian's version by a constraint).
  "$build_dir/pyvenv-numpy2/bin/python" -m pip install "${pip_quiet[@]}" --upgrade numpy pytest pandas
  held="$build_dir/pyvenv/numpy-constraint.txt"
  echo "numpy==$("$build_dir/pyvenv/bin/python" -c 'import numpy; print(numpy.__version__)')" > "$held"
  "$build_dir/pyvenv/bin/python" -m pip install "${pip_quiet[@]}" -c "$held" pandas
fi
for venv in "${venvs[@]}"; do
  echo "pip_install: $venv: kanesim with NumPy $("$venv/bin/python" -c 'import numpy; print(numpy.__version__)')"
done
echo "pip_install: done in $((SECONDS - start)) s"
