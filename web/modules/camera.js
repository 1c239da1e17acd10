// Vectors of three numbers and the camera (include/linesurf/render/camera.h), as `linesurf render`
// places it.

export const V = {
  add: (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
  sub: (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
  mul: (a, s) => [a[0] * s, a[1] * s, a[2] * s],
  dot: (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
  cross: (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
  len: (a) => Math.hypot(a[0], a[1], a[2]),
  norm: (a) => { const l = Math.hypot(a[0], a[1], a[2]); return l > 0 ? [a[0] / l, a[1] / l, a[2] / l] : [0, 0, 0]; },
};
// Rodrigues rotation of v about unit axis k by angle t.
export function rotate(v, k, t) {
  const c = Math.cos(t), s = Math.sin(t);
  return V.add(V.add(V.mul(v, c), V.mul(V.cross(k, v), s)), V.mul(k, V.dot(k, v) * (1 - c)));
}

// Camera::lookAt + update(): rows right, trueUp, back; near/far as `linesurf render --eye`.
export function cameraFrame(cam, sphere) {
  const back = V.norm(V.sub(cam.eye, cam.target));
  let up = cam.up;
  if (V.len(up) === 0 || V.len(V.cross(V.norm(up), back)) < 1e-4) {
    const a = back.map(Math.abs);
    up = a[0] <= a[1] && a[0] <= a[2] ? [1, 0, 0] : (a[1] <= a[2] ? [0, 1, 0] : [0, 0, 1]);
  }
  const right = V.norm(V.cross(up, back));
  const trueUp = V.cross(back, right);
  const dist = V.len(V.sub(cam.eye, cam.target));
  const nearD = Math.max(1e-4 * dist, dist - 1.5 * sphere.radius);
  const farD = Math.max(dist + 1.5 * sphere.radius, 2 * nearD);
  return { right: right, up: trueUp, back: back, dist: dist, near: nearD, far: farD };
}

function frontAxis(u) {
  let f = Math.abs(u[1]) > 0.9 ? [0, 0, 1] : u[2] > 0.9 ? [0, -1, 0] : u[2] < -0.9 ? [0, 1, 0] : [0, 0, 1];
  return V.norm(V.sub(f, V.mul(u, V.dot(f, u))));
}

// Camera::orbit with distance 0 (framed): the default view of `linesurf render`.
export function orbitCamera(sphere, azDeg, elDeg, fovDeg, width, height, upAxis) {
  const r = sphere.radius;
  const halfY = 0.5 * fovDeg * Math.PI / 180;
  const halfX = Math.atan(Math.tan(halfY) * width / height);
  const dist = 1.05 * r / Math.sin(Math.min(halfX, halfY));
  const az = azDeg * Math.PI / 180, el = elDeg * Math.PI / 180;
  const U = V.norm(upAxis), F = frontAxis(U), Rt = V.cross(U, F);
  const dir = V.add(V.mul(V.add(V.mul(F, Math.cos(az)), V.mul(Rt, Math.sin(az))), Math.cos(el)), V.mul(U, Math.sin(el)));
  return { eye: V.add(sphere.center, V.mul(dir, dist)), target: sphere.center.slice(), up: U.slice(), fov: fovDeg };
}
