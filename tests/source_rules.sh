#!/usr/bin/env bash
# The repository's own rules, checked on every test run:
#  - no source file longer than about 800 lines (900 is the hard limit): a longer file is split by
#    what its parts do;
#  - citations a reader can follow: code cites the standard and clause, the patent number or the
#    paper, never a document that is not in the repository ("spec 04", "seed 001", "the seed's",
#    "the paper" or a test named ThePaper…, "must-show").
#   bash tests/source_rules.sh REPOSITORY_ROOT
set -euo pipefail
root=${1:-$(dirname "$0")/..}
cd "$root"
status=0
limit=900
while IFS= read -r f; do
  n=$(wc -l <"$f")
  if [ "$n" -gt "$limit" ]; then
    echo "$f: $n lines (at most $limit; split it by what its parts do)"
    status=1
  fi
done < <(find src include apps python tests benchmarks -type f \
           \( -name '*.cpp' -o -name '*.hpp' -o -name '*.py' -o -name '*.in' -o -name '*.sh' \) | sort)
# file:line of every citation of a document readers do not have (the command line's grammar test,
# cli/grammar_part.sh, names these words to check that the reports and the help never say them).
if grep -rnE --include='*.cpp' --include='*.hpp' --include='*.py' --include='*.sh' \
     --exclude=source_rules.sh --exclude=grammar_part.sh '\bspecs? 0[0-9]|\bseed 0[0-9]{2}|\bthe seed'"'"'s|\bthe paper\b|ThePaper|\bmust-show\b' \
     src include apps python tests benchmarks scripts; then
  echo "cite what the code implements (standard and clause, patent number, paper), not the above"
  status=1
fi
exit $status
