#!/usr/bin/env bash
# Browser test of the streaming viewer of hierarchies (`linesurf view MODEL.lod`): the CLI serves the
# page and the .lod file (HTTP Range) from localhost, headless Chromium (software GL: SwiftShader)
# loads it with a camera and a splat budget in the URL fragment, and the page must
#  - draw what `linesurf render MODEL.lod --budget N` draws from that camera (SSIM >= MIN_SSIM);
#  - fetch, with a budget of half the model, well under the file (bytes fetched <= MAX_FETCH_SHARE
#    of its size): only the selected nodes' blocks, the preamble and the table;
#  - with a budget of the whole model, draw the plain model's picture (`linesurf render MODEL.ply`);
#  - draw the rest of a hierarchy one of whose node blocks is damaged, naming the node in the DOM
#    (and draw what `linesurf render` draws of it);
#  - refuse a node block copied from another hierarchy (another hierarchy id), naming the node.
# Also: `linesurf view` refuses a damaged hierarchy in one line (exit 2) before serving.
# The page's state is read from document.body's attributes (data-state="drawn" once the selected
# cut is loaded and drawn, data-bytes-fetched, data-splats, data-nodes, data-failed-nodes,
# data-first-frame-ms).
#
# LOD=/path/big.lod runs the first check only, on that hierarchy from its default view (BUDGET
# splats, default 1000000; a budget over the model's size compares with `linesurf render` of every
# leaf), and prints the bytes fetched against the file's size and, from a second run without
# virtual time, the page's first frame and first complete view on the real clock (the page reports
# them to the server, which prints them).
# Usage: lod_viewer_test.sh LINESURF SOURCE_DIR WORK_DIR. Exit 77 (CTest: skipped) without chromium
# or when this linesurf was built without cpp-httplib.
set -euo pipefail
LS=$(realpath "$1")
SRC=$(realpath "$2")
WORK=$3
MIN_SSIM=${MIN_SSIM:-0.95}
MAX_FETCH_SHARE=${MAX_FETCH_SHARE:-0.35}
CHROMIUM=${CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}
if [ -z "$CHROMIUM" ]; then
  echo "SKIP: chromium not found (scripts/setup.sh installs Debian's chromium)"
  exit 77
fi
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail=0
SERVER_PID=
stop_server() {
  if [ -n "$SERVER_PID" ]; then
    kill -TERM "$SERVER_PID" 2>/dev/null || true
    wait "$SERVER_PID" 2>/dev/null || true
    SERVER_PID=
  fi
}
trap stop_server EXIT

# serve FILE.lod: starts `linesurf view FILE --port 0` in the background, sets PORT.
serve() {
  stop_server
  "$LS" view "$1" --port 0 -q >serve.out 2>serve.err &
  SERVER_PID=$!
  PORT=
  for _ in $(seq 200); do
    PORT=$(sed -n 's|^serving .* at http://127\.0\.0\.1:\([0-9]*\)/ .*|\1|p' serve.out)
    [ -n "$PORT" ] && return 0
    if ! kill -0 "$SERVER_PID" 2>/dev/null; then
      SERVER_PID=
      if grep -q 'libcpp-httplib-dev' serve.err; then
        echo "SKIP: $(cat serve.err)"
        exit 77
      fi
      echo "FAIL: linesurf view $1 did not start: $(cat serve.err)"
      exit 1
    fi
    sleep 0.05
  done
  echo "FAIL: linesurf view $1 printed no 'serving ... at URL' line"
  exit 1
}

# chrome URL ARGS...: one headless run with a fresh profile (the flags of viewer_test.sh);
# --virtual-time-budget lets the page's fetches finish before the screenshot or the DOM dump.
chrome() {
  local url=$1
  shift
  local profile
  profile=$(mktemp -d "$WORK/profile.XXXXXX")
  timeout 300 "$CHROMIUM" --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader \
    --disable-background-networking --disable-component-update --disable-sync --no-first-run \
    --disable-default-apps --mute-audio --hide-scrollbars --force-device-scale-factor=1 \
    --user-data-dir="$profile" --window-size=512,512 --virtual-time-budget=${VIRTUAL_MS:-30000} "$@" "$url" \
    2>>"$WORK/chromium.log"
  rm -rf "$profile"
}
# attr DOM NAME: a data- attribute of <body>.
attr() { grep -o '<body[^>]*>' <<<"$1" | sed -n "s/.* data-$2=\"\([^\"]*\)\".*/\1/p"; }
ssim() { "$LS" compare "$1" "$2" --diff "${2%.png}_diff.png" --json | sed -n 's/.*"ssim": *\([0-9.eE+-]*\).*/\1/p'; }
at_least() { awk -v s="$1" -v m="$2" 'BEGIN { exit !(s >= m) }'; }

