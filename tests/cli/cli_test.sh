#!/usr/bin/env bash
# End-to-end tests of the trueaxis command line: files, exit codes, one-line errors.
set -u
T=${TRUEAXIS:?set TRUEAXIS to the trueaxis binary}
DATA=$(cd "$(dirname "$0")/../data" && pwd)
dir=${1:-$(mktemp -d)}
rm -rf "$dir"; mkdir -p "$dir"; cd "$dir" || exit 1
fails=0; passes=0
ok() { passes=$((passes+1)); }
bad() { echo "FAIL: $*"; fails=$((fails+1)); }
expect_ok() { if "$@" >out.txt 2>err.txt; then ok; else bad "$* -> $(cat err.txt)"; fi; }
# expect_err PATTERN cmd...: non-zero exit, a one-line message on stderr matching PATTERN
expect_err() {
  local pat=$1; shift
  if "$@" >out.txt 2>err.txt; then bad "should fail: $*"; return; fi
  if grep -q -- "$pat" err.txt && [ "$(wc -l <err.txt)" -le 2 ]; then ok; else bad "$*: stderr '$(cat err.txt)' lacks '$pat'"; fi
}

expect_ok "$T" --help
expect_ok "$T" separate --help
grep -q "two-point" out.txt && ok || bad "separate --help lists the methods"

expect_ok "$T" simulate straightness --stations 300 --offsets 0,10,20 --seed 3 --output p3.csv --truth t3.csv
head -1 p3.csv | grep -qx "x,a@0,b@10,c@20" && ok || bad "probes header (each probe's offset in its name)"
head -1 t3.csv | grep -qx "x,workpiece_um,guide_um,pitch_urad" && ok || bad "truth header"
for m in three-point lsq; do
  expect_ok "$T" separate --input p3.csv --method $m --output r-$m.json --csv r-$m.csv
done
head -1 r-lsq.csv | grep -q "^x,workpiece_um" && ok || bad "result csv header"
# two-point needs exactly two probe columns: give it a two-probe file.
cut -d, -f1-3 p3.csv > p2.csv
expect_ok "$T" separate --input p2.csv --method two-point --output r-two.json
expect_ok "$T" separate --input p3.csv --method three-point --reference patent --output r-seed.json
grep -q '"reference": "patent"' r-seed.json && ok || bad "patent reference recorded"
expect_err "seed not in {ls,patent,min-zone}" "$T" separate --input p3.csv --method three-point --reference seed --output r-seed2.json
expect_ok "$T" separate --input p3.csv --method lsq --reference min-zone --sigma 0.05 --output r-mz.json
grep -q '"uncertainty"' r-mz.json && ok || bad "uncertainty written with --sigma"
expect_ok "$T" report r-lsq.json -o rep.html
grep -q "uPlot" rep.html && ok || bad "report embeds uPlot"

# Surfaces: Moody's Union Jack, and a line network with one line taken from a separate result.
expect_ok "$T" surface --moody "$DATA/moody" -o moody.json
grep -q '"method": "moody"' moody.json && grep -q '"min_zone"' moody.json && ok || bad "moody surface.json"
expect_ok "$T" surface --moody "$DATA/moody" --method lsq -o moody-lsq.json --report moody.html
[ "$(grep -o '<svg class="ta-fig"' moody.html | wc -l)" -eq 3 ] && grep -q "the surface in 3-D" moody.html && grep -q "closure at every crossing" moody.html && ok || bad "surface --report: 3-D view, heights and closure figures"
cat > lines.json <<'JSON'
{"lines": [
  {"name": "A", "start": [0, 0], "direction": [0, 1], "from": "r-two.json"},
  {"name": "B", "start": [0, 0], "direction": [1, 0], "spacing": 10, "heights": [0, 1, 2]},
  {"name": "C", "start": [0, 100], "direction": [1, 0], "spacing": 10, "slopes": [100, -100]},
  {"name": "D", "start": [20, 0], "direction": [0, 1], "spacing": 50, "heights": [0, 1, 2]}
]}
JSON
expect_ok "$T" surface --lines lines.json -o net.json
grep -q '"twist"' net.json && ok || bad "axis-parallel network reports the twist unobservable"
sed 's/"heights": \[0, 1, 2\]}$/"heights": [0, "q", 2]}/' lines.json > badlines.json
expect_err "badlines.json:5:" "$T" surface --lines badlines.json -o o.json
sed 's/"direction": \[0, 1\], "spacing": 50/"direction": [1, 1], "spacing": 50/' lines.json > diag.json
expect_err "neither along x nor along y" "$T" surface --lines diag.json --method boundary -o o.json
sed 's/"from": "r-two.json"}/"from": "r-two.json", "spacing": 7}/' lines.json > spacing.json
expect_err "spacing.json:2:88: spacing 7 mm does not match the result's station step 10 mm" "$T" surface --lines spacing.json -o o.json
expect_err "classic needs --moody" "$T" surface --lines lines.json --method classic -o o.json

# The virtual machine: a random machine, its true errors at given points, a probe run on it.
expect_ok "$T" simulate machine --seed 3 --chain FXYZ -o machine.json
grep -q '"EC0Y"' machine.json && grep -q '"chain": "FXYZ"' machine.json && ok || bad "machine.json"
printf 'x,y,z\n0,0,0\n400,300,250\n' > pts.csv
expect_ok "$T" machine error machine.json pts.csv
head -1 out.txt | grep -qx "x,y,z,ex,ey,ez" && [ "$(wc -l <out.txt)" -eq 3 ] && ok || bad "machine error to stdout"
expect_ok "$T" machine error machine.json pts.csv -o errs.csv
[ "$(wc -l <errs.csv)" -eq 3 ] && [ ! -s out.txt ] && ok || bad "machine error -o writes the file, not stdout"
printf 'x,y,z\n0,0,0\n400,300,999\n' > far.csv
expect_err "far.csv:3:9: z = 999 mm is outside the machine's range" "$T" machine error machine.json far.csv
printf '{"ranges": {"x": [0, 8], "y": [0, 6], "z": [0, 5]},\n "errors": {"EXQ": 1}}' > badm.json
expect_err "badm.json:2:20: unknown error 'EXQ'" "$T" machine error badm.json pts.csv
expect_ok "$T" simulate line --machine machine.json --start 0,300,250 --step 20 --offsets 0,20,40 --angle -o run.csv --truth run-truth.csv
[ "$(wc -l <run.csv)" -eq 42 ] && head -1 run.csv | grep -qx "x,a@0,b@20,c@40,angle" && ok || bad "simulate line fills the x range (41 stops, 0..800 mm)"
expect_ok "$T" separate --input run.csv --offsets 0,20,40 --angle angle -o run.json
expect_err "leaves the machine's range" "$T" simulate line --machine machine.json --start 700,0,0 --stations 20 -o o.csv --truth t.csv

# Error space, compensation and controller export on the virtual machine.
"$T" simulate machine --seed 5 --x 0,300 --y 0,200 --z 0,150 -q -o small.json
echo '{"spacing": 50, "probe_noise_um": 0.02, "laser_noise_um": 0.02, "monte_carlo": 4}' > plan.json
expect_ok "$T" space --machine small.json --plan plan.json -o space.json --csv space.csv --report space.html
grep -q "XY plane at z" space.html && grep -q "before and after compensation" space.html && grep -q "space.html" out.txt && ok || bad "space --report: planes and compensation curves"
grep -q "improvement x" out.txt && grep -q '"verification"' space.json && grep -q '"uz"' space.json && ok || bad "space summary and space.json"
printf 'x,y,z\n10,20,30\n300,200,150\n' > cmds.csv
expect_ok "$T" compensate --space space.json -i cmds.csv -o corrected.csv
[ "$(wc -l <corrected.csv)" -eq 3 ] && head -1 corrected.csv | grep -qx "x,y,z" && ok || bad "corrected.csv"
expect_ok "$T" compensate --space space.json -i cmds.csv -o - --interpolation cubic
[ "$(wc -l <out.txt)" -eq 3 ] && ok || bad "compensate to stdout prints only the CSV"
printf 'x,y,z\n10,20,30\n10,20,999\n' > outside.csv
expect_err "outside.csv:3:1: point 2 (10.000, 20.000, 999.000) mm is outside the map's grid" "$T" compensate --space space.json -i outside.csv -o o.csv
expect_ok "$T" compensate --space space.json -i outside.csv -o o.csv --clamp
expect_ok "$T" export linuxcnc --space space.json --axis y --type 0 -o y.comp
[ "$(wc -l <y.comp)" -eq 5 ] && awk 'NF != 3 { exit 1 } NR > 1 && $1 <= prev { exit 1 } { prev = $1 }' y.comp && ok || bad "y.comp: triplets, increasing"
expect_ok "$T" export sinumerik --space space.json --axis y --axis-name Y1 -o y_lec.mpf
[ "$(grep -c '^\$AA_ENC_COMP\[0,[0-9]*,Y1\]=' y_lec.mpf)" -eq 5 ] && ok || bad "export sinumerik --space: one value per grid node"
expect_ok "$T" export csv --space space.json -o table.csv
echo '{"spacing": 50, "noise": 1}' > badplan.json
expect_err "badplan.json:1:26: unknown key 'noise'" "$T" space --machine small.json --plan badplan.json -o o.json
expect_err "'grid' is missing" "$T" compensate --space machine.json -i cmds.csv -o o.csv

# Bad inputs: each a clear one-line error naming the file (and line:column where it applies).
printf 'x,a,b\n0,1,2\n10,1,2\n10,1,2\n' > nonincr.csv
expect_err "nonincr.csv:4:1: x = 10 does not increase" "$T" separate --input nonincr.csv --method two-point --output o.json
printf 'x,a,b\n0,1,2\n10,1,2\n25,1,2\n' > uneven.csv
expect_err "uneven.csv:3:1: uneven step" "$T" separate --input uneven.csv --method two-point --output o.json
printf 'x,a,b\n0,1,2\n10,nan,2\n20,1,2\n' > nan.csv
expect_err "nan.csv:3:4: NaN is not allowed" "$T" separate --input nan.csv --method two-point --output o.json
printf 'x,a,b\n0,1,2\n10,1\n20,1,2\n' > missing.csv
expect_err "missing.csv:3:5: missing field for column 'b'" "$T" separate --input missing.csv --method two-point --output o.json
printf 'x,a,b\n0,1,2\n10,1,2\n' > short.csv
expect_err "too few stations" "$T" separate --input short.csv --method two-point --output o.json
expect_err "p3.csv:1:3: the column names state the probe offsets 0,10,20 mm, but --offsets says 0,15,20" "$T" separate --input p3.csv --offsets 0,15,20 --output o.json
sed '1s/@[0-9]*//g' p3.csv > p3-plain.csv
expect_err "not a whole multiple of the step" "$T" separate --input p3-plain.csv --offsets 0,15,20 --output o.json
# A file that does not state its offsets: they are assumed equal to the step, and the result says so.
expect_ok "$T" separate --input p3-plain.csv --output p3-plain.json
grep -q "the probe offsets were not stated, so they were taken as 0, 10, 20 mm" err.txt && grep -q '"offsets_assumed": true' p3-plain.json && ok || bad "assumed offsets are stated"
expect_ok "$T" separate --input p3.csv --output p3-named.json
! grep -q "were not stated" err.txt && grep -q '"offsets_assumed": false' p3-named.json && ok || bad "offsets from the column names"
printf 'x,a@0,b,c@20\n0,1,2,3\n10,1,2,3\n20,1,2,3\n30,1,2,3\n' > p3-mixed.csv
expect_err "p3-mixed.csv:1:7: column 'b' states no probe offset while others do" "$T" separate --input p3-mixed.csv --output o.json
printf 'x,a@0,b@ten\n0,1,2\n10,1,2\n20,1,2\n' > p3-badoff.csv
expect_err "p3-badoff.csv:1:7: column 'b@ten': the probe offset after '@' must be a number of mm" "$T" separate --input p3-badoff.csv --output o.json
expect_err "missing column 'level'" "$T" separate --input p3.csv --angle level --output o.json
"$T" simulate straightness --stations 100 --offsets 0,20,40 --output chain.csv --truth tc.csv -q
expect_err "chain offsets" "$T" separate --input chain.csv --offsets 0,20,40 --output o.json
expect_err "patent' is defined for the three-point method only" "$T" separate --input p3.csv --reference patent --output o.json
printf '{"workpiece": {"x": [0,1], "value": [1,' > broken.json
expect_err "broken.json:1:" "$T" report broken.json -o x.html
expect_err "" "$T" separate --input does-not-exist.csv --output o.json

