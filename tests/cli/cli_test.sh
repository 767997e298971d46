#!/usr/bin/env bash
# End-to-end tests of the trueaxis command line: files, exit codes, one-line errors. The parts run
# in order in one working directory (later parts use files earlier ones wrote): lib.sh has the
# checks they share.
set -u
here=$(cd "$(dirname "$0")" && pwd)
# shellcheck source=lib.sh
. "$here/lib.sh"
for part in measure grammar scan machine_tests record_add; do
  # shellcheck disable=SC1090
  . "$here/${part}_part.sh"
done
echo "cli: $passes passed, $fails failed"
[ "$fails" -eq 0 ]
