#!/usr/bin/env bash
# Builds the libFuzzer targets with clang (AddressSanitizer + UBSan) and runs each for a bounded
# time, seeded from the repository's data. Exits non-zero on any finding (crash, sanitizer
# report, uncaught exception, leak, time-out or memory blow-up of one input).
#   bash tests/fuzz/run.sh [SECONDS_PER_TARGET]   (default 30; 0: build only)
# The build (build-san) also holds the test suite under the same sanitizers: CI builds the
# targets named in TRUEAXIS_SAN_TARGETS with it (e.g. "trueaxis_tests trueaxis") and runs ctest
# there, so that the library is compiled once for both.
set -euo pipefail
cd "$(dirname "$0")/../.."
seconds=${1:-30}
build=build-san
# -g1: line tables for the sanitizers' stack traces, at a fraction of the compile time of -g.
cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O2 -g1 -DNDEBUG" -DTRUEAXIS_WERROR=ON \
  -DTRUEAXIS_FUZZ=ON -DTRUEAXIS_PYTHON=OFF -DTRUEAXIS_TESTS=ON -DTRUEAXIS_BENCHMARKS=OFF >/dev/null
# shellcheck disable=SC2086
cmake --build "$build" --target fuzz_csv fuzz_json fuzz_ds fuzz_moody fuzz_ippdme \
  ${TRUEAXIS_SAN_TARGETS:-}
