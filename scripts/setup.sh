#!/usr/bin/env bash
# Installs kanesim's build dependencies from Debian 12 packages (only what is missing).
# Usage: scripts/setup.sh            (as root, or with sudo available)
set -euo pipefail
pkgs=(build-essential cmake ninja-build pkg-config git
      libeigen3-dev libsundials-dev libsuitesparse-dev libassimp-dev
      libcli11-dev libfmt-dev libtomlplusplus-dev libgtest-dev libgmock-dev libbenchmark-dev
      clang-14 libclang-rt-14-dev libomp-14-dev python3 python3-venv
      openmpi-bin libopenmpi-dev)  # OpenMPI: kanesim sweep --mpi (optional at build time)
missing=()
for p in "${pkgs[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all dependencies present"
  exit 0
fi
echo "setup: installing ${missing[*]}"
SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
