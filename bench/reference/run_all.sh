#!/bin/sh
# Regenerate every reference data file in tests/data/ (about 2-3 minutes).
#   sh bench/reference/run_all.sh
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
sh "$HERE/../setup_venv.sh"
PY="$HERE/../.venv/bin/python"
"$PY" "$HERE/double_pendulum.py"
"$PY" "$HERE/chain_pinocchio.py"