# Guideway: a pure horizontal shift of 1 um reads dx = -1 on every detector.
cat > gw.json <<'J'
{"detectors": [{"name": "a", "kind": "position", "position": [-60, 0, 0]},
               {"name": "b", "kind": "position", "position": [60, 0, 150]},
               {"name": "c", "kind": "position", "position": [0, 80, 300]}]}
J
printf 's,a_dx,a_dy,b_dx,b_dy,c_dx,c_dy\n0,-1,0,-1,0,-1,0\n10,-1,0,-1,0,-1,0\n' > gw.csv
expect_ok "$T" guideway --layout gw.json --input gw.csv --output gw-result.json
grep -q '"horizontal": \[' gw-result.json && grep -q '"pitch": true' gw-result.json && grep -q "roll" out.txt && ok || bad "guideway result"
sed 's/150\]/0]/; s/300\]/0]/' gw.json > gw-flat.json
expect_ok "$T" guideway --layout gw-flat.json --input gw.csv --output gw-flat-result.json
grep -q "pitch, yaw" err.txt && grep -q '"pitch": null' gw-flat-result.json && ok || bad "coplanar layout: pitch and yaw unobservable"
printf 's,a_dx,a_dy,b_dx,b_dy,c_dx,c_dy,d_dx\n0,-1,0,-1,0,-1,0,0\n' > gw-bad.csv
expect_err "gw-bad.csv:1:33: column 'd_dx' names no detector" "$T" guideway --layout gw.json --input gw-bad.csv --output o.json
expect_ok "$T" simulate guideway5d --layout gw.json --axis y --positions 50 --noise 0.05 -o gw-sim.csv --truth gw-truth.csv
head -1 gw-sim.csv | grep -qx "s,a_dx,a_dy,b_dx,b_dy,c_dx,c_dy" && head -1 gw-truth.csv | grep -qx "s,horizontal_um,vertical_um,pitch_urad,yaw_urad,roll_urad" && ok || bad "simulate guideway5d headers"
expect_ok "$T" guideway --layout gw.json --input gw-sim.csv --output gw-sim.json --sigma 0.05 --report gw.html
grep -q "roll (εz)" gw.html && grep -q "uPlot" gw.html && ok || bad "guideway --report"
# Positioning (ISO 230-2): simulated runs, the evaluation, tolerances, located errors.
expect_ok "$T" simulate positioning --axis y --targets 0:40:600 --cycles 5 --backlash 2 --noise 0.3 -o pos.csv
head -1 pos.csv | grep -qx "target_mm,cycle,direction,deviation_um" && head -1 pos-truth.csv | grep -qx "target_mm,geometric_um,up_um,down_um" && ok || bad "simulate positioning headers"
[ "$(wc -l <pos.csv)" -eq $((16 * 2 * 5 + 1)) ] && ok || bad "simulate positioning: 16 targets x 2 directions x 5 cycles"
expect_ok "$T" positioning --input pos.csv --output pos.json --tolerance A=100
grep -q '"standard": "ISO 230-2:2014"' pos.json && grep -q '"pass": true' pos.json && grep -q "reversal B" out.txt && ok || bad "positioning result"
expect_err "out of tolerance: B = " "$T" positioning --input pos.csv --output pos-bad.json --tolerance B=0.5 -q
grep -q '"pass": false' pos-bad.json && ok || bad "positioning writes its result when out of tolerance"
"$T" positioning --input pos.csv --tolerance X=1 >out.txt 2>err.txt; [ $? -eq 2 ] && grep -q "unknown parameter 'X'" err.txt && ok || bad "unknown tolerance name is a usage error (exit 2)"
printf 'target_mm,cycle,direction,deviation_um\n0,1,+,1\n0,1,up,2\n' > pos-dup.csv
expect_err "pos-dup.csv:3:1: cycle 1 '+' at target 0 mm was already read on line 2" "$T" positioning --input pos-dup.csv
# Millimetres written in the micrometre column: named, and the tolerance is not judged PASS.
awk -F, 'NR == 1 { print; next } { printf "%s,%s,%s,%.9f\n", $1, $2, $3, $4 / 1000 }' pos.csv > pos-mm.csv
expect_err "not judged: the deviations vary by only" "$T" positioning --input pos-mm.csv --tolerance A=25 --output pos-mm.json
grep -q '"not_judged"' pos-mm.json && grep -q '"pass": false' pos-mm.json && ok || bad "positioning: a unit mix-up is not judged"
grep -v '^200,3,-' pos.csv > pos-gap.csv
# The dropped reading is named at the line where the '-' run of cycle 3 jumps from 240 to 160 mm.
gap_line=$(grep -n '^160,3,-' pos-gap.csv | cut -d: -f1)
expect_err "pos-gap.csv:$gap_line:1: no '-' reading at target 200 mm in cycle 3" "$T" positioning --input pos-gap.csv
expect_ok "$T" positioning --input pos-gap.csv --allow-incomplete --output pos-gap.json
grep -q "incomplete cycles" pos-gap.json && ok || bad "--allow-incomplete warns"
# The same runs as an interferometer log: the stops at the targets give the same evaluation.
expect_ok "$T" simulate positioning --axis y --targets 0:40:600 --cycles 5 --backlash 2 --noise 0.3 -o pos2.csv --log pos-log.csv
head -1 pos-log.csv | grep -qx "time_s,reading_mm" && ok || bad "simulate positioning --log header"
expect_ok "$T" positioning --input pos-log.csv --targets 0:40:600 --output pos-log.json
grep -q "161 stops, 160 at targets, 1 not used" out.txt && ok || bad "stops found in the log: $(head -1 out.txt)"
[ "$(grep -o '"E": [0-9.]*' pos-log.json | cut -c1-12)" = "$(grep -o '"E": [0-9.]*' pos.json | cut -c1-12)" ] && ok || bad "the log gives the runs' E"
expect_err "--input is required" "$T" positioning --output o.json
expect_err "pos-log.csv is an interferometer log (time_s, reading_mm): it needs --targets" "$T" positioning --input pos-log.csv
expect_err "--targets belongs to an interferometer log; pos.csv holds runs" "$T" positioning --input pos.csv --targets 0:40:600
expect_code 2 "$T" positioning --input pos.csv --targets 0:40:600
# A LinuxCNC table from the positioning result, read back by the simulator: the reversal goes.
expect_ok "$T" export linuxcnc --positioning pos.json -o pos.comp
[ "$(wc -l <pos.comp)" -eq 16 ] && grep -q "BACKLASH = 0" out.txt && ok || bad "export linuxcnc --positioning"
expect_ok "$T" simulate positioning --axis y --targets 0:40:600 --cycles 5 --backlash 2 --noise 0.3 --seed 2 --compensation pos.comp -o pos-after.csv
expect_ok "$T" positioning --input pos-after.csv --output pos-after.json --tolerance B=1.5
expect_err "give --space FILE or --positioning FILE" "$T" export linuxcnc -o x.comp
expect_ok "$T" export sinumerik --positioning pos.json --axis y --step 20 -o pos_lec.mpf
head -2 pos_lec.mpf | tail -1 | grep -qx "CHANDATA(1)" && grep -q '^\$AA_ENC_COMP\[0,30,Y1\]=' pos_lec.mpf && grep -q "MD32450" out.txt && ok || bad "export sinumerik"
expect_ok "$T" simulate positioning --axis y --targets 0:40:600 --backlash 2 --noise 0.3 --seed 2 --compensation pos_lec.mpf --comp-format sinumerik -o pos-lec.csv
expect_err "exceed MD38000" "$T" export sinumerik --positioning pos.json --step 0.1 --max-points 200 -o o.mpf
# Renishaw's .rtl file: written by the simulator, read by positioning with the CSV's result.
expect_ok "$T" simulate positioning --axis y --targets 0:40:600 --cycles 5 --backlash 2 --noise 0.3 -o pos.rtl
head -1 pos.rtl | tr -d '\r' | grep -qx "HEADER::" && ok || bad "simulate positioning -o pos.rtl writes an .rtl file"
expect_ok "$T" positioning --input pos.rtl --output pos-rtl.json
grep -q "Renishaw .rtl, 16 targets, 10 runs, 160 readings" out.txt && ok || bad "positioning reads the .rtl: $(head -1 out.txt)"
[ "$(grep -o '"E": [0-9.]*' pos-rtl.json | cut -c1-10)" = "$(grep -o '"E": [0-9.]*' pos.json | cut -c1-10)" ] && ok || bad "the .rtl gives the CSV's E"
tr -d '\r' < pos.rtl | awk '/^Run Target Data:/{print; d=1; next} d{print | "sort -n -k1,1 -k2,2"; next} {print}' > pos-sorted.rtl
expect_ok "$T" positioning --input pos-sorted.rtl --output pos-sorted.json
grep -q "every run lists its targets in increasing order" err.txt && grep -q '"B": null' pos-sorted.json && ok || bad "a sorted .rtl is named as one-direction"
expect_ok "$T" positioning --input pos-sorted.rtl --run-directions +- --output pos-sorted.json
[ "$(grep -o '"E": [0-9.]*' pos-sorted.json | cut -c1-10)" = "$(grep -o '"E": [0-9.]*' pos.json | cut -c1-10)" ] && ok || bad "--run-directions +- reads a sorted .rtl"
# A warming axis: the .rtl carries deviations corrected to 20 C (no temperatures), as laser
# software writes them; the CSV carries the temperatures and is corrected on evaluation.
for f in warm.csv warm.rtl; do
  expect_ok "$T" simulate positioning --axis x --targets 0:50:800 --backlash 2 --noise 0.3 --temperature 21:22.5 -o $f
  expect_ok "$T" positioning --input $f --output $f.json
