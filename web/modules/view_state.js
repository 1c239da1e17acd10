// The view's state: its options and camera, read from the URL fragment (#eye=X,Y,Z&fov=..., as
// describeCamera in main.js writes it back) and the page's defaults.
import { V, orbitCamera } from './camera.js';

export function parseFragment(hash) {
  const out = {};
  for (const part of hash.replace(/^#/, '').split('&')) {
    if (!part) continue;
    const i = part.indexOf('=');
    const key = decodeURIComponent(i < 0 ? part : part.slice(0, i));
    out[key] = decodeURIComponent(i < 0 ? '' : part.slice(i + 1));
  }
  return out;
}
function vec3Param(s, what) {
  const v = s.split(',').map(Number);
  if (v.length !== 3 || !v.every(Number.isFinite)) throw new Error('URL fragment: ' + what + ' needs three numbers X,Y,Z');
  return v;
}
export const fmt = (x) => {
  const s = Number(x).toPrecision(7);
  return String(Number(s));
};

// The options of the panel as the fragment sets them (the panel's defaults otherwise).
export function initialState(params) {
  return {
    showPoints: params.points !== '0',
    showSegments: params.segments !== '0',
    lighting: params.light !== '0',
    colorMode: params.color === 'kind' ? 1 : params.color === 'cluster' ? 2 : 0,
    radiusScale: params.scale ? Math.min(4, Math.max(0.25, Number(params.scale) || 1)) : 1,
    camera: null,
  };
}

// The framed default view of the model (for a canvas of w x h pixels) and the camera the
// fragment names, or null where it names none.
export function createCameras(sphere, D, canvas, params) {
  const upAxis = D.upAxis;
  function defaultCamera(w, h) {
    return orbitCamera(sphere, D.azimuth, D.elevation, D.fov, w, h, upAxis);
  }
  function cameraFromFragment() {
    if (!params.eye && !params.target && !params.up && !params.fov) return null;
    const cam = defaultCamera(canvas.width || 512, canvas.height || 512);
    if (params.eye) cam.eye = vec3Param(params.eye, 'eye');
    if (params.target) cam.target = vec3Param(params.target, 'target');
    if (params.up) cam.up = vec3Param(params.up, 'up');
    if (params.eye && !params.target) cam.target = sphere.center.slice();
    if (params.eye && !params.up) cam.up = [0, 1, 0];
    if (params.fov) {
      cam.fov = Number(params.fov);
      if (!(cam.fov >= 1 && cam.fov <= 170)) throw new Error('URL fragment: fov must be in [1, 170] degrees');
    }
    if (V.len(V.sub(cam.eye, cam.target)) === 0) throw new Error('URL fragment: eye and target must differ');
    return cam;
  }
  return { defaultCamera: defaultCamera, cameraFromFragment: cameraFromFragment };
}
