# Circular tests (ISO 230-4) with their compensation, and CMM acceptance (ISO 10360-2, -5) in
# process and over I++ DME.
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
