#!/usr/bin/env bash
# Two builds of trueaxis_bench on the same benchmarks, run in turn so that the machine's slow and
# fast phases fall on both alike; prints, per benchmark and build, the minimum, first quartile and
# median real time over every repetition of every round (ms).
#   benchmarks/bench_ab.sh ROUNDS REPETITIONS FILTER path/to/bench-A path/to/bench-B
# e.g. benchmarks/bench_ab.sh 3 5 'MemcpyReadings|run/three_point$|lsq_3probes|LsqSolver' \
#        old/benchmarks/trueaxis_bench build/benchmarks/trueaxis_bench
# The runs are read as JSON: Google Benchmark's CSV output aborts when the selected benchmarks do
# not all carry the same counters (a path's "segments", a scan's "sim_s_per_wall_s").
set -euo pipefail
[ $# -eq 5 ] || { echo "usage: $0 ROUNDS REPETITIONS FILTER BENCH_A BENCH_B" >&2; exit 2; }
rounds=$1 reps=$2 filter=$3
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
for r in $(seq "$rounds"); do
  for x in A B; do
    bin=$4
    [ $x = B ] && bin=$5
    if ! "$bin" --benchmark_filter="$filter" --benchmark_repetitions="$reps" \
        --benchmark_report_aggregates_only=false --benchmark_format=json \
        >"$out/$x.$r.json" 2>"$out/$x.$r.err"; then
      echo "$bin failed:" >&2; tail -5 "$out/$x.$r.err" >&2; exit 1
    fi
  done
done
/usr/bin/python3 - "$out" <<'PY'
import glob, json, os, sys
scale = {"ns": 1e-6, "us": 1e-3, "ms": 1.0, "s": 1e3}
times = {}
for path in sorted(glob.glob(os.path.join(sys.argv[1], "*.json"))):
    build = os.path.basename(path)[0]
    for b in json.load(open(path))["benchmarks"]:
        if b.get("run_type") == "aggregate" or "real_time" not in b:
            continue
        times.setdefault((b["name"], build), []).append(b["real_time"] * scale[b["time_unit"]])
for (name, build) in sorted(times, key=lambda k: (k[0], k[1])):
    t = sorted(times[(name, build)])
    n = len(t)
    print(f"{build} {name:<45} min {t[0]:8.2f}  p25 {t[(n + 3) // 4 - 1]:8.2f}  "
          f"median {t[(n + 1) // 2 - 1]:8.2f}  (n={n})")
PY
