// Orbit, pan and zoom of the camera by mouse, touch and wheel; each change asks for a frame.
import { V, cameraFrame, rotate } from './camera.js';

// The controls on `canvas` for the camera of `state` around the model's bounding sphere.
export function attachControls(canvas, state, sphere, requestDraw) {
  function orbit(dx, dy) {
    const c = state.camera;
    const up = V.norm(c.up);
    let off = V.sub(c.eye, c.target);
    off = rotate(off, up, -dx * 0.008);
    const f = cameraFrame({ eye: V.add(c.target, off), target: c.target, up: c.up }, sphere);
    const rotated = rotate(off, f.right, -dy * 0.008);
    // keep away from the poles of the up axis (turntable)
    if (Math.abs(V.dot(V.norm(rotated), up)) < 0.995) off = rotated;
    c.eye = V.add(c.target, off);
    state.autoFramed = false;
  }
  function pan(dx, dy) {
    const c = state.camera;
    const f = cameraFrame(c, sphere);
    const perPixel = 2 * f.dist * Math.tan(0.5 * c.fov * Math.PI / 180) / canvas.height * (window.devicePixelRatio || 1);
    const move = V.add(V.mul(f.right, -dx * perPixel), V.mul(f.up, dy * perPixel));
    c.eye = V.add(c.eye, move);
    c.target = V.add(c.target, move);
    state.autoFramed = false;
  }
  function zoom(factor) {
    const c = state.camera;
    const off = V.sub(c.eye, c.target);
    const d = V.len(off);
    const nd = Math.min(Math.max(d * factor, 1e-3 * sphere.radius), 1e3 * sphere.radius);
    c.eye = V.add(c.target, V.mul(off, nd / d));
    state.autoFramed = false;
  }
  const pointers = new Map();
  let gesture = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    try { canvas.setPointerCapture(e.pointerId); } catch (err) { /* synthetic or vanished pointer */ }
    pointers.set(e.pointerId, { x: e.clientX, y: e.clientY, button: e.button, shift: e.shiftKey });
    gesture = null;
  });
  const release = (e) => { pointers.delete(e.pointerId); gesture = null; };
  canvas.addEventListener('pointerup', release);
  canvas.addEventListener('pointercancel', release);
  canvas.addEventListener('pointermove', (e) => {
    const p = pointers.get(e.pointerId);
    if (!p) return;
    if (pointers.size === 1) {
      const dx = e.clientX - p.x, dy = e.clientY - p.y;
      if (p.button === 2 || p.button === 1 || p.shift || e.shiftKey) pan(dx, dy);
      else orbit(dx, dy);
    } else if (pointers.size === 2) {
      const others = [...pointers.entries()].filter(([id]) => id !== e.pointerId);
      const q = others[0][1];
      const before = Math.hypot(p.x - q.x, p.y - q.y), after = Math.hypot(e.clientX - q.x, e.clientY - q.y);
      if (before > 0 && after > 0) zoom(before / after);
      pan((e.clientX - p.x) / 2, (e.clientY - p.y) / 2);
    }
    p.x = e.clientX;
    p.y = e.clientY;
    requestDraw();
  });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const dy = e.deltaMode === 1 ? e.deltaY * 33 : e.deltaMode === 2 ? e.deltaY * 400 : e.deltaY;
    zoom(Math.exp(dy * 0.0015));
    requestDraw();
  }, { passive: false });
}
