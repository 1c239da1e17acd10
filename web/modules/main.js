// linesurf view: WebGL2 splatting of points and line segments (thesis §4.2.2, §5, §6.2; the GPU
// line-segment splatting of §9.3). Embedded in the page by `linesurf view`. A page of a model
// holds it and needs no network; a page of a level-of-detail hierarchy (meta.lod, served by
// `linesurf view MODEL.lod`) reads the hierarchy's nodes from its server by HTTP Range requests,
// chosen for each view within a splat budget as lod::selectNodes chooses them (src/lod/lod_read.cpp).
//
// Frame (Botsch, Hornung, Zwicker, Kobbelt 2005, "High-quality surface splatting on today's GPUs"):
//  1. visibility: every splat writes its depth pushed back by its z threshold (depth only);
//  2. accumulation: fragments not behind that depth add (w * colour, w) into a float target;
//  3. normalisation: colour = sum(w c) / sum(w), background where nothing was drawn.
// Each splat is a quad in its own tangent plane, so the GPU's perspective-correct interpolation
// gives the exact ray-plane intersection at every pixel centre, as the CPU renderer computes it
// (src/render/point_splat.cpp, segment_splat.cpp). Conventions follow include/linesurf/render/
// camera.h and render_options.h, so a view here and `linesurf render` from the same camera agree.
//
// This module is the entry: web/bundle.cmake bundles it with the modules it imports into the
// one script of the page; the modules also load as they are (<script type="module">).
import { runBench } from './bench.js';
import { createBatches } from './batch.js';
import { attachControls } from './controls.js';
import { $, fail } from './dom.js';
import { compile, createContext } from './gl.js';
import { createLod } from './lod.js';
import { loadModel, readMeta } from './model.js';
import { bindPanel, countDrawn, initPanel } from './panel.js';
import { createRenderer } from './renderer.js';
import { POINT_FS, POINT_VS, RESOLVE_FS, RESOLVE_VS, SEGMENT_FS, SEGMENT_VS } from './shaders.js';
import { createCameras, fmt, initialState, parseFragment } from './view_state.js';

