#!/usr/bin/env bash
# Code comments say why the code is as it is, not when: no "stop" or "issue" and a number, no
# work-item tags ("i1", a digit and letters) in the sources, tests, scripts and build files. A
# comment points to a decision by its topic heading in docs/decisions.md instead. Lists every hit
# as PATH:LINE: TEXT and exits 1 when there is one.
# usage: check_history_tags.sh [SOURCE_ROOT]   (default: the repository this script is in)
set -euo pipefail
root=${1:-$(cd "$(dirname "$0")/.." && pwd)}
cd "$root"
paths=()
for p in src include apps python web tests bench scripts cmake examples CMakeLists.txt Makefile; do
  [ -e "$p" ] && paths+=("$p")
done
pattern='\b[Ss]tops? [0-9]+\b|\b[Ii]ssues? [0-9]+\b|\bi1[0-9][a-z]+\b'
if hits=$(grep -rnIE --exclude-dir=__pycache__ --exclude-dir=node_modules "$pattern" "${paths[@]}"); then
  printf '%s\n' "$hits" >&2
  echo "$root: $(printf '%s\n' "$hits" | wc -l) line(s) above tell the history of the work; cite a topic heading of docs/decisions.md instead" >&2
  exit 1
fi
echo "$root: no work history in ${paths[*]}"
