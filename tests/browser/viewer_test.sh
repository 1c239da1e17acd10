#!/usr/bin/env bash
# Browser test of `linesurf view`: headless Chromium (software GL: SwiftShader) loads
# the viewer page of a model with a camera in the URL fragment, takes a screenshot, and compares
# it with `linesurf render` from the same camera by SSIM (igea points and greedy hybrid >= 0.95;
# the Al contour line and point models, which carry shading normals, >= 0.975). Shading
# normals: flat point and segment patches whose shading / endpoint normals lean
# (also along the segments) must be as bright in the page as on the CPU and clearly unlike the
# same patch lit by its plane. Also: a page with damaged data shows a message (never a blank
# canvas) and a model over the budget is refused.
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

# metric A.png B.png KEY: one figure of `linesurf compare` (ssim, mean_abs_diff, ...).
metric() {
  "$LS" compare "$1" "$2" --json | sed -n "s/.*\"$3\": *\([0-9.eE+-]*\).*/\1/p"
}

# check NAME MODEL X,Y,Z(eye) X,Y,Z(target) X,Y,Z(up) FOV [MIN_SSIM]
check() {
  local name=$1 model=$2 eye=$3 target=$4 up=$5 fov=$6 min=${7:-$MIN_SSIM}
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
  if awk -v s="$ssim" -v m="$min" 'BEGIN { exit !(s >= m) }'; then
    echo "ok   $name: SSIM $ssim (viewer vs linesurf render, >= $min)"
  else
    echo "FAIL $name: SSIM $ssim < $min (images in $WORK)"
    fail=1
  fi
}

"$LS" extract shape-approx "$SRC/data/igea_points.ply" -o igea_greedy.ply -q
"$LS" extract contour "$SRC/data/al_mesh.ply" -o al_contour.ply --seed 1 -q
check igea_points "$SRC/data/igea_points.ply" 0.15,0.1,0.3 0,0,0 0,1,0 30
check igea_greedy igea_greedy.ply -0.2,0.05,0.25 0,0,0 0,1,0 30
# contour models carry shading normals (points) and endpoint normals leaning along the segments
# (lit as `linesurf render` lights them); measured 0.986 (lines) and 0.987 (points; 0.953 with the
# plane normals lighting)
"$LS" extract contour "$SRC/data/al_mesh.ply" -o al_contour_points.ply --seed 1 --all-points -q
check al_contour al_contour.ply 2.5,1.5,3 0,0.68,0 0,1,0 30 0.975
check al_contour_points al_contour_points.ply 2.5,1.5,3 0,0.68,0 0,1,0 30 0.975

