#!/usr/bin/env bash
# The FMU tests' client (tests/fmi, ctest's fmi.fmpy): FMPy from PyPI, the reference FMI
# master in Python, in its own venv $BUILD_DIR/fmpyvenv. The venv sees Debian's NumPy and
# pytest (--system-site-packages); FMPy brings the rest of what it needs.
# Usage: scripts/fmpy_venv.sh   (scripts/test.sh runs it; quiet when FMPy is there)
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${BUILD_DIR:-build}
venv="$build_dir/fmpyvenv"
fmpy_version=0.3.32  # the version the tests were written against
python=/usr/bin/python3
[ -x "$python" ] || python=python3
[ -x "$venv/bin/python" ] || "$python" -m venv --system-site-packages "$venv"
if ! "$venv/bin/python" -c "import fmpy, sys; sys.exit(fmpy.__version__ != '$fmpy_version')" 2>/dev/null; then
  echo "fmpy_venv: pip install fmpy==$fmpy_version into $venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "fmpy==$fmpy_version"
fi
