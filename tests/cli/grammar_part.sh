# One grammar and honest outputs: usage errors, missing inputs, suggestions, located errors,
# write errors, reports without internal words.
# One grammar: every command-line mistake exits 2 (CLI11's own codes are 105, 106, 109...).
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
