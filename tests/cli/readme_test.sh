#!/usr/bin/env bash
# Runs the README's examples as a newcomer would: the shell block under "## Use", in order, in an
# empty directory, then the Python block in the same directory with /usr/bin/python3.
#   readme_test.sh README.md            uses the trueaxis on PATH and the installed Python module
#   TRUEAXIS_BIN_DIR=... TRUEAXIS_PY=... readme_test.sh README.md
#                                       uses a build tree (ctest) instead
set -euo pipefail
readme=$(cd "$(dirname "$1")" && pwd)/$(basename "$1")
work=${2:-$(mktemp -d)}
rm -rf "$work"; mkdir -p "$work"; cd "$work"
[ -n "${TRUEAXIS_BIN_DIR:-}" ] && export PATH="$TRUEAXIS_BIN_DIR:$PATH"
[ -n "${TRUEAXIS_PY:-}" ] && export PYTHONPATH="$TRUEAXIS_PY"
# A fenced block that follows a marker line '<!-- example: shell -->' or '<!-- example: python -->'.
extract() {
  awk -v kind="$1" '
    $0 == "<!-- example: " kind " -->" { armed = 1; next }
    armed && /^```/ { if (inside) { inside = 0; armed = 0 } else inside = 1; next }
    inside { print }' "$readme"
}
extract shell > examples.sh
extract python > examples.py
[ -s examples.sh ] || { echo "README has no shell example block"; exit 1; }
[ -s examples.py ] || { echo "README has no python example block"; exit 1; }
echo "== $(grep -c '^trueaxis' examples.sh) shell examples from the README in $work"
n=0
while IFS= read -r line; do
  case "$line" in ''|'#'*) continue ;; esac
  n=$((n+1))
  echo "\$ $line"
  if ! bash -euo pipefail -c "$line" >example.out 2>example.err; then
    echo "FAIL: README example $n: $line"; cat example.out example.err; exit 1
  fi
done < examples.sh
echo "== the README's Python example"
/usr/bin/python3 examples.py
echo "readme: $((n+1)) passed, 0 failed"