done
[ "$(grep -o '"E": [0-9.]*' warm.rtl.json | cut -c1-10)" = "$(grep -o '"E": [0-9.]*' warm.csv.json | cut -c1-10)" ] && ok || bad "the .rtl of a warming axis is corrected to 20 °C"
sed 's/^Target-count : 16/Target-count : 17/' pos.rtl > pos-bad.rtl
expect_err "pos-bad.rtl:8:1: Target-count is 17 (line 7) but the Targets list has 16" "$T" positioning --input pos-bad.rtl
expect_err "belongs to a Renishaw .rtl input" "$T" positioning --input pos.csv --run-directions +-
# HEIDENHAIN: both directions in one *.COM table; the virtual axis rerun with it.
expect_ok "$T" export heidenhain --positioning pos.json --axis Y -o Y.COM
head -2 Y.COM | tr -s ' ' | grep -qx "NR AXISPOS Y BACKLASH" && tail -1 Y.COM | grep -qx "\[END\]" && [ "$(wc -l <Y.COM)" -eq 19 ] && ok || bad "export heidenhain"
expect_ok "$T" simulate positioning --axis y --targets 0:40:600 --cycles 5 --backlash 2 --noise 0.3 --seed 2 --compensation Y.COM --comp-format heidenhain -o pos-hh.csv
expect_ok "$T" positioning --input pos-hh.csv --output pos-hh.json --tolerance B=1.5,E=2.5
# FANUC: pitch error data with parameters 3620-3624 for axis 2; backlash for 1851 printed.
expect_ok "$T" export fanuc --positioning pos.json --axis-number 2 --axis Y -o y-pitch.txt
grep -qx "N3620A2P0" y-pitch.txt && grep -qx "N3624A2P40.0" y-pitch.txt && grep -q "parameter 1851" out.txt && ok || bad "export fanuc"
expect_ok "$T" simulate positioning --axis y --targets 0:40:600 --cycles 5 --backlash 2 --noise 0.3 --seed 2 --compensation y-pitch.txt --comp-format fanuc --comp-axis-number 2 -o pos-fanuc.csv
expect_ok "$T" positioning --input pos-fanuc.csv --output pos-fanuc.json --tolerance M=2.5
expect_err "parameter 3620 for axis 1 is missing" "$T" simulate positioning --axis y --compensation y-pitch.txt --comp-format fanuc -o o.csv
expect_err "below the control's minimum" "$T" export fanuc --positioning pos.json --interval 2 --max-feedrate 30000 -o o.txt
printf '0 0 0\n10 0\n' > bad.comp
expect_err "bad.comp:2:5: expected three numbers" "$T" simulate positioning --compensation bad.comp -o o.csv
# Quadrant currents: the layout needs the QPD's gain (printed by the simulator).
expect_ok "$T" simulate guideway5d --layout gw.json --currents --spot-radius 2 --positions 20 -o gw-cur.csv --truth gw-cur-truth.csv
gain=$(grep -o '"gain_um": [0-9.]*' out.txt | grep -o '[0-9.]*$')
sed "s/^{\"detectors\"/{\"qpd\": {\"gain_um\": $gain, \"min_sum\": 0.5},\n \"detectors\"/" gw.json > gw-qpd.json
expect_ok "$T" guideway --layout gw-qpd.json --input gw-cur.csv --output gw-cur.json
head -1 gw-cur.csv | grep -q "a_i1,a_i2,a_i3,a_i4" && grep -q '"roll": \[' gw-cur.json && ok || bad "guideway from quadrant currents"
awk -F, 'NR==3{$2=0.1;$3=0.1;$4=0.1;$5=0.1} {print}' OFS=, gw-cur.csv > gw-lost.csv
expect_err "gw-lost.csv:3:.*detector 'a' at s = .* spot lost" "$T" guideway --layout gw-qpd.json --input gw-lost.csv --output o.json
expect_ok "$T" guideway --layout gw-qpd.json --input gw-lost.csv --output o.json --skip-bad
grep -q "skipped: " err.txt && grep -q "(1 positions skipped)" out.txt && ok || bad "--skip-bad drops the lost sample"

# Geometric fits: NIST's .ds format and CSV.
expect_ok "$T" fit cylinder --input "$DATA/nist-l2/Cylinder/cyl1.ds" --output cyl.json
grep -q '"direction"' cyl.json && grep -q '"diameter": 57.2892295075' cyl.json && ok || bad "fit cylinder on NIST cyl1"
printf 'x,y,z\n1,0,0\n0,1,0\n-1,0,0\n0,-1,0\n0,0,1\n' > ball.csv
expect_ok "$T" fit sphere -i ball.csv -o ball.json
grep -q '"diameter": 2' ball.json && ok || bad "fit sphere from CSV"
expect_ok "$T" fit plane --zone -i "$DATA/nist-l2/Plane/pla1.ds" -o pla.json
grep -q '"zone"' pla.json && grep -q "minimum zone" out.txt && ok || bad "fit plane --zone"
expect_err "" "$T" fit sphere --zone -i ball.csv -o o.json
# The form figure: without the points' uncertainty no U (null, with why); with it, U beside it.
expect_ok "$T" fit plane --zone -i "$DATA/nist-l2/Plane/pla1.ds" -o pla.json
grep -q '"name": "flatness"' pla.json && grep -q '"U": null' pla.json && grep -q "flatness (minimum zone): .* no uncertainty: the points' own uncertainty is not stated" out.txt && ok || bad "fit: form without --point-u"
expect_ok "$T" fit plane --zone --point-u 0.01 -i "$DATA/nist-l2/Plane/pla1.ds" -o pla-u.json
grep -q "flatness (minimum zone): .* µm, U = .* µm (95 %)" out.txt && grep -q '"resolved": true' pla-u.json && ok || bad "fit --point-u states the form's U"
expect_err "point-u: must be a positive number, not '-1'" "$T" fit plane --point-u -1 -i "$DATA/nist-l2/Plane/pla1.ds" -o o.json
printf '3\n0 0 0\n1 1 1\n2 2 2\n' > line.ds
expect_err "plane fit: the points are collinear" "$T" fit plane -i line.ds -o o.json
printf '2\n0 0 0\n1 1 one\n' > bad.ds
expect_err "bad.ds:3:5: expected a number" "$T" fit line -i bad.ds -o o.json

# Ball gauge: simulate, map, correct.
expect_ok "$T" simulate ballgauge --noise 0.3 --gauge bg-gauge.json --measurements bg-meas.json --truth bg-truth.csv
expect_ok "$T" ballgauge --gauge bg-gauge.json --measurements bg-meas.json --output bg-map.json
grep -q "80 mapped points on a 5 x 4 x 4 grid" out.txt && grep -q '"grid"' bg-map.json && ok || bad "ballgauge map"
printf 'x,y,z\n300,250,150\n' > bg-pts.csv
expect_ok "$T" correct --map bg-map.json --input bg-pts.csv --output bg-corr.csv
printf 'x,y,z\n300,250,150\n900,250,150\n' > bg-out.csv
expect_err "bg-out.csv:3:1: point 2 (900.000, 250.000, 150.000) mm is outside" "$T" correct --map bg-map.json --input bg-out.csv --output o.csv
expect_ok "$T" simulate ballgauge --alignment ls --noise 0.3 --gauge bg-gauge.json --measurements bg-ls.json --truth bg-truth.csv
grep -q '"alignment": "ls"' bg-ls.json && ok || bad "simulate ballgauge --alignment ls"
expect_ok "$T" ballgauge --gauge bg-gauge.json --measurements bg-ls.json --output bg-ls-map.json
grep -q "placement 1    ls " out.txt && ok || bad "ballgauge with the least-squares alignment"
sed 's/"index": 7,/"index": 70,/' bg-meas.json > bg-bad.json
expect_err "bg-bad.json:[0-9]*:[0-9]*: ball index 70 is not in the gauge" "$T" ballgauge --gauge bg-gauge.json --measurements bg-bad.json --output o.json

# Ball plates: a campaign of six placements (each aligned by itself; the upright plates probed
# from both sides with a horizontal stylus) identifies the 21 errors; one placement alone is a map
# of its plane, used on that plane only.
expect_ok "$T" simulate ballgauge --plate 5x5 --pitch 100 --noise 0.3 --gauge bp-gauge.json --measurements bp-meas.json --truth bp-truth.csv --lengths bp-lengths.csv
grep -q "6 placements of a 5x5 ball plate at 100 mm pitch" out.txt && grep -q "probed from the side" out.txt && ok || bad "simulate ballgauge --plate"
grep -q '"stylus_offset": \[' bp-meas.json && ok || bad "the upright placements state their stylus"
expect_ok "$T" ballgauge --gauge bp-gauge.json --measurements bp-meas.json --output bp-map.json --parametric bp-model.json --stylus-offset 0,0,-100
grep -q "150 mapped points in 6 separate frames" out.txt && grep -q "use the 21-error model (bp-model.json)" err.txt && ! grep -q '"grid"' bp-map.json && grep -q "5 styli: (0, 0, -100) mm in XY low, XY high; (0, 100, 0) mm in XZ from -Y" out.txt && ok || bad "ballgauge on a plate campaign"
/usr/bin/python3 - <<'PY' && ok || bad "upright plates from one side"
import json
m = json.load(open("bp-meas.json"))
m["placements"] = [p for p in m["placements"] if p["name"] not in ("XZ from +Y", "YZ from -X")]
json.dump(m, open("bp-one-side.json", "w"))
PY
expect_err "cannot tell EZZ, .* apart .* the stylus the model is for, (0, 0, -100) mm" "$T" ballgauge --gauge bp-gauge.json --measurements bp-one-side.json --output o.json --parametric o-model.json --stylus-offset 0,0,-100
expect_ok "$T" verify-lengths --model bp-model.json -i bp-lengths.csv -o bp-verify.json
grep -q "parametric correction: 105 lengths" out.txt && ok || bad "verify-lengths with a plate campaign's model"
"$T" simulate ballgauge --plate 5y5 >out.txt 2>err.txt; [ $? -eq 2 ] && grep -q "give ROWSxCOLUMNS" err.txt && ok || bad "--plate 5y5 is a usage error"
/usr/bin/python3 - <<'PY' && ok || bad "one plate placement"
import json
m = json.load(open("bp-meas.json"))
m["placements"] = m["placements"][2:3]  # the XZ placement (probed from -Y) alone
json.dump(m, open("bp-xz.json", "w"))
PY
expect_ok "$T" ballgauge --gauge bp-gauge.json --measurements bp-xz.json --output bp-xz-map.json
grep -q "25 mapped points on a 5 x 5 grid in the plane y = " out.txt && grep -q '"plane"' bp-xz-map.json && ok || bad "a plate's map on its plane"
Y=$(/usr/bin/python3 -c 'import json; print(json.load(open("bp-xz-map.json"))["grid"]["plane"]["at"])')
printf 'x,y,z\n350,%s,200\n350,%s,200\n' "$Y" "$(/usr/bin/python3 -c "print($Y + 2)")" > bp-on.csv
expect_ok "$T" correct --map bp-xz-map.json --input bp-on.csv --output bp-corr.csv
grep -q "bilinear on the plate's plane" out.txt && ok || bad "correct on a plate's plane"
printf 'x,y,z\n350,%s,200\n' "$(/usr/bin/python3 -c "print($Y + 40)")" > bp-off.csv
expect_err "bp-off.csv:2:1: point 1 .* is 40.000 mm off the plane y = " "$T" correct --map bp-xz-map.json --input bp-off.csv --output o.csv

