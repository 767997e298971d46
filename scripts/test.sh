#!/usr/bin/env bash
# Runs every test (GoogleTest, the CLI end to end, the README examples, pytest with the browser
# check) via ctest.
# Expects scripts/setup.sh to have run (it builds ./build).
set -euo pipefail
cd "$(dirname "$0")/.."
cmake --build build
ctest --test-dir build --output-on-failure -j"$(nproc)"
