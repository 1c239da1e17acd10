#!/usr/bin/env bash
# Browser test of `linesurf view` (issue 16): headless Chromium (software GL: SwiftShader) loads
# the viewer page of three models with a camera in the URL fragment, takes a screenshot, and
# compares it with `linesurf render` from the same camera (SSIM >= 0.95 each). Also: a page with
# damaged data shows a message (never a blank canvas) and a model over the budget is refused.
# Usage: viewer_test.sh LINESURF SOURCE_DIR WORK_DIR. Exit 77 (CTest: skipped) without chromium.
set -euo pipefail
LS=$(realpath "$1")
SRC=$(realpath "$2")
WORK=$3
MIN_SSIM=${MIN_SSIM:-0.95}
CHROMIUM=${CHROMIUM:-$(command -v chromium || command -v chromium-browser || true)}
if [ -z "$CHROMIUM" ]; then
  echo "SKIP: chromium not found (scripts/setup.sh installs Debian's chromium)"
  exit 77
fi
rm -rf "$WORK"
mkdir -p "$WORK"
cd "$WORK"
fail=0

# chrome PAGE FRAGMENT ARGS...: one headless run with a fresh profile.
chrome() {
  local page=$1 frag=$2
  shift 2
  local profile
  profile=$(mktemp -d "$WORK/profile.XXXXXX")
  timeout 120 "$CHROMIUM" --headless --no-sandbox --use-angle=swiftshader --enable-unsafe-swiftshader \
    --disable-background-networking --disable-component-update --disable-sync --no-first-run \
    --disable-default-apps --mute-audio --hide-scrollbars --force-device-scale-factor=1 \
    --user-data-dir="$profile" "$@" "file://$WORK/$page#$frag" 2>>"$WORK/chromium.log"
  rm -rf "$profile"
}