# Gauge-block verification, grid and parametric (grid map and parametric model).
expect_ok "$T" simulate ballgauge --alignment ls --noise 0.3 --gauge bg-gauge.json --measurements bg-ls.json --truth bg-truth.csv --lengths bg-lengths.csv
grep -q "105 gauge-block measurements" out.txt && head -1 bg-lengths.csv | grep -qx "x1,y1,z1,x2,y2,z2,nominal" && ok || bad "simulate ballgauge --lengths"
expect_ok "$T" ballgauge --gauge bg-gauge.json --measurements bg-ls.json --output bg-ls-map.json --parametric bg-model.json --stylus-offset 0,0,-100 --report bg-map.html
grep -q "parametric model (FYXZ chain, polynomials of degree 3)" out.txt && grep -q '"identification"' bg-model.json && grep -q "<svg" bg-map.html && ok || bad "ballgauge --parametric --report"
expect_err "stylus-offset" "$T" ballgauge --gauge bg-gauge.json --measurements bg-ls.json --output o.json --parametric o2.json
printf 'x,y,z\n300,250,300\n' > bg-cmd.csv
expect_ok "$T" machine error bg-model.json bg-cmd.csv -o bg-model-err.csv
[ "$(wc -l <bg-model-err.csv)" -eq 2 ] && ok || bad "the parametric model is a machine.json"
expect_ok "$T" verify-lengths --map bg-ls-map.json --model bg-model.json -i bg-lengths.csv -o bg-verify.json --report bg-verify.html
grep -q "length verification, grid correction: 105 lengths in 35 set-ups (a gauge at one place)" out.txt && grep -q "parametric correction" out.txt && grep -q '"expected_after_rms"' bg-verify.json && grep -q "figure 10" bg-verify.html && ok || bad "verify-lengths"
expect_err "needs --map" "$T" verify-lengths -i bg-lengths.csv -o o.json
printf 'x1,y1,z1,x2,y2,z2,nominal\n200,200,200,300,200,200,100\n200,200,200,300,200,200,0\n' > bg-badlen.csv
expect_err "bg-badlen.csv:3:[0-9]*: nominal length 0 mm: must be > 0" "$T" verify-lengths --map bg-ls-map.json -i bg-badlen.csv -o o.json
printf 'x1,y1,z1,x2,y2,z2,nominal\n200,200,200,900,200,200,700\n' > bg-outlen.csv
expect_err "bg-outlen.csv:2:13: grid correction: length 1: point 2 (900.000, 200.000, 200.000) mm is outside" "$T" verify-lengths --map bg-ls-map.json -i bg-outlen.csv -o o.json
expect_err "bg-outlen.csv:2:13: parametric correction: length 1: point 2 (900.000, 200.000, 200.000) is outside the identified span" "$T" verify-lengths --model bg-model.json -i bg-outlen.csv -o o.json
expect_err "bg-ls-map.json:[0-9]*:[0-9]*: not a parametric model" "$T" verify-lengths --model bg-ls-map.json -i bg-lengths.csv -o o.json

# One grammar: every command-line mistake exits 2 (CLI11's own codes are 105, 106, 109...).
expect_code() { local want=$1; shift; "$@" >out.txt 2>err.txt; local rc=$?; [ "$rc" -eq "$want" ] && ok || bad "$* exited $rc, want $want"; }
expect_code 2 "$T" bogus
expect_code 2 "$T" separate
expect_code 2 "$T" separate --input p3.csv --output o.json --method nine-point
expect_code 2 "$T" separate --input p3.csv --output o.json --no-such-flag
# A missing input is an error like every other: exit 1, "trueaxis: error: FILE: no such file".
expect_code 1 "$T" separate --input does-not-exist.csv --output o.json
grep -qx "trueaxis: error: does-not-exist.csv: no such file" err.txt && ok || bad "a missing input: $(cat err.txt)"
expect_err "plate-missing: no such directory" "$T" surface --moody plate-missing -o s.json
expect_code 2 "$T" fit sphere --input p3.csv --output o.json --stations x
expect_code 2 "$T" simulate
expect_code 0 "$T" help
# 'trueaxis help' and 'trueaxis' alone: every command on a line of its own with its purpose.
for c in separate surface simulate machine space compensate export guideway positioning fit \
         ballgauge correct verify-lengths design scan serve ipp acceptance record report demo examples help; do
  grep -Eq "^  $c +[a-zA-Z]" out.txt || bad "trueaxis help lists '$c' with its purpose"
done
[ "$(awk 'length > 100' out.txt | wc -l)" -eq 0 ] && ok || bad "the command list has lines of at most 100 characters"
cp out.txt help-list.txt
expect_code 0 "$T"
cmp -s out.txt help-list.txt && ok || bad "trueaxis alone prints the command list"
expect_code 0 "$T" fit sphere --version
grep -q "^trueaxis [0-9]" out.txt && ok || bad "--version works on every command"
# A slip of the keyboard gets a suggestion, with exit 2.
expect_code 2 "$T" separate --input p3.csv --output o.json --sigm 1
grep -q "did you mean --sigma?" err.txt && ok || bad "a mistyped flag: $(cat err.txt)"
expect_code 2 "$T" separat --input p3.csv
grep -q "did you mean separate?" err.txt && ok || bad "a mistyped command: $(cat err.txt)"
expect_code 2 "$T" simulate machin
grep -q "did you mean machine?" err.txt && ok || bad "a mistyped sub-command: $(cat err.txt)"
# --axis is a machine axis everywhere (X taken as x); the control's own name is --axis-name.
expect_err "'w' is not a machine axis: give x, y or z" "$T" simulate positioning --axis w -o w.csv
expect_err "such as X1, goes in --axis-name" "$T" export sinumerik --positioning p.json --axis X1 -o x.mpf
expect_ok "$T" simulate positioning --axis X --targets 0:100:400 --cycles 2 -o upper.csv
expect_code 0 "$T" help simulate line
grep -q -- "--start" out.txt && ok || bad "trueaxis help simulate line"
expect_code 2 "$T" help nosuchcommand
grep -q "no command 'nosuchcommand'" err.txt && ok || bad "help on an unknown command says so"

# separate: an angle column is never a silent fourth probe; named columns work; warnings in words.
expect_ok "$T" simulate straightness --stations 200 --angle --seed 4 -o pa.csv --truth pa-truth.csv
expect_err "pa.csv:1:17: column 'angle' looks like an angle channel" "$T" separate --input pa.csv --output o.json
expect_err "pa.csv:1:12: unexpected column 'c@20'" "$T" separate --input pa.csv --output o.json --offsets 0,10 --angle angle
expect_ok "$T" separate --input pa.csv --output pa.json --angle angle --sigma 0.05
expect_ok "$T" separate --input pa.csv --output pa3.json --probes a,b,c --method three-point
expect_ok "$T" simulate straightness --stations 500 --offsets 0,10,20 --noise 0.05 -o rd.csv --truth rd-truth.csv
expect_ok "$T" separate --input rd.csv --method lsq --sigma 0.05 --output rd.json
grep -q "is not resolved" err.txt && grep -q "is not resolved" rd.json && ok || bad "separate warns when u exceeds the straightness"
# The unresolved figure is not printed as a number: "not resolved (U = ...)" on stdout, and
# resolved false beside U_um in the JSON.
grep -q "workpiece straightness: not resolved (U = " out.txt && ok || bad "separate: stdout says not resolved"
python3 -c "import json,sys; s=json.load(open('rd.json'))['straightness']['workpiece']; sys.exit(0 if s['resolved'] is False and s['U_um'] > s['min_zone'] else 1)" && ok || bad "separate: JSON resolved false with U_um"
expect_ok "$T" report rd.json -o rd.html
grep -q 'class="warn"' rd.html && ok || bad "the report shows the warning"

# Simulations with their default names never overwrite each other's files.
mkdir -p defaults && (cd defaults &&
  "$T" simulate straightness -q && "$T" simulate machine --seed 2 -o m.json -q &&
  "$T" simulate line --machine m.json --start 0,300,250 -q &&
  "$T" simulate guideway5d --machine m.json --layout ../gw.json -q &&
  "$T" simulate ballgauge -q) >out.txt 2>err.txt || bad "default simulations: $(cat err.txt)"
for f in probes.csv probes-truth.csv line.csv line-truth.csv spots.csv spots-truth.csv gauge.json measurements.json ballgauge-truth.csv; do
  [ -s "defaults/$f" ] && ok || bad "default simulation output $f missing"
done
head -1 defaults/probes-truth.csv | grep -qx "x,workpiece_um,guide_um,pitch_urad" && head -1 defaults/spots-truth.csv | grep -q "^s,horizontal_um" && ok || bad "each simulation keeps its own truth"

# Robustness (fuzzing findings): located errors with exit 1, never exit 3 or a quoted file.
printf '{"lines": [\n  {"name": "A", "start": [0, 1e309], "direction": [1, 0], "spacing": 10, "heights": [0, 1, 2]}]}\n' > big.json
expect_code 1 "$T" surface --lines big.json -o o.json
grep -q "big.json:2:30: the number '1e309' is out of range" err.txt && ok || bad "1e309 located: $(cat err.txt)"
for from in /dev/zero . missing.json; do
  printf '{"lines": [{"name": "A", "start": [0, 0], "direction": [1, 0], "from": "%s"}]}\n' "$from" > from.json
  expect_code 1 "$T" surface --lines from.json -o o.json
  grep -q "from.json:1:[0-9]*: line 'A': " err.txt && [ "$(wc -l <err.txt)" -eq 1 ] && ok || bad "from $from: $(head -c 300 err.txt)"
done
printf 'x,a,b,c\r0,1,2,3\r10,1,2,3\r20,1,2,3\r30,1,2,q\r' > cr.csv
expect_err "cr.csv:5:8: 'q' is not a number" "$T" separate --input cr.csv --output o.json
printf '{"chain": "FYXZ", "ranges": {"x": [0, 800], "y": [0, 600], "z": [0, 1e300]}}' > absurd.json
expect_code 1 "$T" machine error absurd.json bg-cmd.csv
grep -q "absurd.json:1:[0-9]*: 'ranges.z\[1\]' = 1e+300 is out of range" err.txt && ok || bad "1e300 in machine.json: $(cat err.txt)"

# space: progress with the time left, no figure that was not computed, refusals before work.
echo '{"spacing": 100}' > p0.json
TRUEAXIS_PROGRESS=always "$T" space --machine small.json --plan p0.json -o s0.json >out.txt 2>err.txt && ok || bad "space without monte carlo"
grep -q "% done, " err.txt && grep -q "standard uncertainty: not computed" out.txt && grep -q "at least RMS" out.txt && ok || bad "space progress and not-computed: $(cat out.txt err.txt)"
grep -q "uncertainty was not computed" err.txt && grep -q '"predicted_rms_at_least"' s0.json && ! grep -q '"uncertainty_rms": 0' s0.json && ok || bad "space.json: no uncomputed figure"
echo '{"spacing": 1}' > p1.json
expect_err "spacing 1 mm gives a" "$T" space --machine small.json --plan p1.json -o o.json

# Outputs: a write error is an error; one rule for missing directories; whole files only.
printf 'x,y,z\n1,0,0\n0,1,0\n-1,0,0\n0,-1,0\n0,0,1\n0.6,0.8,0\n' > sph.csv
expect_err "/dev/full: write error" "$T" fit sphere --input sph.csv --output /dev/full
expect_err "nodir/r.html: the directory 'nodir' does not exist" "$T" surface --lines lines.json -o o.json --report nodir/r.html
expect_err "nodir/r.html: the directory 'nodir' does not exist" "$T" report rd.json -o nodir/r.html
expect_err "nodir/f.json: the directory 'nodir' does not exist" "$T" fit sphere --input sph.csv --output nodir/f.json
printf 'x,y,z\n2,0,0\n0,2,0\n-2,0,0\n0,-2,0\n0,0,2\n1.2,1.6,0\n' > sph2.csv
for i in 1 2 3 4 5 6 7 8; do
  "$T" fit sphere -q --input sph.csv --output race.json & "$T" fit sphere -q --input sph2.csv --output race.json & wait
  python3 -c "import json,sys; d=json.load(open('race.json')); sys.exit(0 if abs(d['diameter']-2)<1e-9 or abs(d['diameter']-4)<1e-9 else 1)" || bad "concurrent writers left a mixed file"
done
ls race.json.partial-* >/dev/null 2>&1 && bad "temporary files left behind" || ok

# A wrong touch in measurements.json is refused by name, or left out with --drop-outliers.
python3 -c "
import json; d = json.load(open('bg-meas.json')); d['placements'][1]['balls'][7]['points'][3][0] += 11000
json.dump(d, open('bg-wrong.json', 'w'))"
expect_err "placement 2: ball [0-9]*: point 4 is .* mm off the sphere" "$T" ballgauge --gauge bg-gauge.json --measurements bg-wrong.json --output o.json
"$T" ballgauge --gauge bg-gauge.json --measurements bg-wrong.json --output o.json --drop-outliers >out.txt 2>err.txt && grep -q "warning: bg-wrong.json: placement 2: ball [0-9]*: point 4 is" err.txt && ok || bad "--drop-outliers: $(cat err.txt)"