# Shading normals (docs/decisions.md "Smooth contour models"). A flat square in z = 0 (plane normal
# +z) that fills the view; its shading normals lean like those of a dome, normalize(0.8 x, 0.8 y, 1)
# (up to 42 degrees in the view), which the headlight turns into a gradient. A point patch with them
# as shading normals (snx sny snz), and a line patch (segments along x) with them as endpoint
# normals, so that they lean along the segment as well as across it. The page must match
# `linesurf render` (mean |difference| <= MAX_SHADE_DIFF grey levels) and differ from the patch lit by its
# plane normal (>= MIN_SHADE_CONTRAST levels: a page that ignored the shading normals would fail the
# first).
MAX_SHADE_DIFF=${MAX_SHADE_DIFF:-2}
MIN_SHADE_CONTRAST=${MIN_SHADE_CONTRAST:-10}
# patch KIND(points|segments) TILT(0|1) > FILE.ply: ascii PLY, spacing 0.02 over [-1.2, 1.2]^2
patch() {
  awk -v kind="$1" -v tilt="$2" 'function n(x, y, w,   l) { l = sqrt(0.64 * tilt * (x * x + y * y) + 1)
      w = (0.8 * tilt * x / l) " " (0.8 * tilt * y / l) " " (1 / l); return w }
    BEGIN {
      h = 0.02; m = 120; seg = 5
      cp = kind == "points" ? (m + 1) * (m + 1) : (m + 1) * (m / seg); cs = kind == "points" ? 0 : cp
      print "ply"; print "format ascii 1.0"
      print "element vertex " (kind == "points" ? cp : 0)
      print "property float x"; print "property float y"; print "property float z"
      print "property float nx"; print "property float ny"; print "property float nz"; print "property float radius"
      if (kind == "points") { print "property float snx"; print "property float sny"; print "property float snz" }
      if (kind != "points") {
        print "element segment " cs
        print "property float x0"; print "property float y0"; print "property float z0"
        print "property float x1"; print "property float y1"; print "property float z1"
        print "property float nx"; print "property float ny"; print "property float nz"; print "property float radius"
        print "property float nx0"; print "property float ny0"; print "property float nz0"
        print "property float nx1"; print "property float ny1"; print "property float nz1"
      }
      print "end_header"
      for (j = 0; j <= m; ++j) {
        y = -1.2 + j * h
        if (kind == "points") for (i = 0; i <= m; ++i) { x = -1.2 + i * h; print x, y, 0, 0, 0, 1, 0.8 * h, n(x, y) }
        else for (i = 0; i < m; i += seg) { x = -1.2 + i * h; x1 = x + seg * h
          print x, y, 0, x1, y, 0, 0, 0, 1, 0.55 * h, n(x, y), n(x1, y) }
      }
    }'
}
for kind in points segments; do
  patch "$kind" 1 >"shade_$kind.ply"
  patch "$kind" 0 >"flat_$kind.ply"
  "$LS" view "shade_$kind.ply" -o "shade_$kind.html" -q
  chrome "shade_$kind.html" "eye=0,0,3&target=0,0,0&up=0,1,0&fov=30&ui=0" \
    --window-size=256,256 --virtual-time-budget=10000 --screenshot="$WORK/shade_${kind}_viewer.png" >/dev/null
  for m in shade flat; do
    "$LS" render "${m}_$kind.ply" -o "${m}_${kind}_render.png" --size 256x256 --eye 0 0 3 --target 0 0 0 --up 0 1 0 \
      --fov 30 -q
  done
  if [ ! -s "shade_${kind}_viewer.png" ]; then
    echo "FAIL shading normals ($kind): chromium wrote no screenshot"
    fail=1
    continue
  fi
  diff=$(metric "shade_${kind}_render.png" "shade_${kind}_viewer.png" mean_abs_diff)
  contrast=$(metric "shade_${kind}_render.png" "flat_${kind}_render.png" mean_abs_diff)
  ignored=$(metric "shade_${kind}_viewer.png" "flat_${kind}_render.png" mean_abs_diff)
  if awk -v d="$diff" -v c="$contrast" -v md="$MAX_SHADE_DIFF" -v mc="$MIN_SHADE_CONTRAST" \
       'BEGIN { exit !(d <= md && c >= mc) }'; then
    echo "ok   shading normals ($kind): page vs render mean |diff| $diff <= $MAX_SHADE_DIFF; vs the plane-lit patch $ignored (render: $contrast >= $MIN_SHADE_CONTRAST)"
  else
    echo "FAIL shading normals ($kind): page vs render mean |diff| $diff (max $MAX_SHADE_DIFF), plane-lit contrast $contrast (min $MIN_SHADE_CONTRAST), page vs plane-lit $ignored (images in $WORK)"
    fail=1
  fi
done

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

# The panel says which optional attributes light and weigh the model (point shading
# normals and masses).
dom=$(chrome al_contour_points.html "" --window-size=512,512 --virtual-time-budget=5000 --dump-dom | tr '\n' ' ')
if grep -q '<div class="row" id="attributes">model carries: point shading normals, point masses</div>' <<<"$dom"; then
  echo "ok   panel: 'model carries: point shading normals, point masses'"
else
  echo "FAIL panel: no 'model carries: point shading normals, point masses' ($(grep -o '<div class="row" id="attributes"[^<]*' <<<"$dom"))"
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
