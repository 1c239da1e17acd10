#!/usr/bin/env bash
# bench/ooc_budget.sh: peak resident set (/usr/bin/time -v "Maximum resident set size", the
# process's VmHWM) of the out-of-core commands against --max-mb, on a synthetic scan of
# ${BUDGET_POINTS:-3000000} points (scripts/gen_scan, seed 1): clean, with one far outlier at
# (1000, 1000, 1000) (the scan is a unit sphere: ~290 diagonals away), with 50 far outliers
# (golden-angle spiral, radius 1000 about the origin) and with one outlier 1e6 diagonals from the
# scan's centre. The outliers are appended as rows of the binary PLY (the vertex count in the
# header raised to match) by the small step `add_outliers` below.
#
# Env: BUDGET_MB (default "256 1024"), BUDGET_CASES ("clean one fifty million"), BUDGET_COMMANDS
# ("normals eps-delta" ; also shape-approx, lod), BUDGET_DIR (/tmp/linesurf_ooc_budget).
# Prints one row per run: case, command, --max-mb, peak MiB, peak / budget, exit code, wall time.
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${LINESURF_BUILD:-$root/build}"
dir="${BUDGET_DIR:-/tmp/linesurf_ooc_budget}"
n="${BUDGET_POINTS:-3000000}"
read -r -a budgets <<< "${BUDGET_MB:-256 1024}"
read -r -a cases <<< "${BUDGET_CASES:-clean one fifty million}"
read -r -a commands <<< "${BUDGET_COMMANDS:-normals eps-delta}"
mkdir -p "$dir"

# add_outliers IN OUT KIND: OUT = IN (binary little-endian PLY, x y z floats first) with outliers.
add_outliers() {
  /usr/bin/python3 - "$1" "$2" "$3" <<'EOF'
import math, struct, sys
src, dst, kind = sys.argv[1:4]
data = open(src, 'rb').read()
end = data.index(b'end_header\n') + len(b'end_header\n')
head = data[:end].decode()
lines = head.split('\n')
count = next(int(l.split()[2]) for l in lines if l.startswith('element vertex'))
props = [l for l in lines if l.startswith('property')]
assert all(p.split()[1] == 'float' for p in props), 'float properties only'
row = 4 * len(props)
body = data[end:end + count * row]
if kind == 'one':
    pts = [(1000.0, 1000.0, 1000.0)]
elif kind == 'fifty':
    pts = []
    for i in range(50):
        t = (i + 0.5) / 50; z = 1 - 2 * t; r = math.sqrt(1 - z * z); phi = 2.399963 * i
        pts.append((1000 * r * math.cos(phi), 1000 * r * math.sin(phi), 1000 * z))
else:  # million: 1e6 scan diagonals from the scan's centre
    import array
    a = array.array('f'); a.frombytes(body)
    k = len(props)
    lo = [min(a[c::k]) for c in range(3)]; hi = [max(a[c::k]) for c in range(3)]
    diag = math.sqrt(sum((h - l) ** 2 for l, h in zip(lo, hi)))
    pts = [tuple((l + h) / 2 + 1e6 * diag / math.sqrt(3) for l, h in zip(lo, hi))]
extra = b''.join(struct.pack('<' + 'f' * len(props), *(p + (0.0,) * (len(props) - 3))) for p in pts)
head = head.replace('element vertex %d\n' % count, 'element vertex %d\n' % (count + len(pts)))
open(dst, 'wb').write(head.encode() + body + extra)
EOF
}

scan_of() {  # case -> path
  local c=$1 clean="$dir/scan_clean.ply"
  [[ -f "$clean" ]] || "$build/linesurf_gen_scan" "$clean" "$n" 1 >/dev/null
  if [[ $c == clean ]]; then echo "$clean"; return; fi
  local out="$dir/scan_$c.ply"
  [[ -f "$out" ]] || add_outliers "$clean" "$out" "$c"
  echo "$out"
}

printf '| scan | command | --max-mb | peak RSS (MiB) | peak / budget | exit | wall |\n|---|---|---:|---:|---:|---:|---:|\n'
for c in "${cases[@]}"; do
  scan=$(scan_of "$c")
  for cmd in "${commands[@]}"; do
    for mb in "${budgets[@]}"; do
      out="$dir/out_${c}_${cmd}_${mb}"
      case $cmd in
        normals) args=(normals "$scan" -o "$out.ply" --out-of-core) ;;
        eps-delta) args=(extract eps-delta "$scan" -o "$out.ply" --out-of-core) ;;
        shape-approx) args=(extract shape-approx "$scan" -o "$out.ply" --out-of-core) ;;
        lod)  # from the scan's normals (lod build takes points with normals and radii)
          nrm="$dir/normals_$c.ply"
          [[ -f "$nrm" ]] || "$build/linesurf" -q normals "$scan" -o "$nrm" --out-of-core --max-mb 1024
          args=(lod build "$nrm" -o "$out.lod" --out-of-core) ;;
      esac
      set +e
      /usr/bin/time -v "$build/linesurf" -q "${args[@]}" --max-mb "$mb" > "$dir/last.out" 2> "$dir/last.time"
      rc=$?
      set -e
      kb=$(awk -F: '/Maximum resident set size/ {gsub(/ /, "", $2); print $2}' "$dir/last.time")
      wall=$(awk '/Elapsed/ {print $NF}' "$dir/last.time")
      awk -v c="$c" -v cmd="$cmd" -v mb="$mb" -v kb="$kb" -v rc="$rc" -v wall="$wall" \
        'BEGIN {printf "| %s | %s | %d | %.0f | %.2f | %d | %s |\n", c, cmd, mb, kb / 1024, kb / 1024 / mb, rc, wall}'
      [[ $rc -eq 0 ]] || head -c 400 "$dir/last.time" | grep -v "Command being timed" | head -3 >&2
      rm -rf "$out.ply" "$out.lod" "$out.ply.tiles"
    done
  done
done
