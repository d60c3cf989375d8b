#!/bin/sh
# Regenerate every reference data file in tests/data/ and the four-bar and rolling-disk
# references in bench/data/ (about 5-6 minutes).
#   sh bench/reference/run_all.sh
set -eu
HERE=$(cd "$(dirname "$0")" && pwd)
sh "$HERE/../setup_venv.sh"
PY="$HERE/../.venv/bin/python"
"$PY" "$HERE/double_pendulum.py"
"$PY" "$HERE/chain_pinocchio.py"
"$PY" "$HERE/fourbar.py"
"$PY" "$HERE/rolling_disk.py"
