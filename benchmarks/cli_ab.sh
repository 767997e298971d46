#!/usr/bin/env bash
# Two builds of the CLI on the same command, run in turn N times each so that the machine's slow
# and fast phases fall on both alike; prints each one's median and every run (wall-clock ms).
#   benchmarks/cli_ab.sh N path/to/trueaxis-A path/to/trueaxis-B -- ARGS...
# e.g. benchmarks/cli_ab.sh 9 old/trueaxis build/trueaxis -- separate -i p3.csv -m lsq -o r.json -q
set -euo pipefail
[ $# -ge 4 ] && [ "$4" = -- ] || { echo "usage: $0 N BIN_A BIN_B -- ARGS..." >&2; exit 2; }
n=$1 a=$2 b=$3
shift 4
ta=() tb=()
ms() { awk -v s="$1" -v e="$2" 'BEGIN{printf "%.1f", (e - s) * 1e3}'; }
for _ in $(seq "$n"); do
  s=$EPOCHREALTIME; "$a" "$@" >/dev/null 2>&1 || true; e=$EPOCHREALTIME; ta+=("$(ms "$s" "$e")")
  s=$EPOCHREALTIME; "$b" "$@" >/dev/null 2>&1 || true; e=$EPOCHREALTIME; tb+=("$(ms "$s" "$e")")
done
median() { printf '%s\n' "$@" | sort -g | awk '{v[NR] = $1} END{print v[int((NR + 1) / 2)]}'; }
echo "A $a: median $(median "${ta[@]}") ms (${ta[*]})"
echo "B $b: median $(median "${tb[@]}") ms (${tb[*]})"
