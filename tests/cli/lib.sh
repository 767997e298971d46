# Shared by the command line's end-to-end tests: cli_test.sh (which sources this, then each of its
# parts in order, in one working directory: later parts use files earlier ones wrote) and
# records_test.sh. Takes the working directory as the script's first argument.
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
# expect_code CODE cmd...: the command exits with CODE.
expect_code() { local want=$1; shift; "$@" >out.txt 2>err.txt; local rc=$?; [ "$rc" -eq "$want" ] && ok || bad "$* exited $rc, want $want"; }
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