# case NAME MODEL X,Y,Z(eye) X,Y,Z(target) X,Y,Z(up) FOV
check() {
  local name=$1 model=$2 eye=$3 target=$4 up=$5 fov=$6
  "$LS" view "$model" -o "$name.html" -q
  chrome "$name.html" "eye=$eye&target=$target&up=$up&fov=$fov&ui=0" \
    --window-size=512,512 --virtual-time-budget=10000 --screenshot="$WORK/${name}_viewer.png" >/dev/null
  if [ ! -s "${name}_viewer.png" ]; then
    echo "FAIL $name: chromium wrote no screenshot (see $WORK/chromium.log)"
    fail=1
    return
  fi
  "$LS" render "$model" -o "${name}_render.png" --size 512x512 --eye ${eye//,/ } --target ${target//,/ } \
    --up ${up//,/ } --fov "$fov" -q
  local ssim
  ssim=$("$LS" compare "${name}_render.png" "${name}_viewer.png" --diff "${name}_diff.png" --json |
    sed -n 's/.*"ssim": *\([0-9.eE+-]*\).*/\1/p')
  if awk -v s="$ssim" -v m="$MIN_SSIM" 'BEGIN { exit !(s >= m) }'; then
    echo "ok   $name: SSIM $ssim (viewer vs linesurf render, >= $MIN_SSIM)"
  else
    echo "FAIL $name: SSIM $ssim < $MIN_SSIM (images in $WORK)"
    fail=1
  fi
}

"$LS" extract shape-approx "$SRC/data/igea_points.ply" -o igea_greedy.ply -q
"$LS" extract contour "$SRC/data/al_mesh.ply" -o al_contour.ply --seed 1 -q
check igea_points "$SRC/data/igea_points.ply" 0.15,0.1,0.3 0,0,0 0,1,0 30
check igea_greedy igea_greedy.ply -0.2,0.05,0.25 0,0,0 0,1,0 30
check al_contour al_contour.ply 2.5,1.5,3 0,0.68,0 0,1,0 30

# Controls: a mouse drag orbits (the camera shown as render arguments changes), the wheel zooms,
# a right-drag pans, and "reset view" brings back the default view. Synthetic pointer events.
cat >probe.js <<'JS'
<script>
setTimeout(() => {
  const c = document.getElementById('gl'), cam = () => document.getElementById('camera').textContent;
  const ev = (type, x, y, button) => c.dispatchEvent(new PointerEvent(type, { pointerId: 7, clientX: x, clientY: y,
    button: button, buttons: 1, bubbles: true }));
  const out = [cam()];
  const step = (f) => new Promise((r) => { f(); setTimeout(r, 100); });
  step(() => { ev('pointerdown', 200, 200, 0); ev('pointermove', 260, 230, 0); ev('pointerup', 260, 230, 0); })
    .then(() => { out.push(cam()); return step(() => c.dispatchEvent(new WheelEvent('wheel', { deltaY: 300, bubbles: true, cancelable: true }))); })
    .then(() => { out.push(cam()); return step(() => { ev('pointerdown', 200, 200, 2); ev('pointermove', 230, 200, 2); ev('pointerup', 230, 200, 2); }); })
    .then(() => { out.push(cam()); return step(() => document.getElementById('reset').click()); })
    .then(() => { out.push(cam()); const p = document.createElement('pre'); p.id = 'probe'; p.textContent = out.join('\n'); document.body.appendChild(p); });
}, 200);
</script>
JS
sed '/<\/body>/e cat probe.js' al_contour.html >probe.html
dom=$(chrome probe.html "" --window-size=512,512 --virtual-time-budget=10000 --dump-dom)
mapfile -t cams < <(sed -n '/<pre id="probe">/,/<\/pre>/p' <<<"$dom" | sed 's/<[^>]*>//g' | grep 'linesurf render')
if [ ${#cams[@]} -eq 5 ] && [ "${cams[1]}" != "${cams[0]}" ] && [ "${cams[2]}" != "${cams[1]}" ] &&
   [ "${cams[3]}" != "${cams[2]}" ] && [ "${cams[4]}" = "${cams[0]}" ]; then
  echo "ok   controls: orbit, zoom and pan move the camera, reset restores '${cams[0]#*al_contour.ply }'"
else
  echo "FAIL controls: cameras seen:"
  printf '  %s\n' "${cams[@]}"
  fail=1
fi

# A damaged page shows its message instead of a blank canvas.
# (the first 8 base64 characters of the model data cut: 6 bytes missing)
sed -E 's|(<script id="linesurf-data" type="application/octet-stream">)[A-Za-z0-9+/]{8}|\1|' al_contour.html >damaged.html
if cmp -s al_contour.html damaged.html; then echo "FAIL damaged: could not damage the page"; fail=1; fi
# expect_message NAME PAGE CHROMIUM-FLAGS...: the page shows its error message, not a blank canvas.
expect_message() {
  local name=$1 page=$2
  shift 2
  local dom
  dom=$(chrome "$page" "" --window-size=512,512 --virtual-time-budget=5000 --dump-dom "$@" | tr '\n' ' ')
  if grep -q '<body data-state="error">' <<<"$dom" && grep -q '<div id="error">linesurf view cannot draw' <<<"$dom"; then
    echo "ok   $name: shows '$(grep -o '<div id="error">[^<]*' <<<"$dom" | sed 's/<div id="error">//')'"
  else
    echo "FAIL $name: no visible error message"
    fail=1
  fi
}
expect_message "damaged page" damaged.html
expect_message "no WebGL2" al_contour.html --disable-webgl2

# Over the page's budget: refused with a one-line error and exit code 2, no page written.
set +e
err=$("$LS" view "$SRC/data/igea_points.ply" -o over.html --max-primitives 1000 2>&1 >/dev/null)
code=$?
set -e
if [ "$code" -eq 2 ] && [ "$(printf '%s\n' "$err" | wc -l)" -eq 1 ] && [ ! -e over.html ] && grep -q budget <<<"$err"; then
  echo "ok   over budget: exit $code, '$err'"
else
  echo "FAIL over budget: exit $code, '$err'"
  fail=1
fi
exit $fail
