#!/usr/bin/env bash
# The README's first command: installs the Debian packages that building and running kanesim
# needs (scripts/setup.sh build), builds the kanesim command (Release, in build/) and
# simulates the double pendulum into double_pendulum.csv, with its animation
# (double_pendulum.glb) and the viewer page (double_pendulum.html).
# Usage: scripts/demo.sh            (JOBS=N for parallelism, default 2)
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=${JOBS:-2}
scripts/setup.sh build
# The configuration scripts/test.sh uses too (it then compiles only what the demo did not);
# only the command and the modules it opens (meshes, the viewer's server) are built here.
scripts/configure.sh demo build
cmake --build build -j"$jobs" --target kanesim
build/cli/kanesim run examples/double_pendulum.mech -o double_pendulum.csv --animation double_pendulum.glb
build/cli/kanesim view examples/double_pendulum.mech --html double_pendulum.html
echo "demo: wrote double_pendulum.csv ($(($(wc -l < double_pendulum.csv) - 1)) rows); first rows:"
head -n 4 double_pendulum.csv
echo "demo: to see the motion, open double_pendulum.html in a browser (offline), load double_pendulum.glb"
echo "      in any glTF viewer, or run: build/cli/kanesim view examples/double_pendulum.mech"
