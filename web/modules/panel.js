// The panel: what the page tells of its model, the options bound to the view's state, and the
// count of the primitives drawn.
import { V } from './camera.js';
import { $ } from './dom.js';

// What the panel shows of the model, and the options the model cannot take switched off.
export function initPanel(meta, model, params, state) {
  if (params.ui === '0') $('ui').classList.add('hidden');
  $('name').textContent = meta.name || '';
  if (meta.name) document.title = meta.name + ' - linesurf view';
  if (!model || !model.np || !(model.points.cluster)) $('clusterOption').disabled = true;
  if (model) {  // the optional attributes the page draws with
    const has = [];
    if (model.np && model.points.shadingNormal) has.push('point shading normals');
    if (model.np && model.points.mass) has.push('point masses');
    if (model.ns && model.segments.normal0 && model.segments.normal1) has.push('segment endpoint normals');
    if ((model.np && model.points.color) || (model.ns && model.segments.color)) has.push('colours');
    if (model.np && model.points.cluster) has.push('cluster ids');
    $('attributes').textContent = has.length ? 'model carries: ' + has.join(', ') : '';
    $('attributes').hidden = !has.length;
  }
  if (state.colorMode === 2 && $('clusterOption').disabled) state.colorMode = 0;
}

// The panel's controls bound to the state: each change asks for a frame.
export function bindPanel(canvas, state, model, defaultCamera, requestDraw) {
  $('reset').addEventListener('click', () => {
    state.camera = defaultCamera(canvas.width, canvas.height);
    state.autoFramed = true;
    requestDraw();
  });
  const bind = (id, key, conv) => {
    const el = $(id);
    const prop = el.type === 'checkbox' ? 'checked' : 'value';
    el[prop] = el.type === 'checkbox' ? state[key] : String(key === 'radiusScale' ? Math.log2(state[key]) : state[key]);
    el.addEventListener('input', () => { state[key] = conv(el[prop]); syncLabels(); requestDraw(); });
  };
  function syncLabels() { $('radiusScaleValue').textContent = state.radiusScale.toFixed(2); }
  bind('showPoints', 'showPoints', Boolean);
  bind('showSegments', 'showSegments', Boolean);
  bind('lighting', 'lighting', Boolean);
  bind('colorMode', 'colorMode', Number);
  bind('radiusScale', 'radiusScale', (v) => Math.pow(2, Number(v)));
  syncLabels();
  if (model && !model.np) $('showPoints').disabled = true;
  if (model && !model.ns) $('showSegments').disabled = true;
}

// Front-facing primitives in front of the camera (the GPU culls the others in its vertex stage).
export function countDrawn(model, state, sphere) {
  const c = { points: 0, segments: 0 };
  const eyeN = V.mul(V.sub(state.camera.eye, sphere.center), 1 / sphere.radius);
  if (model.np && state.showPoints) {
    const p = model.points.position.data, n = model.points.normal.data;
    for (let i = 0, j = 0; i < model.np; ++i, j += 3)
      if ((eyeN[0] - p[j]) * n[j] + (eyeN[1] - p[j + 1]) * n[j + 1] + (eyeN[2] - p[j + 2]) * n[j + 2] > 0) ++c.points;
  }
  if (model.ns && state.showSegments) {
    const p = model.segments.p0.data, n = model.segments.normal.data;
    for (let i = 0, j = 0; i < model.ns; ++i, j += 3)
      if ((eyeN[0] - p[j]) * n[j] + (eyeN[1] - p[j + 1]) * n[j + 1] + (eyeN[2] - p[j + 2]) * n[j + 2] > 0) ++c.segments;
  }
  return c;
}
