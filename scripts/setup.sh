#!/usr/bin/env bash
# Installs kanesim's build dependencies from Debian 12 packages (only what is missing).
# Usage: scripts/setup.sh            (as root, or with sudo available)
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config git
      libeigen3-dev libsundials-dev libsuitesparse-dev libassimp-dev
      libcli11-dev libfmt-dev libtomlplusplus-dev libgtest-dev libgmock-dev libbenchmark-dev
      libtinyxml2-dev             # the URDF importer (import/)
      clang-14 libclang-rt-14-dev libomp-14-dev python3 python3-venv
      openmpi-bin libopenmpi-dev  # OpenMPI: kanesim sweep --mpi (optional at build time)
      libcpp-httplib-dev          # the viewer's HTTP server (viz)
      libjs-three libjs-dygraphs  # the viewer page's libraries, read at run time
      chromium                    # the viewer's browser tests (headless, tests/viz)
      ccache                      # scripts/test.sh: the pip build reuses build/'s objects
      pybind11-dev python3-dev python3-numpy python3-pytest)  # the Python module (python/)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all dependencies present"
else
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# Test tools (not needed to build or run kanesim): the Khronos glTF validator, from npm at the
# version pinned in tests/tools/package-lock.json. Node and npm come from Debian (nodejs, npm)
# when the machine has none; without them the validator's test is skipped (tests/geometry).
tools="$(cd "$(dirname "$0")/.." && pwd)/tests/tools"
if ! command -v npm >/dev/null 2>&1; then
  echo "setup: installing nodejs npm (for the glTF validator test)"
  { $SUDO apt-get update -qq && $SUDO apt-get install -y -qq --no-install-recommends nodejs npm; } ||
    echo "setup: could not install npm; the glTF validator test will be skipped"
fi
if command -v npm >/dev/null 2>&1 && [ ! -d "$tools/node_modules/gltf-validator" ]; then
  echo "setup: npm ci in tests/tools (gltf-validator)"
  (cd "$tools" && npm ci --no-audit --no-fund --loglevel=error) ||
    echo "setup: npm ci failed; the glTF validator test will be skipped"
fi