# One grammar: flags like every other command, --report wherever a result is written.
expect_ok "$T" machine error --machine machine.json --input bg-cmd.csv -o me-flags.csv
expect_ok "$T" machine error machine.json bg-cmd.csv -o me-pos.csv
cmp -s me-flags.csv me-pos.csv && ok || bad "machine error: flags and positionals agree"
expect_ok "$T" separate --input p3.csv --output sr.json --report sr.html
grep -q "uPlot" sr.html && ok || bad "separate --report"
expect_ok "$T" simulate guideway5d --layout gw.json --stations 20 -o gs.csv
[ "$(wc -l <gs.csv)" -eq 21 ] && ok || bad "simulate guideway5d --stations"

# 'trueaxis report FILE' reads every result file trueaxis writes, by its "kind".
expect_ok "$T" fit sphere --input sph.csv --output sph-fit.json
for pair in r-lsq.json:separation moody.json:surface space.json:space gw-sim.json:guideway bg-ls-map.json:"ballgauge map" bg-verify.json:"length verification" sph-fit.json:fit; do
  f=${pair%%:*}; kind=${pair#*:}
  grep -q "\"kind\": \"$kind\"" "$f" || bad "$f has kind '$kind'"
  if "$T" report "$f" -o "rep-$f.html" >out.txt 2>err.txt && grep -q "($kind)" out.txt && grep -q "<table>" "rep-$f.html"; then ok; else bad "report $f: $(cat err.txt)"; fi
done
grep -q "Drag across a plot" rep-sph-fit.json.html && bad "a report without plots promises zoom" || ok
expect_err "model.json: a parametric model is drawn with its map" "$T" report bg-model.json -o o.html
echo '{"hello": 1}' > notours.json
expect_err "notours.json:1:1: not a trueaxis result file" "$T" report notours.json -o o.html

# Reports a metrologist would sign: no internal words, a list of references.
for f in rep-*.html sr.html; do
  grep -qi "spec 0\|(seed)\|the paper's\|seed method" "$f" && bad "$f speaks of specs, seeds or the paper" || ok
done
grep -q "<h2>References</h2>" rep-sph-fit.json.html && grep -q "ISO 10360-6" rep-sph-fit.json.html && ok || bad "fit report cites its sources"
"$T" --help > help.txt; for c in separate surface space fit ballgauge verify-lengths guideway; do "$T" help $c >> help.txt; done
grep -qi "spec 0\|the seed\|the paper's" help.txt && bad "help speaks of specs, seeds or the paper" || ok

# E0 against a user-given MPE: verdict, envelope, JSON; a malformed MPE is a usage error.
expect_ok "$T" verify-lengths --map bg-ls-map.json -i bg-lengths.csv -o bg-e0.json --report bg-e0.html --mpe "1.5+L/300"
grep -q "E0 after the grid correction against MPE 1.5+L/300 µm: PASS" out.txt && grep -q '"e0"' bg-e0.json && grep -q "E0 envelope" bg-e0.html && ok || bad "verify-lengths --mpe: $(cat out.txt)"
expect_ok "$T" verify-lengths --map bg-ls-map.json -i bg-lengths.csv -o bg-e0t.json --mpe "0.1"
grep -q "E0 after the grid correction against MPE 0.1 µm: FAIL" out.txt && ok || bad "a tight MPE fails"
expect_code 2 "$T" verify-lengths --map bg-ls-map.json -i bg-lengths.csv -o o.json --mpe "1.5+L/x"

# New inputs refuse bad values: --meta without '=', a result file with a broken reference, and
# 'examples' over existing files (nothing written without --force).
expect_code 2 "$T" report rd.json -o o.html --meta novalue
python3 -c "
import json; d = json.load(open('moody.json')); d['crossings'][0]['lines'][0] = 'nope'
json.dump(d, open('badsurf.json', 'w'), indent=1)"
expect_err "badsurf.json:[0-9]*:[0-9]*: line 'nope' is not in 'lines'" "$T" report badsurf.json -o o.html
mkdir -p ex && (cd ex && "$T" examples -q) && ok || bad "examples"
expect_err "lines.json: exists; nothing was written (use --force to overwrite)" "$T" examples -o ex
expect_ok "$T" examples -o ex --force -q

# Design data for scanning: sections of NIST's I++ test part, paths, and refusals.
expect_ok "$T" design --step "$DATA/ippdme/ipp_simple.stp" --section "origin=0,0,37.5;normal=0,0,1;name=mid" -o design.json --path path.csv
grep -q "mid.1: closed contour of 400.000 mm, material on the left" out.txt && grep -q "mid.2: closed contour of 157.080 mm, material on the right" out.txt && ok || bad "design: ipp sections $(cat out.txt)"
head -1 path.csv | grep -q "^section,segment,length_mm,speed_mm_s" && [ "$(grep -c '^mid.1,' path.csv)" -ge 8 ] && ok || bad "design --path csv"
expect_ok "$T" design --design design.json --tip-radius 2 --pushing 0.5 -q
# The CAD part (Open CASCADE) is opened when a command needs it, not at every start: the dynamic
# loader's own log of the files it maps.
LD_DEBUG=files "$T" --version >/dev/null 2>ld.txt
if ! grep -q "file=libfmt" ld.txt; then bad "LD_DEBUG=files shows no loads: $(head -c 300 ld.txt)"
elif grep -q "libtrueaxis_occt\|libTKernel" ld.txt; then bad "--version opens the CAD library"
else ok; fi
LD_DEBUG=files "$T" design --design design.json -q >/dev/null 2>ld.txt
grep -q "file=.*libtrueaxis_occt.so" ld.txt && grep -q "file=libTKernel" ld.txt && ok || bad "design --design does not open the CAD library"
expect_code 2 "$T" design --step "$DATA/ippdme/ipp_simple.stp" --section "origin=0,0;normal=0,0,1"
expect_code 2 "$T" design --step "$DATA/ippdme/ipp_simple.stp"
expect_code 2 "$T" design --design design.json --pushing 5
expect_err "misses the part" "$T" design --step "$DATA/ippdme/ipp_simple.stp" --section "origin=0,0,90;normal=0,0,1"
expect_err "does not fit" "$T" design --design design.json --tip-radius 30
python3 -c "
import json; d = json.load(open('design.json')); d['sections'][0]['curve']['nurbs']['knots'][3] = -500
json.dump(d, open('baddesign.json', 'w'), indent=1)"
expect_err "baddesign.json:[0-9]*:[0-9]*: section 'mid.1': knots must not decrease" "$T" design --design baddesign.json
printf 'not a step file\n' > bad.stp
expect_err "bad.stp:1:1: not a STEP file" "$T" design --step bad.stp --section "origin=0,0,25;normal=0,0,1"

expect_ok "$T" simulate part --design design.json --translate 2,0,0 --rotate 0,0,0.5 --bump mid.1,150,0.5,20 --noise 1 --seed 3 -o part.json
grep -q '"bumps"' part.json && grep -q '"sections"' part.json && grep -q "centroid moves by 2.0000 mm" out.txt && ok || bad "simulate part: $(cat out.txt)"
expect_err "bump on section 'nope': the design has no such section" "$T" simulate part --design design.json --bump nope,1,1,1 -o p.json
expect_code 2 "$T" simulate part --design design.json --translate 1,2 -o p.json
expect_code 2 "$T" simulate part --design design.json --rotate 0,0,x -o p.json
expect_code 2 "$T" simulate part --design design.json --scale-along 0,1,0 -o p.json
expect_code 2 "$T" simulate part --design design.json --bump mid.1,1,1 -o p.json
expect_err "part scale 3: must be in" "$T" simulate part --design design.json --scale 3 -o p.json

# Error-tolerant scanning: a moved part with a bump, its events, points and the truth; the second
# part of the batch scans with the corrected design and has no trajectory error.
expect_ok "$T" simulate part --design design.json --translate 1.8,-1.1,0 --bump mid.1,150,2,30 --seed 3 -o bumped.json
expect_ok "$T" scan --design design.json --part bumped.json -o scan.json --points points.csv --log events.csv --corrected-design design2.json --truth truth.csv
grep -q "2 of 2 sections scanned" out.txt && grep -q "max |distance| 0.00 µm" out.txt && ok || bad "scan summary: $(cat out.txt)"
head -1 points.csv | grep -qx "section,x,y,z,nx,ny,nz,t" && head -1 events.csv | grep -qx "t,section,arc_mm,delta_l_mm,mode,event,decision" && ok || bad "scan csv headers"
for ev in trajectory_error touch correction_applied autonomous_scan design_spliced rescan section_done; do
  grep -q ",$ev," events.csv && ok || bad "events.csv lacks $ev"
done
python3 -c "
import json; s = json.load(open('scan.json'))
assert s['ok'] and len(s['sections']) == 2, s['summary']
a, b = s['sections']
assert a['autonomous_count'] == 1 and b['autonomous_count'] == 0
assert any(c['accepted'] and c['type'] == 'translation' for c in b['corrections'])
assert abs(s['machine_time_s']['total'] - sum(x['machine_time_s']['total'] for x in s['sections'])) < 1e-6
" && ok || bad "scan.json content"
expect_ok "$T" simulate part --design design.json --translate 1.8,-1.1,0 --bump mid.1,150,2,30 --seed 4 -o bumped2.json
expect_ok "$T" scan --design design2.json --part bumped2.json -o scan2.json --log events2.csv
grep -q ",trajectory_error," events2.csv && bad "second part still has trajectory errors" || ok
expect_err "section 'mid.1': trajectory error" "$T" scan --design design.json --part bumped.json --strategy design -o scan3.json -q
expect_code 2 "$T" scan --design design.json --part bumped.json --strategy fast -o s.json
# scan.json carries what its report needs: the same tables and plots as the run's own report.
expect_ok "$T" report scan.json -o scan-from-json.html
grep -q "every decision of the flow" scan-from-json.html && grep -q "trajectory error ΔL along each design-value scan" scan-from-json.html && ok || bad "report scan.json"
expect_code 2 "$T" scan --design design.json --part bumped.json --tolerance 0 -o s.json
expect_code 2 "$T" scan --design design.json --part bumped.json --margin -1 -o s.json
# A CMM with geometric errors: the part scans as before, and its points carry the machine's errors.
expect_ok "$T" scan --design design2.json --part bumped2.json --machine machine.json -o scan4.json --truth truth4.csv
grep -q "CMM with the geometric errors of 'random FXYZ machine, seed 3'" out.txt && ok || bad "scan --machine: $(cat out.txt)"
python3 -c "
import csv, json; s = json.load(open('scan4.json'))
assert s['ok'] and s['cmm']['geometric_errors'] == 'random FXYZ machine, seed 3', s['cmm']
worst = max(abs(float(r['distance_um'])) for r in csv.DictReader(open('truth4.csv')))
assert 1 < worst < 100, worst
" && ok || bad "scan --machine: points do not carry the machine's errors"
expect_err "the part does not fit on machine" "$T" scan --design design.json --part bumped.json --machine small.json --part-origin 290,100,75 -o s.json
expect_code 2 "$T" scan --design design.json --part bumped.json --part-origin 1,2,3 -o s.json
# A spiral over a sphere (a space curve with its surface normals): scanned along its design when
# the part is where it should be; moved 2 mm, an error exit that says why (no plane contains it).
python3 -c "
import json, math
n = 1301; pts = []; nor = []
for i in range(n):
    t = i / (n - 1); th = math.radians(20 + 50 * t); ph = 6 * math.pi * t
    u = [math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)]
    pts.append([50 + 50 * u[0], 50 + 50 * u[1], 50 * u[2]]); nor.append(u)
