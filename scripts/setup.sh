#!/usr/bin/env bash
# Installs kanesim's Debian 12 packages, only those missing, in three nested sets:
#   scripts/setup.sh [build]   building and running kanesim (scripts/demo.sh)
#   scripts/setup.sh test      + what the test suite needs (scripts/test.sh)
#   scripts/setup.sh ci        + what .ci/run needs besides (clang for the fuzzers)
# As root, or with sudo available. Quiet when everything is there.
set -euo pipefail
cd "$(dirname "$0")/.."
set_name=${1:-build}
case "$set_name" in build | test | ci) ;; *) echo "usage: scripts/setup.sh [build|test|ci]" >&2; exit 2 ;; esac

build_pkgs=(g++ cmake ninja-build pkg-config ccache
            libeigen3-dev libsuitesparse-dev libassimp-dev
            libcli11-dev libfmt-dev libtomlplusplus-dev
            libexpat1-dev               # the URDF importer's XML parser, static (import/)
            libminizip-dev              # zipping FMUs (kanesim export, fmi/)
            libcpp-httplib-dev          # the viewer's HTTP server (viz/)
            libjs-three libjs-dygraphs) # the viewer page's libraries, read at run time
test_pkgs=(build-essential git python3 python3-venv
           libgtest-dev libgmock-dev libbenchmark-dev
           openmpi-bin libopenmpi-dev  # kanesim sweep --mpi and its tests
           chromium                    # the viewer's browser tests (headless, tests/viz)
           pybind11-dev python3-dev python3-numpy python3-pytest)  # the Python module (python/)
ci_pkgs=(clang-14 libclang-rt-14-dev libomp-14-dev)  # .ci/run's libFuzzer targets

pkgs=("${build_pkgs[@]}")
[ "$set_name" = build ] || pkgs+=("${test_pkgs[@]}")
[ "$set_name" = ci ] && pkgs+=("${ci_pkgs[@]}")

SUDO=""
[ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive
updated=""
apt_install() {  # PACKAGE...
  [ -n "$updated" ] || { $SUDO apt-get update -qq; updated=1; }
  $SUDO apt-get install -y -qq --no-install-recommends "$@" >/dev/null
}
installed() { dpkg-query -W -f='${Status}' "$1" 2>/dev/null | grep -q "install ok installed"; }

missing=()
for p in "${pkgs[@]}"; do installed "$p" || missing+=("$p"); done
if [ ${#missing[@]} -gt 0 ]; then
  echo "setup: installing ${missing[*]}"
  apt_install "${missing[@]}"
fi

# SUNDIALS: kanesim needs its headers, static archives and CMake files, all in libsundials-dev.
# That package also depends on PETSc, hypre, OpenMPI and gfortran (~190 packages, for
# SUNDIALS's parallel vectors, which kanesim does not use): installing them took longer than
# building kanesim. Where libsundials-dev is not installed, its files and those of the SUNDIALS
# libraries it names are unpacked into .deps/sundials (found by CMakeLists.txt), without them.
if ! installed libsundials-dev && ! compgen -G ".deps/sundials/usr/lib/*/cmake/sundials/SUNDIALSConfig.cmake" >/dev/null; then
  [ -n "$updated" ] || { $SUDO apt-get update -qq; updated=1; }
  sundials=(libsundials-dev $(apt-cache depends libsundials-dev | sed -n 's/^ *Depends: \(libsundials-.*\)/\1/p'))
  echo "setup: unpacking ${sundials[*]} into .deps/sundials"
  debs=$(mktemp -d)
  as_root=()
  [ "$(id -u)" -eq 0 ] && as_root=(-o APT::Sandbox::User=root)  # root: no _apt sandbox warning
  (cd "$debs" && apt-get download -qq "${as_root[@]}" "${sundials[@]}")
  rm -rf .deps/sundials.tmp && mkdir -p .deps/sundials.tmp
  for deb in "$debs"/*.deb; do dpkg-deb -x "$deb" .deps/sundials.tmp; done
  rm -rf "$debs" .deps/sundials && mv .deps/sundials.tmp .deps/sundials
fi

[ "$set_name" = build ] && exit 0

# Test tools (not needed to build or run kanesim): the Khronos glTF validator, from npm at the
# version pinned in tests/tools/package-lock.json. Node and npm come from Debian (nodejs, npm)
# when the machine has none; without them the validator's test is skipped (tests/geometry).
if ! command -v npm >/dev/null 2>&1; then
  echo "setup: installing nodejs npm (for the glTF validator test)"
  apt_install nodejs npm || echo "setup: could not install npm; the glTF validator test will be skipped"
fi
if command -v npm >/dev/null 2>&1 && [ ! -d tests/tools/node_modules/gltf-validator ]; then
  echo "setup: npm ci in tests/tools (gltf-validator)"
  (cd tests/tools && npm ci --no-audit --no-fund --loglevel=error) ||
    echo "setup: npm ci failed; the glTF validator test will be skipped"
fi