function main() {
  const meta = readMeta();
  const lodMode = !!meta.lod;
  const model = lodMode ? null : loadModel(meta);
  const D = meta.defaults;
  const shaderConstants = meta.constants || {};
  const sphere = { center: meta.sphere.center, radius: meta.sphere.radius };
  const canvas = $('gl');
  const { gl, floatBlend, gpuName } = createContext(canvas);

  const pointProg = lodMode || model.np ? compile(gl, POINT_VS, POINT_FS, 'point splat', shaderConstants) : null;
  const segProg = lodMode || model.ns ? compile(gl, SEGMENT_VS, SEGMENT_FS, 'segment splat', shaderConstants) : null;
  const resolveProg = compile(gl, RESOLVE_VS, RESOLVE_FS, 'normalisation', shaderConstants);

  const { makeBatch, deleteBatch } = createBatches(gl, D.defaultColor);
  const batches = model ? [makeBatch(model.points, model.np, model.segments, model.ns)] : [];

  // ---- state -------------------------------------------------------------------------------
  const params = parseFragment(location.hash);
  const state = initialState(params);
  initPanel(meta, model, params, state);
  const { defaultCamera, cameraFromFragment } = createCameras(sphere, D, canvas, params);

  const renderer = createRenderer({ gl, canvas, state, sphere, D, floatBlend, model, pointProg, segProg, resolveProg });
  const { renderFrame, sync } = renderer;
  const lod = lodMode ? createLod(meta.lod, { params, state, canvas, sphere, shaderConstants, renderer, makeBatch,
                                              deleteBatch, drawSoon, describeCamera, requestDraw }) : null;

  // ---- drawing -----------------------------------------------------------------------------
  let lastFrameMs = 0, counts = { points: 0, segments: 0 };

  function describeCamera() {
    const c = state.camera;
    const v3 = (a) => a.map(fmt).join(' ');
    const args = `--size ${canvas.width}x${canvas.height} --eye ${v3(c.eye)} --target ${v3(c.target)} --up ${v3(c.up)} --fov ${fmt(c.fov)}`;
    const file = /^[\w.+-]+$/.test(meta.name || '') ? meta.name : 'MODEL';
    const extra = lodMode ? ' --budget ' + lod.budget
      : typeof meta.renderArguments === 'string' && meta.renderArguments ? ' ' + meta.renderArguments : '';
    $('camera').textContent = 'linesurf render ' + file + ' ' + args + extra;
    const frag = `eye=${c.eye.map(fmt).join(',')}&target=${c.target.map(fmt).join(',')}&up=${c.up.map(fmt).join(',')}&fov=${fmt(c.fov)}`;
    const keep = Object.keys(params).filter((k) => !['eye', 'target', 'up', 'fov'].includes(k))
      .map((k) => encodeURIComponent(k) + '=' + encodeURIComponent(params[k]));
    try { history.replaceState(null, '', '#' + [frag].concat(keep).join('&')); } catch (e) { /* file:// in some browsers */ }
  }

  function draw() {
    const list = lodMode ? lod.frame() : batches;
    const t0 = performance.now();
    renderFrame(list);
    sync();
    lastFrameMs = performance.now() - t0;
    if (lodMode) {
      lod.drawn(list, lastFrameMs);
      finishFrame();
      return;
    }
    counts = countDrawn(model, state, sphere);
    const pct = (a, b) => b ? ' (' + (100 * a / b).toFixed(0) + '%)' : '';
    const parts = [];
    if (model.np) parts.push(state.showPoints ? `${counts.points.toLocaleString('en')} of ${model.np.toLocaleString('en')} points${pct(counts.points, model.np)}` : 'points hidden');
    if (model.ns) parts.push(state.showSegments ? `${counts.segments.toLocaleString('en')} of ${model.ns.toLocaleString('en')} segments${pct(counts.segments, model.ns)}` : 'segments hidden');
    $('counts').textContent = 'front-facing: ' + parts.join(', ');
    finishFrame();
    document.body.setAttribute('data-state', 'drawn');
  }
  function finishFrame() {
    // (under a headless browser's virtual time the clock stands still: no figure then)
    $('frameTime').textContent = (lastFrameMs > 0 ? `frame ${lastFrameMs.toFixed(1)} ms` : 'frame') +
      ` at ${canvas.width}x${canvas.height}` + (gpuName ? ' on ' + gpuName : '') +
      (floatBlend ? '' : ' (half-float accumulation)');
    describeCamera();
  }

  // After nodes arrive: a task, not an animation frame, so that a headless browser under
  // virtual time (which runs animation frames only as its clock advances) draws the complete cut
  // before its budget ends. While requests are still out, at most 5 frames a second (a frame of
  // a large cut is costly, and each would be redrawn soon); the last arrival draws at once.
  let drawTimer = null, drawTimerLast = false;
  function drawSoon(last) {
    if (drawTimer !== null) {
      if (!last || drawTimerLast) return;
      clearTimeout(drawTimer);
    }
    drawTimerLast = !!last;
    drawTimer = setTimeout(() => { drawTimer = null; try { draw(); } catch (e) { fail(e.message); } }, last ? 0 : 200);
  }

  let pending = false;
  function requestDraw() {
    describeCamera();  // at once: the arguments follow the mouse even before the frame is drawn
    if (pending) return;
    pending = true;
    requestAnimationFrame(() => { pending = false; try { draw(); } catch (e) { fail(e.message); } });
  }

  function resize() {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(window.innerWidth * dpr)), h = Math.max(1, Math.round(window.innerHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w;
      canvas.height = h;
    }
    // the default view frames the model for the window's aspect, as `linesurf render --size`
    if (!state.camera || state.autoFramed) { state.camera = defaultCamera(w, h); state.autoFramed = true; }
  }

  resize();  // canvas size first: a fragment without an eye takes the framed default for it
  const fromFragment = cameraFromFragment();
  if (fromFragment) { state.camera = fromFragment; state.autoFramed = false; }

  // ---- controls ----------------------------------------------------------------------------
  attachControls(canvas, state, sphere, requestDraw);
  bindPanel(canvas, state, model, defaultCamera, requestDraw);
  window.addEventListener('resize', () => { resize(); requestDraw(); });
  window.addEventListener('hashchange', () => {
    const p = parseFragment(location.hash);
    if (lodMode && p.budget && Number(p.budget) !== lod.budget) { lod.setBudget(Number(p.budget)); requestDraw(); }
    if (p.eye || p.target || p.up || p.fov) {
      Object.assign(params, p);
      try { state.camera = cameraFromFragment(); state.autoFramed = false; requestDraw(); } catch (e) { fail(e.message); }
    }
  });

  // Benchmark: #bench=N renders N frames (each finished) and reports the median frame time.
  if (params.bench) {
    runBench({ params, canvas, state, defaultCamera, draw, frame: () => (lodMode ? lod.frame() : batches), renderer,
               gpuName, gl });
    return;
  }
  draw();
  if (lodMode) lod.start();
}

try {
  main();
} catch (e) {
  fail(e && e.message ? e.message : String(e));
}