# shot NAME FRAGMENT: the page's screenshot NAME_viewer.png and its DOM (in DOM), from one run.
shot() {
  DOM=$(chrome "http://127.0.0.1:$PORT/#$2" --screenshot="$WORK/$1_viewer.png" --dump-dom | tr '\n' ' ')
  if [ ! -s "$1_viewer.png" ]; then
    echo "FAIL $1: chromium wrote no screenshot (see $WORK/chromium.log)"
    fail=1
    return 1
  fi
  if [ "$(attr "$DOM" state)" != drawn ]; then
    echo "FAIL $1: the page did not finish its cut (state '$(attr "$DOM" state)'; $(grep -o '<div id="error">[^<]*' <<<"$DOM" || true))"
    fail=1
    return 1
  fi
}

# compare NAME REFERENCE.png MIN WHAT
compare() {
  local s
  s=$(ssim "$2" "$1_viewer.png")
  if at_least "$s" "$3"; then
    echo "ok   $1: SSIM $s ($4, >= $3); $(attr "$DOM" splats) splats in $(attr "$DOM" nodes) nodes"
  else
    echo "FAIL $1: SSIM $s < $3 ($4; images in $WORK)"
    fail=1
  fi
}

if [ -n "${LOD:-}" ]; then
  BUDGET=${BUDGET:-1000000}
  serve "$LOD"
  shot given "ui=0&budget=$BUDGET" || exit 1
  echo "     $(grep -o '<div class="row" id="lodStatus">[^<]*' <<<"$DOM" | sed 's/.*>//')"
  "$LS" render "$LOD" --budget "$BUDGET" -o given_render.png --size 512x512 -q
  compare given given_render.png "$MIN_SSIM" "page vs linesurf render --budget $BUDGET, default view"
  size=$(stat -c %s "$LOD")
  fetched=$(attr "$DOM" bytes-fetched)
  echo "     $LOD: $fetched bytes fetched of $size ($(awk -v a="$fetched" -v b="$size" 'BEGIN { printf "%.2f%%", 100 * a / b }'))"
  # Times on the real clock: the page, loaded without virtual time, reports its first frame to
  # the server (GET /report), which prints it (the last line: the run above reported too, on its
  # virtual clock); Chromium is stopped after REAL_SECONDS.
  profile=$(mktemp -d "$WORK/profile.XXXXXX")
  timeout "${REAL_SECONDS:-60}" "$CHROMIUM" --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader \
    --disable-background-networking --disable-component-update --disable-sync --no-first-run --mute-audio \
    --user-data-dir="$profile" --window-size=512,512 --remote-debugging-port=0 \
    "http://127.0.0.1:$PORT/#ui=0&budget=$BUDGET" >/dev/null 2>>"$WORK/chromium.log" || true
  rm -rf "$profile"
  echo "     real clock: $(grep '^page: ' serve.out | tail -n 1 | grep . || echo 'no report within '"${REAL_SECONDS:-60}"' s')"
  exit $fail
fi