json.dump({'sections': [{'name': 'spiral', 'closed': False, 'curve': {'polyline': pts}, 'normals': nor}]},
          open('spiral.json', 'w'))"
expect_ok "$T" design --design spiral.json
grep -q "spiral: open space curve of 647.07. mm" out.txt && ok || bad "design of a space curve: $(cat out.txt)"
expect_ok "$T" simulate part --design spiral.json --seed 1 -o spiral-part.json
expect_ok "$T" scan --design spiral.json --part spiral-part.json -o spiral-scan.json
expect_ok "$T" simulate part --design spiral.json --translate 2,0,0 --seed 1 -o spiral-moved.json
expect_err "section 'spiral': the path is three-dimensional" "$T" scan --design spiral.json --part spiral-moved.json -o spiral-scan2.json --report spiral.html -q
[ -s spiral.html ] && grep -q '"status": "error"' spiral-scan2.json && ok || bad "a failed space-curve scan still writes its files"

# I++ DME: NIST's programs and recorded responses are valid; its parser-error program is not, and
# each bad line is named with its place and the specification's error number.
NIST="$DATA/ippdme/nist"
expect_ok "$T" ipp check "$NIST/GoTo.prg" "$NIST/GoTo.res" "$NIST/PtMeas.prg" "$NIST/PtMeas.res"
grep -q "lines checked (.* commands, .* responses): all valid I++ DME" out.txt && ok || bad "ipp check: $(cat out.txt)"
if "$T" ipp check "$NIST/numbersErrorCmd.prg" >out.txt 2>err.txt; then bad "ipp check should fail on NIST's number errors"; else
  grep -q "numbersErrorCmd.prg:[0-9]*:14: error 0509: a number of 17 digits (at most 16)" out.txt && ok || bad "ipp check numbers: $(head -3 out.txt)"
fi
printf '00001 StartSession()\r\n00002 GoTo(X(1), X(2))\r\n00003 AbortE()\r\n00004 Home()\n' > prog.prg
"$T" ipp check prog.prg >out.txt 2>&1
[ "$(grep -c ': error ' out.txt)" -eq 2 ] && grep -q "prog.prg:2:18: error 0502: GoTo: X is given twice" out.txt && grep -q "prog.prg:3:7: error 0001" out.txt && ok || bad "ipp check prog: $(cat out.txt)"
expect_code 2 "$T" ipp
expect_code 2 "$T" ipp check

# start_server ARGS...: 'trueaxis serve ARGS' in the background (SERVE; its output in serve.txt),
# and PORT once it says where it listens. That may take seconds on a loaded machine (a server with
# a part opens the CAD library first), so it is given 60 s; a server that never says is killed
# and named (PORT 1 then, so that its clients fail at once instead of waiting).
start_server() {
  "$T" serve "$@" >serve.txt 2>&1 &
  SERVE=$!
  for _ in $(seq 600); do
    PORT=$(sed -n 's/.*on 127.0.0.1:\([0-9]*\),.*/\1/p' serve.txt)
    [ -n "$PORT" ] && return 0
    kill -0 "$SERVE" 2>/dev/null || break
    sleep 0.1
  done
  bad "serve $*: no address (it stopped, or 60 s passed): $(cat serve.txt)"
  kill "$SERVE" 2>/dev/null
  PORT=1
}
# end_server: the server's exit status once its sessions are done; one that is still running
# 60 s later (its client never came) is killed and named, so the test cannot hang.
end_server() {
  for _ in $(seq 600); do
    kill -0 "$SERVE" 2>/dev/null || { wait "$SERVE"; return; }
    sleep 0.1
  done
  kill "$SERVE" 2>/dev/null
  wait "$SERVE"
  bad "serve did not stop after its sessions: $(cat serve.txt)"
  return 1
}
# The virtual CMM served over I++ DME: NIST's programs run through 'ipp run' and compared with
# NIST's recordings; the server stops after the sessions asked for.
start_server --port 0 --time-scale 0 --sessions 3
expect_ok "$T" ipp run "$NIST/PtMeas.prg" --port "$PORT" --expect "$NIST/PtMeas.res" --log client.log
grep -q "the structure matches" out.txt && grep -q "00210 # Y(0.77900)" out.txt && grep -q "sent: 00080 PtMeas" client.log && ok || bad "ipp run PtMeas: $(tail -3 out.txt)"
# Error.prg: the specification's 2500 where NIST's server answered 1008 — named, exit 1.
if "$T" ipp run "$NIST/Error.prg" --port "$PORT" --expect "$NIST/Error.res" -q >out.txt 2>err.txt; then bad "ipp run Error.prg should differ"; else
  grep -q "tag 00010: expected \[& !1008 %\], got \[& !2500 %\]" out.txt && grep -q "1 tag(s) differ" out.txt && ok || bad "ipp run Error: $(cat out.txt err.txt)"
fi
# A bad program line is sent as it is (the server answers it) and named with file:line:column.
printf '00001 StartSession()\r\n\\\\\r\n00002 GoTo(X(1), X(2))\r\n\\\\\r\n09999 EndSession()\r\n' > bad.prg
expect_ok "$T" ipp run bad.prg --port "$PORT"
grep -q "bad.prg:3:18: error 0502: GoTo: X is given twice (sent as it is)" err.txt && grep -q '00002 ! Error(3, 0502, "column 18: GoTo: X is given twice"' out.txt && ok || bad "ipp run bad line: $(cat err.txt out.txt)"
end_server && grep -q "stopped after 3 session(s)" serve.txt && ok || bad "serve --sessions 3: $(cat serve.txt)"
expect_err "cannot connect to an I++ DME server at 127.0.0.1:1" "$T" ipp run "$NIST/PtMeas.prg" --port 1
# The scanning controller over I++ DME: the part served, scanned through the protocol, makes the
# same decisions as in process (the lines per section without their point counts and times).
start_server --part part.json --port 0 --time-scale 0 --sessions 1
flow() { grep -E "^mid\.[0-9]+: " "$1" | sed -E 's/ — [0-9]+ points,/ —/; s/, [0-9.]+ s$//'; }
"$T" scan --design design.json --part part.json -o scan-here.json >here.txt 2>&1
expect_ok "$T" scan --design design.json --cmm "ipp://127.0.0.1:$PORT" --part part.json -o scan-ipp.json --truth truth-ipp.csv
cp out.txt there.txt
[ -n "$(flow here.txt)" ] && [ "$(flow here.txt)" = "$(flow there.txt)" ] && grep -q "scanned through the I++ DME server at ipp://127.0.0.1:$PORT" there.txt && ok || bad "scan --cmm differs from in process: $(cat here.txt there.txt)"
end_server
# A server of I++ DME 1.4.1 (no ScanOnCurve): the same decisions, scanning point by point.
start_server --part part.json --port 0 --time-scale 0 --sessions 1 --dme-version 1.4.1
expect_ok "$T" scan --design design.json --cmm "ipp://127.0.0.1:$PORT" --part part.json -o scan-141.json --point-step 2 --truth truth-141.csv
cp out.txt there141.txt
[ "$(flow here.txt)" = "$(flow there141.txt)" ] && grep -q "speaks I++ DME 1.4.1, which has no ScanOnCurve (1.4.2): scanning point by point, a PtMeas every 2 mm" err.txt && ok || bad "scan --cmm on a 1.4.1 server: $(cat here.txt there141.txt err.txt)"
end_server
expect_code 2 "$T" serve --dme-version 1.3 --port 0
expect_code 2 "$T" scan --design design.json --cmm "ipp://127.0.0.1:1" --point-step 0 -o s.json
expect_code 2 "$T" scan --design design.json --cmm "127.0.0.1:$PORT" -o s.json
grep -q "expected ipp://HOST:PORT" err.txt && ok || bad "scan --cmm bad address: $(cat err.txt)"
expect_code 2 "$T" scan --design design.json -o s.json
expect_err "cannot connect to an I++ DME server at 127.0.0.1:1" "$T" scan --design design.json --cmm ipp://127.0.0.1:1 -o s.json
# A ball gauge measured through the server with PtMeas gives the map simulated in process (both
# without noise: the same to a few nm); the placements' balls stand in the server's world.
expect_ok "$T" simulate ballgauge --machine machine.json --sections 2 --tip-radius 1 --gauge bgi-gauge.json --measurements bgi-here.json --truth bgi-truth.csv --balls bgi-balls.csv
head -1 bgi-balls.csv | grep -qx "x,y,z,diameter" && [ "$(wc -l < bgi-balls.csv)" -eq 61 ] && ok || bad "simulate ballgauge --balls: $(head -2 bgi-balls.csv)"
start_server --machine machine.json --balls bgi-balls.csv --port 0 --time-scale 0 --sessions 1
expect_code 2 "$T" simulate ballgauge --cmm "ipp://127.0.0.1:$PORT" --noise 0.5
expect_code 2 "$T" simulate ballgauge --cmm "127.0.0.1:$PORT"
expect_ok "$T" simulate ballgauge --machine machine.json --sections 2 --cmm "ipp://127.0.0.1:$PORT" --gauge bgi-gauge.json --measurements bgi-there.json --truth bgi-truth.csv
grep -q "measured 2 placements of a 40-ball frame gauge through the I++ DME server at ipp://127.0.0.1:$PORT" out.txt && grep -q "60 balls of bgi-balls.csv" serve.txt && ok || bad "simulate ballgauge --cmm: $(cat out.txt serve.txt)"
end_server
# A 1.4.1 server cannot tell its tip radius (Tool.AvrRadius is 1.4.2's): refused until it is given.
start_server --machine machine.json --balls bgi-balls.csv --port 0 --time-scale 0 --sessions 2 --dme-version 1.4.1
expect_err "speaks I++ DME 1.4.1, which has no Tool.AvrRadius (1.4.2): give the stylus tip's radius" "$T" simulate ballgauge --machine machine.json --sections 2 --cmm "ipp://127.0.0.1:$PORT" --gauge bgi-gauge.json --measurements bgi-141.json --truth bgi-truth.csv
expect_ok "$T" simulate ballgauge --machine machine.json --sections 2 --cmm "ipp://127.0.0.1:$PORT" --tip-radius 1 --gauge bgi-gauge.json --measurements bgi-141.json --truth bgi-truth.csv
grep -q "tip radius 1 mm" out.txt && ok || bad "simulate ballgauge --cmm on 1.4.1: $(cat out.txt)"
end_server
expect_ok "$T" ballgauge --gauge bgi-gauge.json --measurements bgi-here.json -o bgi-here-map.json
expect_ok "$T" ballgauge --gauge bgi-gauge.json --measurements bgi-there.json -o bgi-there-map.json
python3 -c "
import json, sys
a = json.load(open('bgi-here-map.json'))['points']; b = json.load(open('bgi-there-map.json'))['points']
d = max(abs(p['error'][k] - q['error'][k]) for p, q in zip(a, b) for k in range(3))
big = max(abs(v) for p in a for v in p['error'])
sys.exit(0 if len(a) == len(b) == 60 and d < 0.05 and big > 2 else 1)" && ok || bad "the ball-gauge map through I++ DME differs from the one in process"
printf 'x,y,z,diameter\n1,2,3,-25\n' > bad-balls.csv
expect_err "bad-balls.csv:2:7: ball diameter -25 mm: must be > 0" "$T" serve --balls bad-balls.csv --port 0
expect_code 2 "$T" serve --port 70000
expect_ok "$T" serve --help
grep -q "Without --part each probing meets" out.txt && ok || bad "serve --help"

