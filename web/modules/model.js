// The model embedded in the page: its description (JSON) and its arrays (base64), each checked
// against the buffer before the viewer reads it.
import { $ } from './dom.js';

const TYPES = { f32: [Float32Array, 4], i16: [Int16Array, 2], u8: [Uint8Array, 1] };

function decodeBase64(text) {
  const s = atob(text.replace(/\s+/g, ''));
  const out = new Uint8Array(s.length);
  for (let i = 0; i < s.length; ++i) out[i] = s.charCodeAt(i);
  return out.buffer;
}

// A typed view of one embedded array, checked against the buffer.
function arrayOf(buffer, desc, count, what) {
  if (!desc) return null;
  const t = TYPES[desc.type];
  if (!t) throw new Error(what + ': unknown element type ' + desc.type);
  const comps = desc.components | 0;
  if (!(comps >= 1 && comps <= 4)) throw new Error(what + ': bad component count');
  const off = desc.offset;
  if (!Number.isInteger(off) || off < 0 || off % t[1] !== 0) throw new Error(what + ': bad offset');
  if (off + count * comps * t[1] > buffer.byteLength)
    throw new Error(what + ': the embedded data is truncated (' + buffer.byteLength + ' bytes)');
  return { data: new t[0](buffer, off, count * comps), desc: desc, comps: comps };
}

export function readMeta() {
  let meta;
  try {
    meta = JSON.parse($('linesurf-meta').textContent);
  } catch (e) {
    throw new Error('the model description is not valid JSON (' + e.message + ')');
  }
  if (!meta || meta.format !== 'linesurf-view' || meta.version !== 1)
    throw new Error('not a linesurf view model (format/version)');
  const s = meta.sphere;
  if (!s || !(s.radius > 0) || !s.center || s.center.length !== 3 || !s.center.every(Number.isFinite))
    throw new Error('bad bounding sphere');
  return meta;
}

export function loadModel(meta) {
  let buffer;
  try {
    buffer = decodeBase64($('linesurf-data').textContent);
  } catch (e) {
    throw new Error('the embedded model data is not valid base64');
  }
  if (buffer.byteLength !== meta.bytes)
    throw new Error('the embedded data holds ' + buffer.byteLength + ' bytes, the description says ' + meta.bytes);
  const np = meta.points ? meta.points.count : 0, ns = meta.segments ? meta.segments.count : 0;
  if (!Number.isInteger(np) || !Number.isInteger(ns) || np < 0 || ns < 0) throw new Error('bad primitive counts');
  if (np + ns === 0) throw new Error('the model holds no drawable point or segment');
  const model = { meta: meta, np: np, ns: ns };
  const arrays = (desc, count, names, what) => {
    const out = {};
    for (const k of names) out[k] = arrayOf(buffer, desc[k], count, what + ' ' + k);
    return out;
  };
  if (np) {
    model.points = arrays(meta.points, np, ['position', 'normal', 'shadingNormal', 'radius', 'color', 'cluster', 'mass'], 'point');
    if (!model.points.position || !model.points.normal || !model.points.radius)
      throw new Error('points need positions, normals and radii');
  }
  if (ns) {
    model.segments = arrays(meta.segments, ns, ['p0', 'p1', 'normal', 'normal0', 'normal1', 'radius', 'color'], 'segment');
    if (!model.segments.p0 || !model.segments.p1 || !model.segments.normal || !model.segments.radius)
      throw new Error('segments need endpoints, normals and radii');
  }
  return model;
}
