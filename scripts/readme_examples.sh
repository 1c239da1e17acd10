#!/usr/bin/env bash
# The README's Examples block, generated from its own commands.
#
# The block lies between the lines `<!-- examples:begin -->` and `<!-- examples:end -->` of
# README.md. Its commands are its lines that start with `$ `; each is run, as written, in a scratch
# folder that holds nothing but `data` (a link to the bundled models), with the CLI under test first
# on PATH, so the block shows what a user who cloned the repository and installed linesurf sees.
#
#   scripts/readme_examples.sh --update [--cli build/linesurf]   rewrite the block from the commands
#   scripts/readme_examples.sh --check  [--cli build/linesurf]   exit 1 when the block differs
#
# What may differ between runs and machines is masked in the comparison only (the README keeps the
# figures of the run that wrote it): every number on the lines that report times (`time`, `times`,
# `render WxH: …`), any other number followed by `s` or `ms`, the thread count (`N threads`,
# the machine's cores) and the counts of the `Z3` line, which the SIMD path the machine runs
# (AVX2 or AVX-512) can move by a fragment at a splat's rim. Every other figure (counts, errors, metrics, sizes) is deterministic for
# any thread count and must match exactly.
set -euo pipefail
ROOT="$(cd "$(dirname "$0")/.." && pwd)"
README="$ROOT/README.md"
MODE=""
CLI="$ROOT/build/linesurf"
while [ $# -gt 0 ]; do
  case "$1" in
    --update|--check) MODE=${1#--}; shift ;;
    --cli) CLI=$2; shift 2 ;;
    --readme) README=$2; shift 2 ;;
    *) echo "usage: $0 --update|--check [--cli PATH] [--readme PATH]" >&2; exit 1 ;;
  esac
done
[ -n "$MODE" ] || { echo "usage: $0 --update|--check [--cli PATH] [--readme PATH]" >&2; exit 1; }
CLI="$(cd "$(dirname "$CLI")" && pwd)/$(basename "$CLI")"
[ -x "$CLI" ] || { echo "$CLI: not an executable (build it: cmake --build build --target linesurf)" >&2; exit 1; }

BEGIN='<!-- examples:begin -->'
END='<!-- examples:end -->'
grep -qxF "$BEGIN" "$README" && grep -qxF "$END" "$README" ||
  { echo "$README: no '$BEGIN' ... '$END' block" >&2; exit 1; }

# The block as it stands (between the markers, fences included).
current=$(awk -v b="$BEGIN" -v e="$END" '$0==e{f=0} f{print} $0==b{f=1}' "$README")
mapfile -t commands < <(printf '%s\n' "$current" | sed -n 's/^\$ //p')
[ ${#commands[@]} -gt 0 ] || { echo "$README: the Examples block has no '\$ ' command" >&2; exit 1; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mkdir "$work/bin"
ln -s "$CLI" "$work/bin/linesurf"
ln -s "$ROOT/data" "$work/data"

# Runs the commands in order and prints the new block; a failing command fails the whole run.
generate() {
  echo '```text'
  local first=1
  for c in "${commands[@]}"; do
    [ $first = 1 ] || echo
    first=0
    echo "\$ $c"
    if ! (cd "$work" && PATH="$work/bin:$PATH" bash -c "$c") 2>&1; then
      echo "readme_examples: command failed: $c" >&2
      return 1
    fi
  done
  echo '```'
}
generated=$(generate) || exit 1

mask() {
  sed -E -e '/^(time|times|render [0-9]+x[0-9]+:|Z3 )/ s/[0-9]+(\.[0-9]+)?/#/g' \
         -e 's/\b[0-9]+(\.[0-9]+)? ?(ms|s)\b/# \2/g' \
         -e 's/\b[0-9]+ threads/# threads/g'
}

case "$MODE" in
  update)
    tmp=$(mktemp "$README.XXXXXX")
    awk -v b="$BEGIN" -v e="$END" -v blockfile=<(printf '%s\n' "$generated") '
      $0==b {print; while ((getline line < blockfile) > 0) print line; skip=1; next}
      $0==e {skip=0}
      !skip {print}' "$README" >"$tmp"
    cat "$tmp" >"$README"  # keeps the file's mode
    rm -f "$tmp"
    echo "readme_examples: rewrote the Examples block of $README (${#commands[@]} commands)"
    ;;
  check)
    if diff -u --label "README.md (Examples block, times masked)" --label "what the commands print now" \
         <(printf '%s\n' "$current" | mask) <(printf '%s\n' "$generated" | mask); then
      echo "readme_examples: the Examples block matches its ${#commands[@]} commands"
    else
      echo "readme_examples: README.md's Examples block is stale; regenerate it: scripts/readme_examples.sh --update" >&2
      exit 1
    fi
    ;;
esac
