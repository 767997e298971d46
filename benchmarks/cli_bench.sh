#!/usr/bin/env bash
# CLI end to end on a 10^6-row probes CSV, against one awk pass summing a column of the same file,
# measured in the same run (issue 2, item 8b). Usage: benchmarks/cli_bench.sh [path/to/trueaxis]
set -euo pipefail
T=${1:-trueaxis}
D=$(mktemp -d)
trap 'rm -rf "$D"' EXIT
"$T" simulate straightness --stations 1000000 --step 0.01 --offsets 0,0.01,0.02 --noise 0.01 \
  -o "$D/p3.csv" --truth "$D/t3.csv" -q
"$T" simulate straightness --stations 1000000 --step 0.01 --offsets 0,0.01 --noise 0.01 \
  -o "$D/p2.csv" --truth "$D/t2.csv" -q
best() {  # best of 3 wall-clock seconds
  local b=1e9 t
  for _ in 1 2 3; do
    /usr/bin/time -f %e -o "$D/time" "$@" >/dev/null 2>&1
    t=$(tail -1 "$D/time")
    b=$(awk -v a="$b" -v c="$t" 'BEGIN{print (c<a)?c:a}')
  done
  echo "$b"
}
startup() {  # median wall-clock milliseconds of 21 runs
  local s e i
  for i in $(seq 21); do
    s=$EPOCHREALTIME; "$@" >/dev/null 2>&1; e=$EPOCHREALTIME
    awk -v a="$s" -v b="$e" 'BEGIN{printf "%.1f\n", (b - a) * 1e3}'
  done | sort -g | sed -n 11p
}
echo "start-up: trueaxis --version $(startup "$T" --version) ms, awk 'BEGIN{}' $(startup awk 'BEGIN{}') ms (medians of 21)"
awk_t=$(best awk -F, 'NR>1{s+=$2}END{print s}' "$D/p3.csv")
echo "file: $(du -m "$D/p3.csv" | cut -f1) MB; awk pass: ${awk_t} s"
for m in two-point three-point lsq; do
  f=$D/p3.csv; [ "$m" = two-point ] && f=$D/p2.csv
  t=$(best "$T" separate -i "$f" -m "$m" -o "$D/r.json" -q)
  echo "$m: ${t} s, ratio to awk $(awk -v a="$t" -v b="$awk_t" 'BEGIN{printf "%.2f", a/b}')"
done