"$LS" extract shape-approx "$SRC/data/igea_points.ply" -o igea.ply -q
"$LS" lod build igea.ply -o igea.lod --leaf-size 256 -q
total=$("$LS" info igea.ply | awk '/points:/ { p = $2 } /segments:/ { s = $2 } END { print p + s }')
half=$((total / 2))
EYE=-0.2,0.05,0.25 TARGET=0,0,0 UP=0,1,0 FOV=30
CAM="eye=$EYE&target=$TARGET&up=$UP&fov=$FOV&ui=0"
render() {  # render MODEL OUT.png [ARGS...]
  local model=$1 out=$2
  shift 2
  "$LS" render "$model" -o "$out" --size 512x512 --eye ${EYE//,/ } --target ${TARGET//,/ } --up ${UP//,/ } --fov "$FOV" -q "$@"
}

# A bad hierarchy is refused before serving, in one line naming it (exit 2 as other bad inputs).
head -c 1000 igea.lod >truncated.lod
set +e
err=$("$LS" view truncated.lod --port 0 2>&1 >/dev/null)
code=$?
set -e
if [ "$code" -eq 2 ] && [ "$(printf '%s\n' "$err" | wc -l)" -eq 1 ] && grep -q '^truncated.lod: ' <<<"$err"; then
  echo "ok   bad hierarchy refused: exit 2, '$err'"
else
  echo "FAIL bad hierarchy: exit $code, '$err'"
  fail=1
fi

serve igea.lod
size=$(stat -c %s igea.lod)

# 1. half the model: the cut of `linesurf render --budget`, fetched in part.
if shot half "$CAM&budget=$half"; then
  render igea.lod half_render.png --budget "$half"
  compare half half_render.png "$MIN_SSIM" "page vs linesurf render --budget $half"
  fetched=$(attr "$DOM" bytes-fetched)
  # The page told the server its first view (what `linesurf view` prints for people and benchmarks).
  if grep -q "^page: first frame [0-9.]* ms, first complete view [0-9.]* ms ($(attr "$DOM" splats) splats" serve.out; then
    echo "ok   report: '$(grep '^page: ' serve.out | head -1)'"
  else
    echo "FAIL report: the server printed no 'page: first frame ...' line with the page's splat count"
    fail=1
  fi
  if [ -n "$fetched" ] && awk -v f="$fetched" -v s="$size" -v m="$MAX_FETCH_SHARE" 'BEGIN { exit !(f > 0 && f <= m * s) }'; then
    echo "ok   half budget: $fetched bytes fetched of $size ($(awk -v a="$fetched" -v b="$size" 'BEGIN { printf "%.1f%%", 100 * a / b }'), <= ${MAX_FETCH_SHARE} of the file)"
  else
    echo "FAIL half budget: $fetched bytes fetched of $size (more than ${MAX_FETCH_SHARE} of the file)"
    fail=1
  fi
fi

# 2. the whole model: every leaf, the plain model's picture.
if shot full "$CAM&budget=$total"; then
  render igea.ply full_render.png
  compare full full_render.png "$MIN_SSIM" "page of every leaf vs linesurf render of the plain model"
fi

# node_block FILE.lod LEAF_RANK: "NODE OFFSET SIZE PRIMITIVES" of the LEAF_RANK-th leaf (table order).
node_block() {
  python3 - "$1" "$2" <<'PY'
import json, struct, sys
data = open(sys.argv[1], 'rb').read()
jbytes, = struct.unpack_from('<I', data, 12)
count, = struct.unpack_from('<Q', data, 24)
table = 32 + jbytes
leaves = []
for i in range(count):
    r = table + 88 * i
    off, size = struct.unpack_from('<QQ', data, r + 8)
    points, segments = struct.unpack_from('<II', data, r + 72)
    if data[r + 86]:
        leaves.append((i, off, size, points + segments))
print(*leaves[int(sys.argv[2]) % len(leaves)])
PY
}
# patch DST OFFSET SRC SRC_OFFSET BYTES: copies bytes of SRC over DST in place.
patch() { dd if="$3" of="$1" bs=1 skip="$4" seek="$2" count="$5" conv=notrunc status=none; }

# 3. one leaf's block damaged (its header overwritten): the rest is drawn (every primitive but
# the node's), the node named.
cp igea.lod damaged.lod
read -r dnode doff _ dcount < <(node_block damaged.lod 300)
printf 'damaged block header....' >noise.bin
patch damaged.lod "$doff" noise.bin 0 24
serve damaged.lod
if shot damaged "$CAM&budget=$total"; then
  if [ "$(attr "$DOM" failed-nodes)" = "$dnode" ] && grep -q "node $dnode failed: " <<<"$DOM" &&
     [ "$(attr "$DOM" splats)" -eq $((total - dcount)) ]; then
    echo "ok   damaged block: the page draws $(attr "$DOM" splats) splats and says '$(grep -o "node $dnode failed: [^<]*" <<<"$DOM" | head -1)'"
  else
    echo "FAIL damaged block: node $dnode not named (failed nodes '$(attr "$DOM" failed-nodes)'), or not $((total - dcount)) splats ($(attr "$DOM" splats))"
    fail=1
  fi
  # `linesurf render` leaves the node out as well (with a warning): the same picture
  render damaged.lod damaged_render.png --budget "$total" 2>/dev/null
  compare damaged damaged_render.png "$MIN_SSIM" "page vs linesurf render of the damaged hierarchy"
fi

# 4. a block of another hierarchy (same model, another grid: another hierarchy id) copied over a
# leaf's block: refused as foreign, named.
"$LS" lod build igea.ply -o other.lod --leaf-size 256 --grid 16 -q
cp igea.lod foreign.lod
read -r fnode foff fsize fcount < <(node_block foreign.lod 100)
read -r _ ooff osize _ < <(node_block other.lod 100)
patch foreign.lod "$foff" other.lod "$ooff" $((fsize < osize ? fsize : osize))
serve foreign.lod
if shot foreign "$CAM&budget=$total"; then
  if [ "$(attr "$DOM" failed-nodes)" = "$fnode" ] && grep -q "node $fnode failed: its block belongs to another hierarchy" <<<"$DOM" &&
     [ "$(attr "$DOM" splats)" -eq $((total - fcount)) ]; then
    echo "ok   foreign block: $(attr "$DOM" splats) splats drawn, '$(grep -o "node $fnode failed: [^<]*" <<<"$DOM" | head -1)'"
  else
    echo "FAIL foreign block: node $fnode not refused as foreign (failed nodes '$(attr "$DOM" failed-nodes)'; $(grep -o 'node [0-9]* failed: [^<]*' <<<"$DOM" | head -1))"
    fail=1
  fi
fi
stop_server
exit $fail