# Circular test (ISO 230-4): a ballbar on the virtual machine, the figures and the diagnosis,
# the tolerances' exit status, bad traces refused at file:line:col.
printf '{"X": {"backlash_um": 4}, "Y": {"backlash_um": 2, "spike_um": 3, "spike_decay_deg": 6}}\n' > servo.json
expect_ok "$T" simulate circular --machine-seed 4 --plane XY --radius 100 --feed 1000 --servo servo.json --noise 0.1 -o circ.csv
head -1 circ.csv | grep -qx "direction,angle_deg,deviation_um" && [ -s circ-truth.json ] && ok || bad "simulate circular files"
expect_ok "$T" circular --input circ.csv --plane XY --radius 100 --feed 1000 -o circ.json --report circ.html
python3 -c "
import json, sys
r = json.load(open('circ.json')); t = json.load(open('circ-truth.json')); d = r['diagnosis']
ok = r['kind'] == 'circular' and set(r['G_um']) == {'ccw', 'cw'} and r['H_um'] > 0
ok = ok and abs(d['backlash_um']['X']['value'] - 4) < 0.3 and abs(d['backlash_um']['Y']['value'] - 2) < 0.3
ok = ok and abs(d['reversal_spike_um']['Y']['ccw']['value'] - 3) < 0.3 and d['backlash_um']['X']['u'] > 0
sys.exit(0 if ok else 1)" && ok || bad "circular: figures and diagnosis against the truth"
grep -q "polar plot" circ.html && ok || bad "circular report's polar plot"
expect_ok "$T" report circ.json -o circ-again.html
grep -q "polar plot" circ-again.html && grep -q "Diagnosis: the trace explained by its causes" circ-again.html && ok || bad "report of a saved circular result"
expect_code 1 "$T" circular --input circ.csv -o circ2.json --tolerance G=0.5
grep -q "tolerance not met: G = " err.txt && ok || bad "circular tolerance message"
expect_code 2 "$T" circular --input circ.csv -o circ2.json --tolerance F=3
printf 'direction,angle_deg,deviation_um\nccw,0,1.5\nup,1,1.2\n' > bad-dir.csv
expect_err "bad-dir.csv:3:1: direction 'up'" "$T" circular --input bad-dir.csv -o x.json
printf 'direction,angle_deg,deviation_um\nccw,0,abc\n' > bad-num.csv
expect_err "bad-num.csv:2:7: 'abc' is not a number" "$T" circular --input bad-num.csv -o x.json
printf 'direction,angle_deg\nccw,0\n' > bad-head.csv
expect_err "bad-head.csv:1:1: the header has no 'deviation_um' column" "$T" circular --input bad-head.csv -o x.json
head -100 circ.csv > part.csv
expect_err "part.csv:100:22: the ccw samples leave 350.6° of the circle without data" "$T" circular --input part.csv -o x.json --plane XY
expect_code 2 "$T" circular --input circ.csv -o x.json --plane XZ
# A raw time series: the same test, its times turned into angles with the stated feed and radius.
python3 -c "
import csv, math
w = 1000 / 60 / 100
with open('circ-ts.csv', 'w') as f:
    f.write('t_s,deviation_um\\n')
    for d, a, v in list(csv.reader(open('circ.csv')))[1:]:
        a = math.radians(float(a))
        f.write('%.6f,%s\\n' % (a / w if d == 'ccw' else 1000 + (2 * math.pi - a) / w, v))"
expect_err "circ-ts.csv:1:1: a time series needs the feed" "$T" circular --input circ-ts.csv -o x.json
expect_ok "$T" circular --input circ-ts.csv --feed 1000 --radius 100 -o circ-ts.json
python3 -c "
import json, sys
a = json.load(open('circ.json')); b = json.load(open('circ-ts.json'))
sys.exit(0 if abs(a['G_um']['ccw'] - b['G_um']['ccw']) < 0.05 else 1)" && ok || bad "circular from a time series"
expect_err "circ-ts.csv:" "$T" circular --input circ-ts.csv --feed 1000 --radius 100 --order ccw -o x.json
# The compensation: written for four controllers and read back; the test rerun with it loaded.
expect_ok "$T" circular --input circ.csv -o circ.json --compensation comp --travel 0,600
for f in linuxcnc-backlash.ini heidenhain-backlash.mp fanuc-backlash.txt siemens-backlash.ini siemens-squareness.ini heidenhain-squareness.com compensation.json; do
  [ -s "comp/$f" ] || bad "compensation file $f"
done
grep -q "read back and checked" out.txt && grep -q "not written for LinuxCNC: squareness" out.txt && ok || bad "compensation summary"
expect_ok "$T" simulate circular --machine-seed 4 --plane XY --radius 100 --feed 1000 --servo servo.json --noise 0.1 --compensation comp/compensation.json -o circ-after.csv
expect_ok "$T" circular --input circ-after.csv -o circ-after.json --before circ.json --report circ-after.html
python3 -c "
import json, sys
b = json.load(open('circ.json')); a = json.load(open('circ-after.json'))
g = lambda r: max(r['G_um'].values())
ok = g(a) < 0.7 * g(b) and all(abs(a['diagnosis']['backlash_um'][k]['value']) < 0.1 for k in 'XY')
sys.exit(0 if ok else 1)" && ok || bad "circular: G after the compensation"
grep -q "cw, before" circ-after.html && ok || bad "before and after on one polar plot"
expect_err "comp/compensation.json: a compensation for XY; this test runs in YZ" "$T" simulate circular --machine-seed 4 --plane YZ --compensation comp/compensation.json -o x.csv
expect_err "a test in XY of radius 100 mm; this one is in XY of 50 mm" "$T" circular --input circ-after.csv --radius 50 -o x.json --before circ.json
expect_code 2 "$T" circular --input circ.csv -o x.json --compensation comp --travel 600,0

