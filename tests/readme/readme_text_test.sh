#!/usr/bin/env bash
# README.md is for users: at most 150 lines, and no history of the work ("stop" or "issue"
# and a number, work-item tags: "i1", a digit and letters): what was measured when belongs in
# docs/results.md.
set -euo pipefail
README=${1:?usage: readme_text_test.sh README.md}
lines=$(wc -l <"$README")
status=0
if [ "$lines" -gt 150 ]; then
  echo "$README: $lines lines, more than 150" >&2
  status=1
fi
if grep -nEi '\b(stop|issue)s? [0-9]+|\bi1[0-9][a-z]+\b' "$README" >&2; then
  echo "$README: the lines above tell the history of the work" >&2
  status=1
fi
[ $status = 0 ] && echo "$README: $lines lines, no work history"
exit $status
