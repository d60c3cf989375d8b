#!/usr/bin/env bash
# The FMU tests' client (tests/fmi, ctest's fmi.fmpy): FMPy from PyPI, the reference FMI
# master in Python, in its own venv $BUILD_DIR/fmpyvenv. The venv sees Debian's NumPy and
# pytest (--system-site-packages); FMPy brings the rest of what it needs. The venv also holds
# the other test-only tools from PyPI that every build's suite needs (the sanitizers' too):
# pint, the unit oracle of lang.units_against_pint (tests/lang/units_oracle.py).
# Usage: scripts/fmpy_venv.sh   (scripts/test.sh runs it; quiet when FMPy and pint are there)
set -euo pipefail
cd "$(dirname "$0")/.."
build_dir=${BUILD_DIR:-build}
venv="$build_dir/fmpyvenv"
fmpy_version=0.3.32  # the version the tests were written against
pint_version=0.25.3  # the oracle's version when its 430 strings were checked
python=/usr/bin/python3
[ -x "$python" ] || python=python3
[ -x "$venv/bin/python" ] || "$python" -m venv --system-site-packages "$venv"
if ! "$venv/bin/python" -c "import fmpy, sys; sys.exit(fmpy.__version__ != '$fmpy_version')" 2>/dev/null; then
  echo "fmpy_venv: pip install fmpy==$fmpy_version into $venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "fmpy==$fmpy_version"
fi
if ! "$venv/bin/python" -c "import pint, sys; sys.exit(pint.__version__ != '$pint_version')" 2>/dev/null; then
  echo "fmpy_venv: pip install pint==$pint_version into $venv"
  "$venv/bin/python" -m pip install --quiet --disable-pip-version-check "pint==$pint_version"
fi