# CMM acceptance (ISO 10360-2, -5) on the virtual CMM of a machine file, with the example set-up.
mkdir -p acc && (cd acc && "$T" examples -q) && ok || bad "examples for acceptance"
expect_ok "$T" simulate machine --seed 3 -o acc/m.json
expect_code 1 "$T" acceptance e0 --machine acc/m.json --artefacts acc/acceptance.json --mpe "1.5+L/300" -o acc/e0.json
grep -q "E0: 105 lengths in 7 positions; .*: does not conform -> acc/e0.json" out.txt && ok || bad "acceptance e0 summary: $(cat out.txt)"
python3 -c "
import json, sys
r = json.load(open('acc/e0.json'))
ok = r['kind'] == 'acceptance-e0' and len(r['lengths']) == 105 and r['pass'] is False
ok = ok and r['E0_max_um'] == max(abs(l['error_um']) for l in r['lengths'])
ok = ok and all(len(l['endpoints']) == 2 and len(l['endpoints'][0]) == 3 for l in r['lengths'])
sys.exit(0 if ok else 1)" && ok || bad "acceptance e0 json"
expect_ok "$T" acceptance e0 --machine acc/m.json --artefacts acc/acceptance.json --mpe "40" -o acc/e0-wide.json -q --report acc/e0.html --meta "machine=Prismo 7"
grep -q "Length error against nominal length, one colour per position" acc/e0.html && grep -q "Prismo 7" acc/e0.html && grep -q "conforms" acc/e0.html && ok || bad "acceptance e0 report"
[ ! -s out.txt ] && ok || bad "acceptance e0 -q prints nothing on a pass"
expect_code 0 "$T" acceptance probing --machine acc/m.json --artefacts acc/acceptance.json --mpe-form 1.8 --mpe-size 1.5 --lobing 0.5 --noise 0.1 -o acc/probing.json
grep -q "PForm .* µm, PSize .*; PForm conforms" out.txt && ok || bad "acceptance probing: $(cat out.txt)"
expect_ok "$T" acceptance probing --machine acc/m.json --artefacts acc/acceptance.json --lobing 0.5 -o acc/probing2.json --report acc/probing.html -q
grep -q "Radial deviations of the 25 points" acc/probing.html && ok || bad "acceptance probing report"
expect_ok "$T" report acc/e0.json -o acc/e0-again.html
grep -q "Length measuring error (ISO 10360-2)" acc/e0-again.html && grep -q "acceptance-e0" out.txt && ok || bad "report of a saved acceptance result: $(cat out.txt)"
expect_code 2 "$T" acceptance e0 --machine acc/m.json --artefacts acc/acceptance.json -o x.json
expect_code 2 "$T" acceptance e0 --machine acc/m.json --artefacts acc/acceptance.json --mpe "fast" -o x.json
grep -q "MPE 'fast'" err.txt && ok || bad "acceptance: a bad MPE named: $(cat err.txt)"
python3 -c "
import json; d = json.load(open('acc/acceptance.json')); d['placements'][0]['centre'][0] += 400
json.dump(d, open('acc/outside.json', 'w'), indent=1)"
expect_code 1 "$T" acceptance e0 --machine acc/m.json --artefacts acc/outside.json --mpe 3 -o x.json
grep -q "outside the volume" err.txt && ok || bad "acceptance: a placement outside the volume: $(cat err.txt)"
# The same test over I++ DME on the served virtual CMM: the same lengths as in process.
start_server --machine acc/m.json --artefacts acc/acceptance.json --port 0 --time-scale 0 --sessions 1
grep -q "35 gauge blocks and the reference sphere of acc/acceptance.json (a position at a time)" serve.txt && ok || bad "serve --artefacts: $(cat serve.txt)"
expect_code 1 "$T" acceptance e0 --cmm "ipp://127.0.0.1:$PORT" --machine acc/m.json --artefacts acc/acceptance.json --mpe "1.5+L/300" -o acc/e0-ipp.json
end_server
python3 -c "
import json, sys
a = json.load(open('acc/e0.json')); b = json.load(open('acc/e0-ipp.json'))
ok = b['complete'] and len(b['lengths']) == 105
ok = ok and max(abs(x['error_um'] - y['error_um']) for x, y in zip(a['lengths'], b['lengths'])) < 0.05
sys.exit(0 if ok else 1)" && ok || bad "acceptance e0 over I++ DME agrees with the virtual CMM in process"
expect_code 2 "$T" acceptance e0 --cmm "ipp://127.0.0.1:1" --artefacts acc/acceptance.json --mpe 3 -o x.json
grep -q "travel" err.txt && ok || bad "acceptance --cmm without a travel: $(cat err.txt)"
expect_code 2 "$T" acceptance e0 --cmm "ipp://127.0.0.1:1" --travel 0,0,0,800,-600,400 --artefacts acc/acceptance.json --mpe 3 -o x.json
grep -q "high end must lie above its low end" err.txt && ok || bad "acceptance --travel reversed: $(cat err.txt)"
expect_err "cannot connect to an I++ DME server at 127.0.0.1:1" "$T" acceptance e0 --cmm "ipp://127.0.0.1:1" --travel 0,0,-100,800,600,400 --artefacts acc/acceptance.json --mpe 3 -o x.json
# --correction: the virtual CMM corrects what it reads with a ball-gauge map, as its controller
# would; the map covers part of the volume, so E0 falls but does not vanish.
"$T" simulate ballgauge --machine acc/m.json --gauge acc/g.json -o acc/meas.json --truth acc/bt.csv -q && "$T" ballgauge --gauge acc/g.json --measurements acc/meas.json --output acc/map.json -q && ok || bad "a ball-gauge map for acceptance --correction"
expect_code 1 "$T" acceptance e0 --machine acc/m.json --artefacts acc/acceptance.json --mpe "1.5+L/300" --correction acc/map.json -o acc/e0-corrected.json
python3 -c "
import json, sys
a = json.load(open('acc/e0.json')); b = json.load(open('acc/e0-corrected.json'))
sys.exit(0 if b['E0_max_um'] < 0.8 * a['E0_max_um'] else 1)" && ok || bad "acceptance e0 --correction lowers E0"
expect_code 2 "$T" acceptance e0 --cmm "ipp://127.0.0.1:1" --travel 0,0,-100,800,600,400 --correction acc/map.json --artefacts acc/acceptance.json --mpe 3 -o x.json
grep -q "trueaxis serve --correction" err.txt && ok || bad "acceptance --cmm --correction: $(cat err.txt)"
# --pause: the operator sets up each position; q stops the run, what was measured is kept.
printf '\n\nq\n' | "$T" acceptance e0 --machine acc/m.json --artefacts acc/acceptance.json --mpe 3 --pause -o acc/e0-paused.json >out.txt 2>err.txt; rc=$?
[ "$rc" -eq 1 ] && grep -q "Set up position 3 of 7, 'space diagonal 3 (+X−Y+Z)': D3-" err.txt && grep -q "stopped after 30 lengths: by the operator before position 'space diagonal 3" err.txt && ok || bad "acceptance e0 --pause: $rc $(cat err.txt)"
python3 -c "
import json, sys
r = json.load(open('acc/e0-paused.json'))
sys.exit(0 if r['complete'] is False and len(r['lengths']) == 30 else 1)" && ok || bad "a stopped run keeps its 30 lengths"
# E150: a set-up for the volume the offset stylus reaches, measured in process and over I++ DME
# (the served CMM's Probe1 is the offset stylus): the same lengths, in two positions.
expect_ok "$T" acceptance setup --machine acc/m.json --stylus-offset 150 -o acc/acc150.json
grep -q "35 gauge blocks in 7 positions .* with the offset stylus -> acc/acc150.json" out.txt && ok || bad "acceptance setup: $(cat out.txt)"
expect_code 1 "$T" acceptance e0 --machine acc/m.json --artefacts acc/acc150.json --stylus-offset 150 --mpe "1.5+L/300" -o acc/e150.json --report acc/e150.html
grep -q "E150: 30 lengths in 2 positions; .*stylus offset (150, 0, 0) mm" out.txt && grep -q "Length measuring error E150" acc/e150.html && ok || bad "acceptance e0 --stylus-offset: $(cat out.txt)"
expect_code 1 "$T" acceptance e0 --machine acc/m.json --artefacts acc/acceptance.json --stylus-offset 150 --mpe 3 -o x.json
grep -q "outside the volume" err.txt && ok || bad "E150 on the vertical stylus's set-up: $(cat err.txt)"
start_server --machine acc/m.json --stylus-offset 150 --artefacts acc/acc150.json --port 0 --time-scale 0 --sessions 1
expect_code 1 "$T" acceptance e0 --cmm "ipp://127.0.0.1:$PORT" --machine acc/m.json --stylus-offset 150 --artefacts acc/acc150.json --position "along X" --position "along Y" --mpe "1.5+L/300" -o acc/e150-ipp.json
end_server
expect_code 1 "$T" acceptance e0 --machine acc/m.json --stylus-offset 150 --artefacts acc/acc150.json --position "along X" --position "along Y" --mpe "1.5+L/300" -o acc/e150-xy.json
python3 -c "
import json, sys
a = json.load(open('acc/e150-xy.json')); b = json.load(open('acc/e150-ipp.json'))
ok = a['test'] == 'E150' and b['test'] == 'E150' and b['stylus_offset_mm'] == [150, 0, 0]
ok = ok and b['complete'] and len(b['lengths']) == 30 and {x['position'] for x in b['lengths']} == {'along X', 'along Y'}
ok = ok and max(abs(x['error_um'] - y['error_um']) for x, y in zip(a['lengths'], b['lengths'])) < 0.05
sys.exit(0 if ok else 1)" && ok || bad "E150 over I++ DME agrees with the virtual CMM in process"
expect_code 2 "$T" acceptance e0 --machine acc/m.json --artefacts acc/acceptance.json --position "along X" --mpe 3 -o x.json
grep -q "for E_L, with --stylus-offset" err.txt && ok || bad "acceptance e0 --position without an offset: $(cat err.txt)"
expect_code 2 "$T" acceptance e0 --machine acc/m.json --artefacts acc/acc150.json --stylus-offset 0,0,150 --mpe 3 -o x.json
grep -q "across the ram" err.txt && ok || bad "a stylus offset along the ram: $(cat err.txt)"
expect_code 2 "$T" serve --stylus-offset 150 --port 0
grep -q "needs --machine" err.txt && ok || bad "serve --stylus-offset without a machine: $(cat err.txt)"
echo '{"sphere": {"centre": [0, 0], "diameter_mm": 25}}' > acc/bad.json
# Machine records: results stored with their machine, date and state; refusals; the export.
export TRUEAXIS_DB="$PWD/acc/records.db"
rm -f "$TRUEAXIS_DB"
expect_code 1 "$T" record add acc/e0.json --machine CMM-7 --date 2025-03-01 --as-found
grep -q "no machine 'CMM-7'.*--new-machine" err.txt && ok || bad "record add: an unknown machine: $(cat err.txt)"
expect_ok "$T" record add acc/e0.json --machine CMM-7 --date 2025-03-01 --as-found --operator "J. O'Brien" --new-machine
grep -q "record 1: CMM-7 2025-03-01 acceptance-e0 as-found (E0 " out.txt && ok || bad "record add: $(cat out.txt)"
expect_ok "$T" record add acc/e0-corrected.json acc/probing.json --machine CMM-7 --date 2025-03-02 --as-left
expect_code 1 "$T" record add acc/e0.json --machine CMM-7
grep -q "already stored for machine 'CMM-7' (record 1, 2025-03-01)" err.txt && ok || bad "record add: a duplicate: $(cat err.txt)"
expect_code 1 "$T" record add acc/acceptance.json --machine CMM-7
grep -q "acc/acceptance.json" err.txt && ok || bad "record add: not a result: $(cat err.txt)"
expect_code 1 "$T" record add acc/probing2.json --machine CMM-7 --date 29/11/2026
grep -q "ISO 8601" err.txt && ok || bad "record add: a bad date: $(cat err.txt)"
expect_code 2 "$T" record add acc/probing2.json --machine CMM-7 --as-found --as-left
expect_ok "$T" record machines
grep -q "CMM-7: 3 records, 2025-03-01 … 2025-03-02" out.txt && ok || bad "record machines: $(cat out.txt)"
expect_ok "$T" record list --kind acceptance-e0
[ "$(wc -l < out.txt)" -eq 2 ] && ok || bad "record list --kind: $(cat out.txt)"
expect_ok "$T" record show 3 -o acc/stored.json
cmp -s acc/stored.json acc/probing.json && grep -q "state: as-left" out.txt && ok || bad "record show -o: $(cat out.txt)"
expect_ok "$T" record export --machine CMM-7 -o acc/records.json -q
expect_ok "$T" record export --format csv -o acc/records.csv -q
python3 -c "
import json, sys
r = json.load(open('acc/records.json'))
ok = len(r) == 3 and r[0]['machine'] == 'CMM-7' and r[0]['state'] == 'as-found' and r[0]['operator'] == \"J. O'Brien\"
ok = ok and r[2]['kind'] == 'acceptance-probing' and r[2]['figures']['PForm']['u'] > 0
e0 = json.load(open('acc/e0.json'))
ok = ok and abs(r[0]['figures']['E0']['value'] - e0['E0_max_um']) < 1e-9
sys.exit(0 if ok else 1)" && ok || bad "record export: $(head -c 600 acc/records.json)"
grep -q "^3,CMM-7,2025-03-02,acceptance-probing,as-left,.*,PForm,," acc/records.csv && ok || bad "record export csv: $(head -3 acc/records.csv)"
# A figure's trend: two dates without stated u give a drift but no uncertainty, and say so.
expect_ok "$T" record trend --machine CMM-7 --figure E0 --tolerance 30 --points all -o acc/trend.json
grep -q "CMM-7: E0: 2 points, drift .* µm/year; two points without stated uncertainties" out.txt && ok || bad "record trend: $(cat out.txt)"
python3 -c "
import json, sys
t = json.load(open('acc/trend.json'))
ok = t['kind'] == 'trend' and t['machine'] == 'CMM-7' and len(t['points']) == 2 and t['drift_per_year']['u'] is None
ok = ok and t['due']['date'] is None and t['points'][0]['state'] == 'as-found'
sys.exit(0 if ok else 1)" && ok || bad "record trend json: $(cat acc/trend.json)"
expect_code 1 "$T" record trend --machine CMM-7 --figure E9
grep -q "has no figure E9 in the records (it has: E0, PForm, PSize, R0)" err.txt && ok || bad "record trend: an unknown figure: $(cat err.txt)"
unset TRUEAXIS_DB
expect_err "acc/bad.json:1:[0-9]*: sphere.centre: three numbers" "$T" serve --artefacts acc/bad.json --port 0

# Every kind of result this script wrote, stored: each headline figure equals the file's own.
rm -f kinds.db
expect_ok "$T" record add pos-after.json --machine M --axis X --db kinds.db --new-machine -q
expect_ok "$T" record add circ-after.json p3-named.json gw-cur.json s0.json moody.json ball.json acc/map.json bg-e0.json bg-model.json scan-here.json --machine M --db kinds.db -q
expect_ok "$T" record export --db kinds.db -o kinds.json -q
python3 -c "
import json, math, sys
recs = {r['file']: r['figures'] for r in json.load(open('kinds.json'))}
f = lambda name: json.load(open(name))
p = f('pos-after.json'); c = f('circ-after.json'); s = f('p3-named.json'); g = f('gw-cur.json')
v = f('s0.json')['verification']; fl = f('moody.json')['flatness']; b = f('ball.json')['form']
m = f('acc/map.json')['grid']; sc = f('scan-here.json')
want = {
  'pos-after.json': {k + '@X': p[k] for k in 'ABEMR'},
  'circ-after.json': dict({'G_' + d + '@' + c['plane']: x for d, x in c['G_um'].items()}, **({'H@' + c['plane']: c['H_um']} if c['H_um'] is not None else {})),
  'p3-named.json': {'straightness_' + k: x['min_zone'] for k, x in s['straightness'].items() if x.get('resolved') is not False},
  'gw-cur.json': {k: x['pv'] for k, x in g['summary'].items() if x.get('resolved') is not False},
  's0.json': {'residual_max': v['after_max'], 'residual_rms': v['after_rms'], 'error_max': v['before_max']},
  'moody.json': {'flatness': fl['min_zone']},
  'ball.json': {b['name'] + '@' + f('ball.json')['element']: b['value'] * 1e3},
  'map.json': {'error_max': max(math.sqrt(x*x + y*y + z*z) for x, y, z in zip(m['ex'], m['ey'], m['ez']))},
  'bg-e0.json': {'E_worst_fraction_of_mpe': f('bg-e0.json')['e0']['before']['worst_fraction_of_mpe']},
  'bg-model.json': {},
  'scan-here.json': {'machine_time': sc['machine_time_s']['total']},
}
bad = []
for name, figs in want.items():
    got = {k: x['value'] for k, x in recs[name].items()}
    if set(got) != set(figs) or any(abs(got[k] - figs[k]) > 1e-9 * max(1, abs(figs[k])) for k in figs):
        bad.append((name, got, figs))
print(bad[:3]) if bad else None
sys.exit(1 if bad else 0)" && ok || bad "record add: each kind's headline figures are the file's own"
echo "cli: $passes passed, $fails failed"
[ "$fails" -eq 0 ]
