#!/usr/bin/env bash
# Two builds of trueaxis_bench on the same benchmarks, run in turn so that the machine's slow and
# fast phases fall on both alike; prints, per benchmark and build, the minimum, first quartile and
# median real time over every repetition of every round (ms).
#   benchmarks/bench_ab.sh ROUNDS REPETITIONS FILTER path/to/bench-A path/to/bench-B
# e.g. benchmarks/bench_ab.sh 3 5 'MemcpyReadings|run/three_point$|lsq_3probes|LsqSolver' \
#        old/benchmarks/trueaxis_bench build/benchmarks/trueaxis_bench
set -euo pipefail
[ $# -eq 5 ] || { echo "usage: $0 ROUNDS REPETITIONS FILTER BENCH_A BENCH_B" >&2; exit 2; }
rounds=$1 reps=$2 filter=$3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for _ in $(seq "$rounds"); do
  for x in A B; do
    bin=$4
    [ $x = B ] && bin=$5
    "$bin" --benchmark_filter="$filter" --benchmark_repetitions="$reps" --benchmark_format=csv \
      2>/dev/null | grep '^"' | grep -v '_mean"\|_median"\|_stddev"\|_cv"' >>"$out/$x.csv" || true
  done
done
# name,iterations,real_time,cpu_time,time_unit,...: real time in ms whatever the unit.
for x in A B; do
  awk -F, -v x="$x" '
    { t = $3; u = $5; if (u == "ns") t /= 1e6; else if (u == "us") t /= 1e3; else if (u == "s") t *= 1e3
      gsub(/"/, "", $1); v[$1] = v[$1] " " t }
    END { for (k in v) print x, k, v[k] }' "$out/$x.csv"
done | sort -k2,2 -s | while read -r x name times; do
  sorted=$(printf '%s\n' $times | sort -g)
  n=$(printf '%s\n' "$sorted" | wc -l)
  pick() { printf '%s\n' "$sorted" | sed -n "$1p"; }
  printf '%s %-45s min %8.2f  p25 %8.2f  median %8.2f  (n=%d)\n' "$x" "$name" \
    "$(pick 1)" "$(pick $(((n + 3) / 4)))" "$(pick $(((n + 1) / 2)))" "$n"
done