[ "$seconds" = 0 ] && exit 0
corpus=$build/corpus
rm -rf "$corpus"; mkdir -p "$corpus"/{csv,json,ds,moody,ippdme}
cp examples/*.csv "$corpus/csv/"
printf 'x,a,b,c,angle\n0,1,2,3,4\n10,2,3,4,5\n20,3,4,5,6\n30,4,5,6,7\n' > "$corpus/csv/probes.csv"
printf 'x1,y1,z1,x2,y2,z2,nominal\n0,0,0,100,0,0,100\n' > "$corpus/csv/lengths.csv"
printf 's,a_dx,a_dy,b_dx,b_dy,c_dx,c_dy\n0,1,2,3,4,5,6\n10,1,2,3,4,5,6\n' > "$corpus/csv/spots.csv"
printf 'target_mm,cycle,direction,deviation_um,material_temp_c\n0,1,+,1,20.5\n50,1,+,2,20.5\n50,1,-,3,20.6\n0,1,-,0.5,20.6\n0,2,+,1.2,20.7\n' > "$corpus/csv/runs.csv"
printf 'sep=;\r\ntarget_mm;cycle;direction;deviation_um\r\n0;1;"+";1,5\r\n50,5;1;+;-2,25\r\n' > "$corpus/csv/runs_excel.csv"
printf '"x";"a";"b";"c";"angle"\n0;1,5;2;3;4\n10;2;3,25;4;5\n' > "$corpus/csv/probes_excel.csv"
printf 'target [m],Cycle,direction,deviation (\xc2\xb5m),air_temp [\xb0C]\n0,1,+,1,20\n0.05,1,+,2,20\n' > "$corpus/csv/runs_units.csv"
printf 'x [mm],a / nm,b_um,c (\xce\xbcm),angle [urad]\n0,1,2,3,4\n10,2,3,4,5\n20,3,4,5,6\n' > "$corpus/csv/probes_units.csv"
printf '0.000000 0.001380 -0.001723\n50.000000 0.002275 -0.000580\n' > "$corpus/csv/x.comp"
printf '%%_N_AX_EEC_INI\nCHANDATA(1)\n$AA_ENC_COMP[0,0,X1]=0.003 ; 3 um\n$AA_ENC_COMP[0,1,X1]=-0.001\n$AA_ENC_COMP_STEP[0,X1]=1.0\n$AA_ENC_COMP_MIN[0,X1]=0\n$AA_ENC_COMP_MAX[0,X1]=1.0\n$AA_ENC_COMP_IS_MODULO[0,X1]=0\nM17\n' > "$corpus/csv/x_lec.mpf"
printf 'BEGIN X.COM MM\nNR    AXISPOS         X               BACKLASH\n0     +0.0000         +0.0010         +0.0021\n1     +40.0000        +0.0011         -0.0019\n[END]\n' > "$corpus/csv/X.COM"
printf '%%\n(PITCH ERROR)\nN3620A1P1\nN3621A1P0\nN3622A1P2\nN3623A1P1\nN3624A1P10.0\nN10000P1\nN10001P-2\nN10002P3\n%%\n' > "$corpus/csv/pitch.txt"
printf 'HEADER::\r\nFile type : RTL\r\nTARGET DATA::\r\nFiletype : Linear\r\nTarget-count : 3\r\nTargets :\r\n 0.0 50.0 100.0\r\nRUNS::\r\nRun-count : 2\r\nDEVIATIONS::\r\nRun Target Data:\r\n1  1  0.5\r\n1  2  1.0\r\n1  3  1.5\r\n2  3  -0.5\r\n2  2  -1.0\r\n2  1  -1.5\r\n' > "$corpus/csv/runs.rtl"
printf 'direction,angle_deg,deviation_um\nccw,0,1\nccw,60,2\nccw,120,-1\nccw,180,0.5\nccw,240,1\nccw,300,-2\nccw,359,0\nccw,30,1\ncw,0,1\ncw,300,2\ncw,240,0\ncw,180,1\ncw,120,-1\ncw,60,0.5\ncw,10,1\ncw,90,0\n' > "$corpus/csv/trace.csv"
printf 't_s,deviation_um\n0,1\n0.1,2\n0.2,1\n0.3,0\n0.4,1\n0.5,2\n0.6,1\n0.7,0\n0,1\n0.1,2\n' > "$corpus/csv/series.csv"
printf '[JOINT_0]\nBACKLASH = 0.003\n[JOINT_1]\nBACKLASH = 0.005\n' > "$corpus/csv/backlash.ini"
printf 'MP710.0: +0.0030 ; X\nMP710.1: +0.0050\n' > "$corpus/csv/backlash.mp"
printf '%%\n(BACKLASH)\nN1851A1P3\nN1851A2P5\n%%\n' > "$corpus/csv/backlash_fanuc.txt"
printf '%%_N_BACKLASH_INI\n$MA_BACKLASH[0,AX1]=0.003\nM17\n' > "$corpus/csv/backlash_siemens.ini"
printf '%%_N_NC_CEC_INI\nCHANDATA(1)\n$AN_CEC[0,0]=0\n$AN_CEC[0,1]=0.001\n$AN_CEC_INPUT_AXIS[0]=(AX2)\n$AN_CEC_OUTPUT_AXIS[0]=(AX1)\n$AN_CEC_STEP[0]=100\n$AN_CEC_MIN[0]=0\n$AN_CEC_MAX[0]=100\n$AN_CEC_DIRECTION[0]=0\nM17\n' > "$corpus/csv/cec.ini"
printf 'time_s,reading_mm\n0,-5\n0.5,-5\n1,-5\n1.5,-2\n2,0.001\n2.5,0.001\n3,0.001\n3.5,0.0012\n4,5\n' > "$corpus/csv/log.csv"
# JSON: the first byte picks the reader (see json_fuzz.cpp).
for f in examples/*.json; do
  for r in 0 1 2 3 4 5 6 7 8; do printf "\\x$(printf %02x $r)" | cat - "$f" > "$corpus/json/$(basename "$f").$r"; done
done
printf '\x00{"chain": "FYXZ", "ranges": {"x": [0, 800], "y": [0, 600], "z": [0, 500]}, "errors": {"EXX": {"polynomial": [0, 10]}}}' > "$corpus/json/machine"
printf '\x09{"sections": [{"name": "s", "plane": {"origin": [0, 0, 0], "normal": [0, 0, 1]}, "closed": false, "curve": {"nurbs": {"degree": 2, "knots": [0, 0, 0, 1, 1, 1], "weights": [1, 0.7, 1], "control_points": [[0, 0, 0], [1, 1, 0], [2, 0, 0]]}}, "material": "left"}]}' > "$corpus/json/design"
printf '\x0a{"design": {"sections": [{"name": "s", "plane": {"origin": [0, 0, 0], "normal": [0, 0, 1]}, "closed": false, "curve": {"polyline": [[0, 0, 0], [10, 0, 0], [10, 5, 0]]}, "material": "left"}]}, "deviation": {"scale": 1.01, "rotation_deg": [0, 0, 1], "translation": [1, 0, 0], "bumps": [{"section": "s", "arc_mm": 5, "height_mm": 0.2, "width_mm": 4}], "noise_um": 1, "seed": 3}}' > "$corpus/json/part"
printf '\x0b{"kind": "positioning", "standard": "ISO 230-2:2014", "A": 3, "B": null, "cycles": 2, "targets": [{"position": 0, "n_up": 2, "mean_up": 1, "s_up": 0.5}, {"position": 50, "n_up": 2, "mean_up": 2, "s_up": 0.1}], "temperature": {"material": [20, 21], "air": null, "corrected": true, "reference": 20, "expansion_coefficient": 1.15e-05, "datum_mm": 0, "max_correction_um": 0.5}, "tolerances": {"A": {"limit": 5, "value": 3, "pass": true}}, "warnings": ["w"], "readings": {"target_mm": [0, 50, 0, 50], "cycle": [1, 1, 2, 2], "direction": "++++", "deviation_um": [1, 2, 1, 2]}}' > "$corpus/json/positioning"
printf '\x0c{"kind": "circular", "plane": "XY", "radius_mm": 100, "feed_mm_per_min": 1000, "G_um": {"ccw": 3}, "F_um": {"ccw": {"min": -1, "max": 2}}, "H_um": null, "diagnosis": {"reversal_delay_deg": {"X": 0.2, "Y": 0.3}}, "trace": {"direction": ["ccw", "ccw"], "angle_deg": [0, 180], "deviation_um": [1, 2], "model_um": [1, 2]}}' > "$corpus/json/circular"
printf '\x0d{"X": {"gain_per_s": 30, "backlash_um": 3, "spike_um": 4, "spike_decay_deg": 5, "cyclic_um": 0.5, "pitch_mm": 10}}' > "$corpus/json/servo"
printf '\x0e{"kind": "circular compensation", "plane": "XY", "backlash_um": {"X": {"value": 3}, "Y": {"value": 5}}, "squareness_um_per_m": {"value": 12}}' > "$corpus/json/compensation"
# CMM acceptance results as trueaxis writes them (an E150 run stopped after one position).
printf '\x10' | cat - tests/data/fuzz/acceptance-e150-stopped.json > "$corpus/json/e150"
printf '\x11' | cat - tests/data/fuzz/acceptance-probing.json > "$corpus/json/probing"
printf '\x12' | cat - tests/data/fuzz/acceptance-probing.json > "$corpus/json/figures"
printf '\x10' | cat - tests/data/fuzz/acceptance-e0-no-complete.json > "$corpus/json/e0-found"
printf '\x13' | cat - tests/data/fuzz/certificate-lab.json > "$corpus/json/lab"
printf '\x04{"ball_diameter": 30, "balls": [[0,0,0],[80,0,0],[0,80,0],[80,80,0]]}' > "$corpus/json/gauge"
find tests/data/nist-l2 -name '*.ds' | head -40 | while read -r f; do cp "$f" "$corpus/ds/$(echo "$f" | tr / _)"; done
# Inputs the fuzzers once found a problem with (kept in tests/data/fuzz), so each run starts there.
cp tests/data/fuzz/*.ds "$corpus/ds/"
for f in tests/data/moody/*.txt; do
  for r in 0 1 2 3 4 5 6 7 8; do printf "\\x$(printf %02x $r)" | cat - "$f" > "$corpus/moody/$(basename "$f").$r"; done
done
# I++ DME: every line of NIST's programs and recordings, one per file (one awk for the 5 000
# lines: a shell loop forked once per line and took ~40 s).
awk -v dir="$corpus/ippdme" '{
  gsub(/\r/, ""); if ($0 ~ /^\\\\$/ || $0 ~ /^:/) next
  b = FILENAME; sub(/.*\//, "", b); out = dir "/" b "." (++n[b]); printf "%s", $0 > out; close(out)
}' tests/data/ippdme/nist/*.prg tests/data/ippdme/nist/*.res
# The targets run side by side, as many at a time as there are processors, each for its own
# `seconds`.
fuzz_one() {
  local t=$1
  mkdir -p "$build/findings/$t"
  if ! ASAN_OPTIONS=detect_leaks=1:allocator_may_return_null=0 UBSAN_OPTIONS=print_stacktrace=1 \
      LSAN_OPTIONS=suppressions="$(pwd)/tests/lsan.supp":print_suppressions=0 \
      "$build/tests/fuzz/fuzz_$t" "$corpus/$t" -max_total_time="$seconds" -timeout=10 \
      -seed=1 -rss_limit_mb=2048 -max_len=65536 -artifact_prefix="$build/findings/$t/" \
      -print_final_stats=1 >"$build/fuzz_$t.log" 2>&1; then
    echo "FINDING in fuzz_$t (reproducer in $build/findings/$t/):"; tail -40 "$build/fuzz_$t.log"
    return 1
  fi
  echo "== fuzz_$t for ${seconds} s: $(grep -E "stat::number_of_executed_units|Done [0-9]+ runs" \
    "$build/fuzz_$t.log" | tail -1)"
}
status=0
jobs_max=$(nproc)
pids=()
for t in csv json ds moody ippdme; do
  fuzz_one "$t" &
  pids+=($!)
  if [ "${#pids[@]}" -ge "$jobs_max" ]; then
    wait "${pids[0]}" || status=1
    pids=("${pids[@]:1}")
  fi
done
for p in "${pids[@]}"; do wait "$p" || status=1; done
exit $status
