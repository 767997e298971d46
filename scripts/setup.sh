#!/usr/bin/env bash
# Fresh Debian machine -> dependencies, build, install trueaxis (CLI + Python module for
# /usr/bin/python3), then run 'trueaxis demo'. Run from the repository root as root; as another
# user it asks sudo for the system steps.
set -euo pipefail
cd "$(dirname "$0")/.."
SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
if [ "${TRUEAXIS_SKIP_APT:-0}" != 1 ]; then
  $SUDO apt-get update -qq
  # Node.js is needed once, for the report's plotting library. Some machines carry a Node.js
  # build that bundles npm (and conflicts with Debian's npm package): install only what is missing.
  node_pkgs=""
  command -v node >/dev/null || node_pkgs+=" nodejs"
  command -v npm >/dev/null || node_pkgs+=" npm"
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    g++ cmake ninja-build git $node_pkgs \
    libeigen3-dev libcli11-dev nlohmann-json3-dev libfmt-dev libglpk-dev \
    libocct-data-exchange-dev libocct-modeling-algorithms-dev libtbb-dev \
    libgtest-dev libgmock-dev libbenchmark-dev \
    pybind11-dev python3-dev python3-numpy python3-pytest libasio-dev \
    libsqlite3-dev libsqlitecpp-dev libpqxx-dev \
    chromium gawk clang-format >/dev/null
fi
(cd web && npm ci --no-audit --no-fund --silent)
# The GoogleTest program is built by scripts/test.sh, under the sanitizers (build-san); the
# benchmarks are for developers (-DTRUEAXIS_BENCHMARKS=ON, see BENCHMARKS.md), not for the install.
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DTRUEAXIS_WERROR=ON -DCMAKE_INSTALL_PREFIX=/usr/local \
  -DTRUEAXIS_UNIT_TESTS=OFF -DTRUEAXIS_BENCHMARKS=OFF
cmake --build build
$SUDO cmake --install build
trueaxis demo
