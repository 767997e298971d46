#!/usr/bin/env bash
# End-to-end: one machine's history over two years in the records, its backlash growing as its
# ball screw wears: the trend finds the drift and the date the reversal value B reaches its
# limit, `record due` brings the visit forward; the same history on a PostgreSQL server gives the
# same trend; a read-only database is still listed.
set -u
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=lib.sh
. "$here/lib.sh"
unset TRUEAXIS_DB

# Eight visits, every three months from 2024-01-15: backlash 2 µm growing 1.5 µm a year.
dates=(2024-01-15 2024-04-15 2024-07-15 2024-10-15 2025-01-15 2025-04-15 2025-07-15 2025-10-15)
for v in "${!dates[@]}"; do
  b=$(awk -v v="$v" 'BEGIN { printf "%.4f", 2 + 1.5 * v / 4 }')
  "$T" simulate positioning --axis x --targets 0:100:800 --backlash "$b" --noise 0.2 --seed $((v + 1)) -o "run$v.csv" -q &&
    "$T" positioning --input "run$v.csv" --output "pos$v.json" -q || bad "visit $v: simulate and evaluate"
  new=""; [ "$v" -eq 0 ] && new=--new-machine
  expect_ok "$T" record add "pos$v.json" --db hist.db --machine VMC-1 --axis x --date "${dates[$v]}" --as-found $new -q
done
expect_ok "$T" record trend --db hist.db --machine VMC-1 --figure B --axis x --tolerance 8 -o trend.json
grep -q "VMC-1: B X: 8 points, drift .* µm/year, reaches the tolerance on 20" out.txt && ok || bad "record trend: $(cat out.txt)"
/usr/bin/python3 -c "
import json, sys
t = json.load(open('trend.json'))
d, u = t['drift_per_year']['value'], t['drift_per_year']['u']
# The backlash grows 1.5 µm a year; B follows it.
sys.exit(0 if abs(d - 1.5) <= 3 * u and u < 0.5 and t['due']['date'] > '2025-10-15' else 1)" \
  && ok || bad "record trend: the drift is not the simulated 1.5 µm/year: $(cat trend.json)"
# Due: 24 months after the last visit, unless B reaches 6 µm first (it does, in 2026).
expect_ok "$T" record due --db hist.db --interval 24 --limit B@x=6 --today 2025-11-01 -o due.json
grep -q "^2026-.*due  VMC-1  (last visit 2025-10-15): B@X reaches 6 µm (drift" out.txt && ok || bad "record due: $(cat out.txt)"
expect_ok "$T" record due --db hist.db --interval 1 --today 2026-02-01
grep -q "^2025-11-15  OVERDUE  VMC-1  (last visit 2025-10-15): 1 months after the last visit" out.txt && ok || bad "record due, overdue: $(cat out.txt)"
expect_code 2 "$T" record due --db hist.db --interval 0
expect_code 1 "$T" record due --db hist.db --limit B@x
grep -q "limit 'B@x': write FIGURE=VALUE" err.txt && ok || bad "record due: a bad limit: $(cat err.txt)"
expect_code 1 "$T" record list --db absent.db
grep -q "no records database at absent.db" err.txt && ok || bad "record list: no database: $(cat err.txt)"
[ ! -e absent.db ] && ok || bad "record list created a database"

# Every figure of the machine in one report: B with its limit and due date.
expect_ok "$T" record report --db hist.db --machine VMC-1 --limit B@x=6 -o history.html
grep -q "VMC-1: 5 figures, 5 with a drift -> history.html" out.txt && ok || bad "record report: $(cat out.txt)"
for f in "A on X: history and drift" "B on X: history and drift" "R on X: history and drift" "the trend reaches the limit"; do
  grep -q "$f" history.html && ok || bad "record report lacks '$f'"
done
expect_code 1 "$T" record report --db hist.db --machine NOPE -o none.html
grep -q "machine 'NOPE' has no records" err.txt && ok || bad "record report, unknown machine: $(cat err.txt)"

# A certificate of the last visit: as found, adjusted, as left the same day.
"$T" simulate positioning --axis x --targets 0:100:800 --backlash 1 --noise 0.2 --seed 40 -o left.csv -q &&
  "$T" positioning --input left.csv --output left.json -q || bad "as left: simulate and evaluate"
