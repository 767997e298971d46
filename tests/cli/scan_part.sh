# Design data, error-tolerant scanning and I++ DME: sections and paths, scans in process and
# through the served virtual CMM, NIST's programs.
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
