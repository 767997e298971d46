#!/usr/bin/env bash
# The records: 'record add' of 10^4 results and 'record trend' over 10^5 stored ones, against the
# database's own command-line tool doing the same work in the same run: sqlite3 (each result one
# transaction: the record with its file and its five figures) and, on a PostgreSQL server this
# script starts (tests/records/postgres.sh), psql.
# Usage: benchmarks/records_bench.sh [path/to/trueaxis] [adds] [stored]
set -euo pipefail
T=$(realpath "${1:-$(command -v trueaxis)}")
N=${2:-10000}
M=${3:-100000}
here=$(cd "$(dirname "$0")" && pwd)
D=$(mktemp -d)
trap 'bash "$here/../tests/records/postgres.sh" stop "$D/pg" >/dev/null 2>&1 || true; rm -rf "$D"' EXIT
chmod 755 "$D"  # the PostgreSQL server (another user) reads the files below
cd "$D"
"$T" simulate positioning --axis x --targets 0:100:800 --noise 0.2 -o run.csv -q
"$T" positioning --input run.csv --output pos.json -q
# N distinct results (A differs in its last digits, so each file is another record).
/usr/bin/python3 - "$N" <<'PY'
import json, sys
j = json.load(open("pos.json"))
for i in range(int(sys.argv[1])):
    j["A"] = 10 + i * 1e-6
    json.dump(j, open(f"r{i:05d}.json", "w"))
PY
secs() { local s=$EPOCHREALTIME; "$@" >/dev/null; awk -v a="$s" -v b="$EPOCHREALTIME" 'BEGIN{printf "%.2f", b - a}'; }

# The same inserts as SQL: one transaction per result, its file read by sqlite3's readfile().
"$T" record add r00000.json --db schema.db --machine M --axis x --new-machine -q
sqlite3 schema.db .schema > schema.sql
/usr/bin/python3 - "$N" <<'PY' > inserts.sql
import json, sys
print("PRAGMA foreign_keys = ON;")
print("INSERT INTO machines VALUES ('M', '2026-01-01');")
for i in range(int(sys.argv[1])):
    j = json.load(open(f"r{i:05d}.json"))
    print("BEGIN IMMEDIATE;")
    print(f"INSERT INTO records (machine, date, kind, state, operator, instrument, temperature_C, note, "
          f"trueaxis_version, file_name, digest, content) VALUES ('M', '2026-01-01', 'positioning', '', '', '', "
          f"NULL, '', 'x', 'r{i:05d}.json', 'd{i}', readfile('r{i:05d}.json'));")
    for k, name in enumerate("ABEMR"):
        print(f"INSERT INTO figures VALUES (last_insert_rowid(), {k}, '{name}', 'X', {j[name]!r}, NULL, 'µm');"
              if k == 0 else
              f"INSERT INTO figures SELECT MAX(id), {k}, '{name}', 'X', {j[name]!r}, NULL, 'µm' FROM records;")
    print("COMMIT;")
PY
sqlite3 sql.db < schema.sql
ta=$(secs "$T" record add r*.json --db add.db --machine M --axis x --new-machine -q)
tb=$(secs sqlite3 sql.db < inserts.sql)
echo "SQLite, add $N results: trueaxis record add $ta s, sqlite3 the same inserts $tb s"

# M stored results of one machine, one a day, A drifting: made by SQL in one transaction.
cp schema.db big.db
sqlite3 big.db <<SQL
BEGIN;
WITH RECURSIVE n(i) AS (SELECT 1 UNION ALL SELECT i + 1 FROM n WHERE i < $M)
INSERT INTO records (machine, date, kind, state, operator, instrument, temperature_C, note,
  trueaxis_version, file_name, digest, content)
SELECT 'M', date('1800-01-01', '+' || i || ' days'), 'positioning', '', '', '', NULL, '', 'x', 'r',
  'big' || i, content FROM n, (SELECT content FROM records WHERE id = 1);
INSERT INTO figures SELECT id, 0, 'A', 'X', 10 + id * 1e-5 + (abs(random()) % 1000) * 1e-4, 0.05,
  'µm' FROM records WHERE id > 1;
COMMIT;
SQL
tc=$(secs "$T" record trend --db big.db --machine M --figure A --axis x --tolerance 20 -o trend.json)
td=$(secs sqlite3 big.db "SELECT r.id, r.date, r.state, f.value, f.u, f.unit FROM figures f JOIN
  records r ON r.id = f.record WHERE r.machine = 'M' AND f.name = 'A' AND f.axis = 'X' ORDER BY
  r.date, r.id")
echo "SQLite, trend over $(sqlite3 big.db 'SELECT COUNT(*) FROM records') records: trueaxis record trend $tc s, sqlite3 the same select $td s"

# PostgreSQL: the same adds, against psql running the same statements.
bash "$here/../tests/records/postgres.sh" start "$D/pg" >/dev/null
url=$(cat "$D/pg/url")
psql -q "$url" -c "CREATE DATABASE add_db" -c "CREATE DATABASE sql_db"
"$T" record machines --db "${url%/*}/sql_db" >/dev/null 2>&1 || true
"$T" record add r00000.json --db "${url%/*}/sql_db" --machine X --axis x --new-machine -q
sed -e 's/readfile(\x27\(r[0-9]*\.json\)\x27)/pg_read_binary_file(\x27'"${D//\//\\/}"'\/\1\x27)/' \
    -e 's/BEGIN IMMEDIATE;/BEGIN; SELECT pg_advisory_xact_lock(1);/' \
    -e 's/last_insert_rowid()/(SELECT MAX(id) FROM records)/' \
    -e '/PRAGMA/d' inserts.sql > inserts-pg.sql
te=$(secs "$T" record add r*.json --db "${url%/*}/add_db" --machine M --axis x --new-machine -q)
tf=$(secs psql -q "${url%/*}/sql_db" -f inserts-pg.sql)
echo "PostgreSQL, add $N results: trueaxis record add $te s, psql the same inserts $tf s"
psql -q "${url%/*}/add_db" <<SQL
BEGIN;
INSERT INTO records (machine, date, kind, state, operator, instrument, temperature_C, note,
  trueaxis_version, file_name, digest, content)
SELECT 'M', to_char(date '1800-01-01' + i, 'YYYY-MM-DD'), 'positioning', '', '', '', NULL, '', 'x',
  'r', 'big' || i, (SELECT content FROM records WHERE id = 1) FROM generate_series(1, $M) i;
INSERT INTO figures SELECT id, 0, 'A', 'X', 10 + id * 1e-5 + random() * 0.1, 0.05, 'µm'
  FROM records WHERE digest LIKE 'big%';
COMMIT;
SQL
tg=$(secs "$T" record trend --db "${url%/*}/add_db" --machine M --figure A --axis x --tolerance 20 -o trend-pg.json)
th=$(secs psql -q "${url%/*}/add_db" -c "SELECT r.id, r.date, r.state, f.value, f.u, f.unit FROM
  figures f JOIN records r ON r.id = f.record WHERE r.machine = 'M' AND f.name = 'A' AND f.axis =
  'X' ORDER BY r.date, r.id")
echo "PostgreSQL, trend over $((N + M)) records: trueaxis record trend $tg s, psql the same select $th s"