expect_ok "$T" record add left.json --db hist.db --machine VMC-1 --axis x --date 2025-10-15 --as-left --instrument XL-80 --temperature 20.6 -q
cp "$here/../data/fuzz/certificate-lab.json" lab.json
expect_ok "$T" certificate --db hist.db --machine VMC-1 --date 2025-10-15 --lab lab.json --issued 2025-10-16 -o cert.html --pdf cert.pdf
grep -q "Calibration certificate C-2026-017: 10 figures (.* conform, .* do not, .* without a decision) -> cert.html" out.txt && ok || bad "certificate: $(cat out.txt)"
grep -q "LC-99" cert.html && ok || bad "certificate: the instrument's calibration certificate is not listed"
for want in "Results as found" "Results as left" "Uncertainty of positioning on X" "u_EVE" "V8-0042" "backlash compensation of X raised by 4" "approved by: M. Rossi" "ISO 14253-1"; do
  grep -q "$want" cert.html && ok || bad "certificate lacks '$want'"
done
[ "$(head -c 4 cert.pdf)" = "%PDF" ] && ok || bad "certificate: no PDF"
# Without Chromium: the HTML and a clear message (exit 1).
PATH=/nonexistent "$T" certificate --db hist.db --machine VMC-1 --date 2025-10-15 --lab lab.json -o cert2.html --pdf cert2.pdf >out.txt 2>err.txt
[ $? -eq 1 ] && [ -s cert2.html ] && grep -q "Chromium is not installed" err.txt && ok || bad "certificate without Chromium: $(cat err.txt)"
expect_code 1 "$T" certificate --db hist.db --machine VMC-1 --date 2023-01-01
grep -q "machine 'VMC-1' has no records from 2023-01-01 to 2023-01-01 (its records run from 2024-01-15 to 2025-10-15)" err.txt && ok || bad "certificate: no records: $(cat err.txt)"
printf '{"name": "Lab",\n "limits": {"A": "ten"}}' > badlab.json
expect_code 1 "$T" certificate --db hist.db --machine VMC-1 --date 2025-10-15 --lab badlab.json
grep -q "badlab.json:2:" err.txt && ok || bad "certificate: a bad lab file is located: $(cat err.txt)"

# Read-only: a database in a directory and file nobody may write is still listed; adding to it
# fails with the reason. Root may write anything: as root the commands run as 'nobody'.
mkdir ro && cp hist.db ro/ && chmod 444 ro/hist.db && chmod 555 ro
as=(); [ "$(id -u)" = 0 ] && as=(runuser -u nobody --)
"${as[@]}" "$T" record list --db ro/hist.db >out.txt 2>err.txt && [ "$(wc -l <out.txt)" -eq 9 ] && ok || bad "record list, read-only: $(cat err.txt)"
"${as[@]}" "$T" record add pos0.json --db ro/hist.db --machine VMC-2 --new-machine >out.txt 2>err.txt
[ $? -eq 1 ] && grep -q "cannot be written" err.txt && ok || bad "record add, read-only: $(cat err.txt)"
chmod 755 ro

# PostgreSQL: the same history on a server of the test's own gives the same trend.
if bash "$here/../records/postgres.sh" start "$dir/pg" >pg.txt 2>&1; then
  url=$(cat pg/url)
  psql -q "$url" -c "CREATE DATABASE history" >/dev/null 2>&1 && ok || bad "CREATE DATABASE on the test server"
  pg="${url%/*}/history"
  for v in "${!dates[@]}"; do
    new=""; [ "$v" -eq 0 ] && new=--new-machine
    expect_ok "$T" record add "pos$v.json" --db "$pg" --machine VMC-1 --axis x --date "${dates[$v]}" --as-found $new -q
  done
  expect_ok "$T" record trend --db "$pg" --machine VMC-1 --figure B --axis x --tolerance 8 -o trend-pg.json
  /usr/bin/python3 -c "
import json, sys
a, b = json.load(open('trend.json')), json.load(open('trend-pg.json'))
sys.exit(0 if a == b else 1)" && ok || bad "the trend on PostgreSQL differs from SQLite's"
  expect_ok "$T" record show 8 --db "$pg" -o stored.json
  cmp -s stored.json pos7.json && ok || bad "record show on PostgreSQL: the stored file differs"
  expect_code 1 "$T" record add pos0.json --db "$pg" --machine VMC-1
  grep -q "already stored for machine 'VMC-1' (record 1, 2024-01-15)" err.txt && ok || bad "PostgreSQL duplicate: $(cat err.txt)"
  expect_code 1 "$T" record list --db "${url%/*}/absent"
  grep -q 'database "absent" does not exist' err.txt && ok || bad "PostgreSQL, no database: $(cat err.txt)"
  bash "$here/../records/postgres.sh" stop "$dir/pg"
else
  bad "no PostgreSQL server for the test: $(cat pg.txt)"
fi
echo "records cli: $passes passed, $fails failed"
[ "$fails" -eq 0 ]
