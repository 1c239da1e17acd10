// The cut of a level-of-detail hierarchy drawn for a view.
import { V, cameraFrame } from './camera.js';

// lod::selectNodes (src/lod/lod_read.cpp) for the page's camera: a cut refined coarse to
// fine, largest projected node first, while the total stays within the budget.
export function selectNodes(lod, total, cam, w, h, sphere) {
  const nodes = lod.nodes;
  if (lod.budget >= total) return { nodes: lod.leaves, primitives: total };
  const f = cameraFrame(cam, sphere);
  const focal = 0.5 * h / Math.tan(0.5 * cam.fov * Math.PI / 180);
  const tx = 0.5 * w / focal, ty = 0.5 * h / focal;
  const planes = [[1, 0, -tx, 0], [-1, 0, -tx, 0], [0, 1, -ty, 0], [0, -1, -ty, 0], [0, 0, -1, -f.near], [0, 0, 1, f.far]];
  const eye = cam.eye;
  const visible = (i) => {
    const n = nodes[i], d = V.sub(n.center, eye);
    const c = [V.dot(f.right, d), V.dot(f.up, d), V.dot(f.back, d)];
    for (const p of planes) {
      const len = Math.hypot(p[0], p[1], p[2]);
      if (len > 0 && (p[0] * c[0] + p[1] * c[1] + p[2] * c[2] + p[3]) / len < -n.radius) return false;
    }
    return true;
  };
  const priority = (i) => {
    const n = nodes[i], d = V.len(V.sub(n.center, eye)) - n.radius;
    return n.radius / Math.max(d, 1e-6 * Math.max(n.radius, 1e-30));
  };
  // binary max-heap of [priority, node]; ties: the lower node first
  const heap = [];
  const before = (a, b) => a[0] !== b[0] ? a[0] > b[0] : a[1] < b[1];
  const push = (item) => {
    let k = heap.push(item) - 1;
    while (k > 0) {
      const p = (k - 1) >> 1;
      if (!before(heap[k], heap[p])) break;
      [heap[k], heap[p]] = [heap[p], heap[k]];
      k = p;
    }
  };
  const pop = () => {
    const top = heap[0], last = heap.pop();
    if (heap.length) {
      heap[0] = last;
      for (let k = 0; ;) {
        const l = 2 * k + 1, r = l + 1;
        let m = k;
        if (l < heap.length && before(heap[l], heap[m])) m = l;
        if (r < heap.length && before(heap[r], heap[m])) m = r;
        if (m === k) break;
        [heap[k], heap[m]] = [heap[m], heap[k]];
        k = m;
      }
    }
    return top;
  };
  const inCut = new Uint8Array(nodes.length);
  inCut[0] = 1;
  let sum = nodes[0].count;
  if (!nodes[0].leaf) push([priority(0), 0]);
  while (heap.length) {
    const i = pop()[1], n = nodes[i];
    let cost = -n.count;
    for (let c = n.firstChild; c < n.firstChild + n.childCount; ++c) if (visible(c)) cost += nodes[c].count;
    if (sum + cost > lod.budget) continue;  // stays coarse; smaller nodes may still fit
    sum += cost;
    inCut[i] = 0;
    for (let c = n.firstChild; c < n.firstChild + n.childCount; ++c)
      if (visible(c)) {
        inCut[c] = 1;
        if (!nodes[c].leaf) push([priority(c), c]);
      }
  }
  const out = [];
  for (let i = 0; i < nodes.length; ++i) if (inCut[i]) out.push(i);
  return { nodes: out, primitives: sum };
}
