#!/usr/bin/env bash
# A PostgreSQL server of the tests' own, on a free local port, so that the records' tests run on
# PostgreSQL as they run on SQLite (Debian: the postgresql package; initdb and pg_ctl are in
# /usr/lib/postgresql/<version>/bin). The server refuses to run as root: as root it runs as the
# postgres user the package creates.
#   postgres.sh start STATE_DIR   starts it; STATE_DIR/url holds its URL
#   postgres.sh stop STATE_DIR    stops it and removes its files
set -euo pipefail
cmd=${1:?start or stop}
state=${2:?a directory for the server state}
bin=$(ls -d /usr/lib/postgresql/*/bin 2>/dev/null | sort -V | tail -n 1)
if [ -z "$bin" ] || [ ! -x "$bin/initdb" ]; then
  echo "postgres.sh: the PostgreSQL server is not installed (Debian: apt-get install postgresql)" >&2
  exit 1
fi
as=()
[ "$(id -u)" = 0 ] && as=(runuser -u postgres --)
case $cmd in
  start)
    [ -f "$state/data_dir" ] && "$0" stop "$state" 2>/dev/null || true
    mkdir -p "$state"
    data=$(mktemp -d /tmp/trueaxis-pg.XXXXXX)
    [ "$(id -u)" = 0 ] && chown postgres "$data"
    echo "$data" >"$state/data_dir"
    port=$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
    "${as[@]}" "$bin/initdb" -D "$data/db" -A trust -U trueaxis -E UTF8 --locale=C --no-sync >"$state/initdb.log"
    # No fsync: a test server's data need not survive a power cut.
    "${as[@]}" "$bin/pg_ctl" -D "$data/db" -l "$data/server.log" -w -t 60 \
      -o "-F -p $port -k $data -c listen_addresses=127.0.0.1 -c max_connections=60" start >/dev/null
    echo "postgresql://trueaxis@127.0.0.1:$port/postgres" >"$state/url"
    ;;
  stop)
    data=$(cat "$state/data_dir")
    "${as[@]}" "$bin/pg_ctl" -D "$data/db" -m immediate stop >/dev/null 2>&1 || true
    rm -rf "$data" "$state"
    ;;
  *)
    echo "postgres.sh: start or stop, not '$cmd'" >&2
    exit 2
    ;;
esac
