#!/bin/sh
# Create bench/.venv with the pinned Python packages used by the reference
# scripts (bench/reference/) and the peer benchmarks.  Idempotent: re-running
# only installs what is missing or at the wrong version.
#
#   sh bench/setup_venv.sh          # from anywhere
#   bench/.venv/bin/python bench/reference/double_pendulum.py
set -eu

HERE=$(cd "$(dirname "$0")" && pwd)
VENV="$HERE/.venv"
PYTHON=${PYTHON:-python3}

if [ ! -x "$VENV/bin/python" ]; then
    "$PYTHON" -m venv "$VENV"
fi

# Versions checked with `pip index versions NAME` (Python 3.11). example-robot-data (the URDF
# robots of bench/reference/urdf_robots.py, issue 40) ships data only, no Python module. exudyn (the Exudyn
# peer of the work-precision benchmark) is 1.13.6. mpmath is 1.3.0,
# not the newest 1.4.x, because sympy 1.14 requires mpmath<1.4.
"$VENV/bin/python" -m pip install --quiet --disable-pip-version-check \
    numpy==2.4.6 \
    scipy==1.17.1 \
    mpmath==1.3.0 \
    sympy==1.14.0 \
    matplotlib==3.11.2 \
    pin==4.1.0 \
    mujoco==4.0.0 \
    exudyn==1.13.6 \
    example-robot-data==6.0.0

"$VENV/bin/python" - <<'PY'
import numpy, scipy, mpmath, sympy, matplotlib, pinocchio, mujoco, exudyn, sys
print("python", sys.version.split()[0])
for m in (numpy, scipy, mpmath, sympy, matplotlib, pinocchio, mujoco, exudyn):
    print(m.__name__, m.__version__)
PY
