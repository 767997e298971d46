#!/usr/bin/env bash
# Runs every test, via ctest:
#  1. on the Release build that scripts/setup.sh built and installed (./build): the CLI end to end,
#     every README example, pytest with the report in headless Chromium, the repository's rules;
#  2. on one clang build with AddressSanitizer + UBSan (./build-san, which also holds the libFuzzer
#     targets of tests/fuzz/run.sh): the GoogleTest program (the records' tests on SQLite and on
#     a PostgreSQL server they start).
# The GoogleTest program is compiled only there, once: the library is compiled twice (the
# installed build and the checked one), the test program no longer in both.
# Expects scripts/setup.sh to have run. Installs clang and its sanitizer runtimes if missing.
set -euo pipefail
cd "$(dirname "$0")/.."
echo "== the Release build's tests"
# pandas is a test-only peer: the module takes DataFrames where it finds them, never needs them.
if ! /usr/bin/python3 -c "import pandas" 2>/dev/null; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    python3-pandas >/dev/null
fi
# The records' tests run on PostgreSQL too, on a server they start themselves (initdb, pg_ctl).
if ! ls /usr/lib/postgresql/*/bin/initdb >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    postgresql >/dev/null
fi
cmake --build build
ctest --test-dir build --output-on-failure -j"$(nproc)"
if ! command -v clang++ >/dev/null ||
  ! ls /usr/lib/llvm-*/lib/clang/*/lib/linux/libclang_rt.fuzzer-x86_64.a >/dev/null 2>&1; then
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO=sudo
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends \
    clang libclang-rt-14-dev >/dev/null
fi
echo "== at ${SECONDS} s: the AddressSanitizer + UBSan build (clang) and its tests"
TRUEAXIS_SAN_TARGETS="trueaxis_tests" bash tests/fuzz/run.sh 0
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  LSAN_OPTIONS=suppressions="$(pwd)/tests/lsan.supp":print_suppressions=0 \
  ctest --test-dir build-san --output-on-failure -j"$(nproc)"
echo "== all tests passed in ${SECONDS} s"
