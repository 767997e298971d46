# Measuring jobs from the command line: separation, surfaces, the virtual machine, error space,
# guideway, positioning and controller tables, fits, ball gauges and plates, gauge blocks.
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
