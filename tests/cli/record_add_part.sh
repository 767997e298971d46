# Machine records: every kind of result the earlier parts wrote, stored and read back.
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
