// The level-of-detail hierarchy's binary format as the page reads it (docs/file-format.md): the
// sizes of its records and a node's block decoded into a batch's arrays.
import { V } from './camera.js';

// Bytes of a record of the node table.
export const RECORD = 88;
// Bytes of a node block's header; 32-bit words of a point and of a segment in the block.
const BLOCK_HEADER = 32, POINT_WORDS = 16, SEGMENT_WORDS = 25;
export const hex8 = (v) => (v >>> 0).toString(16).padStart(8, '0');
export const magic = (dv, at, text) => { for (let k = 0; k < 8; ++k) if (dv.getUint8(at + k) !== text.charCodeAt(k)) return false; return true; };

// A node's block checked (magic, hierarchy id, node number and counts; not its checksum,
// see docs/decisions.md) and decoded as viewer_page.cpp prepares a model's primitives.
export function decodeNodeBlock(lod, i, buf, L, sphere, shaderConstants) {
  const n = lod.nodes[i], dv = new DataView(buf);
  if (!magic(dv, 0, 'LSLODND1')) throw new Error('its block is not a node block (wrong magic)');
  if (dv.getUint32(8, true) !== lod.idLo || dv.getUint32(12, true) !== lod.idHi)
    throw new Error(`its block belongs to another hierarchy (${hex8(dv.getUint32(12, true))}${hex8(dv.getUint32(8, true))}, this one is ${lod.idHex}); refused`);
  if (dv.getUint32(16, true) !== i || dv.getUint32(20, true) !== n.points || dv.getUint32(24, true) !== n.segments)
    throw new Error('its block holds another node');
  const c = sphere.center, inv = 1 / sphere.radius, maxMass = shaderConstants.maxPointMass || 1e6;
  const unit = (x, y, z) => { const l = Math.hypot(x, y, z); return l > 0 && Number.isFinite(l) ? [x / l, y / l, z / l] : [0, 0, 0]; };
  const sn16 = (v) => Math.round(Math.min(1, Math.max(-1, v)) * 32767);
  const un8 = (v) => Math.round(Math.min(1, Math.max(0, Number.isFinite(v) ? v : 0)) * 255);
  const fin = (a, k, m) => { for (let j = 0; j < m; ++j) if (!Number.isFinite(a[k + j])) return false; return true; };
  let P = null, np = 0, S = null, ns = 0;
  if (n.points) {
    const f = new Float32Array(buf, BLOCK_HEADER, n.points * POINT_WORDS);
    const pos = new Float32Array(3 * n.points), nrm = new Int16Array(3 * n.points), rad = new Float32Array(n.points);
    const mass = new Float32Array(n.points);
    const snrm = L.shadingNormals ? new Int16Array(3 * n.points) : null, col = L.colors ? new Uint8Array(4 * n.points) : null;
    for (let k = 0; k < n.points; ++k) {
      const b = k * POINT_WORDS, r = f[b + 13];
      if (!fin(f, b, 6) || !(r > 0) || !Number.isFinite(r)) continue;
      pos[3 * np] = (f[b] - c[0]) * inv; pos[3 * np + 1] = (f[b + 1] - c[1]) * inv; pos[3 * np + 2] = (f[b + 2] - c[2]) * inv;
      const u = unit(f[b + 3], f[b + 4], f[b + 5]);
      for (let j = 0; j < 3; ++j) nrm[3 * np + j] = sn16(u[j]);
      if (snrm) { const m = unit(f[b + 6], f[b + 7], f[b + 8]); for (let j = 0; j < 3; ++j) snrm[3 * np + j] = sn16(m[j]); }
      if (col) for (let j = 0; j < 4; ++j) col[4 * np + j] = un8(f[b + 9 + j]);
      rad[np] = r * inv;
      const m = f[b + 14];
      mass[np] = m > 0 && m <= maxMass ? m : 1;
      ++np;
    }
    const A = (data, comps) => ({ data: data.subarray(0, np * comps), comps: comps });
    P = { position: A(pos, 3), normal: A(nrm, 3), radius: A(rad, 1), mass: A(mass, 1),
          shadingNormal: snrm ? A(snrm, 3) : null, color: col ? A(col, 4) : null, cluster: null };
  }
  if (n.segments) {
    const f = new Float32Array(buf, BLOCK_HEADER + 64 * n.points, n.segments * SEGMENT_WORDS);
    const p0 = new Float32Array(3 * n.segments), p1 = new Float32Array(3 * n.segments), rad = new Float32Array(n.segments);
    const nrm = new Int16Array(3 * n.segments), ends = L.endpointNormals;
    const n0 = ends ? new Int16Array(3 * n.segments) : null, n1 = ends ? new Int16Array(3 * n.segments) : null;
    const col = L.colors ? new Uint8Array(4 * n.segments) : null;
    for (let k = 0; k < n.segments; ++k) {
      const b = k * SEGMENT_WORDS, r = f[b + 19];
      if (!fin(f, b, 9) || !(r > 0) || !Number.isFinite(r) ||
          !(Math.hypot(f[b + 3] - f[b], f[b + 4] - f[b + 1], f[b + 5] - f[b + 2]) > 0)) continue;
      for (let j = 0; j < 3; ++j) { p0[3 * ns + j] = (f[b + j] - c[j]) * inv; p1[3 * ns + j] = (f[b + 3 + j] - c[j]) * inv; }
      const e0 = unit(f[b + 9], f[b + 10], f[b + 11]), e1 = unit(f[b + 12], f[b + 13], f[b + 14]);
      // a smooth segment without a plane normal lies in the plane of its mean endpoint normal
      const smooth = ends && V.len(e0) > 0 && V.len(e1) > 0;
      const planeless = !(f[b + 6] * f[b + 6] + f[b + 7] * f[b + 7] + f[b + 8] * f[b + 8] > 0);
      const u = smooth && planeless ? unit(f[b + 9] + f[b + 12], f[b + 10] + f[b + 13], f[b + 11] + f[b + 14])
        : unit(f[b + 6], f[b + 7], f[b + 8]);
      for (let j = 0; j < 3; ++j) nrm[3 * ns + j] = sn16(u[j]);
      if (ends) for (let j = 0; j < 3; ++j) { n0[3 * ns + j] = sn16(e0[j]); n1[3 * ns + j] = sn16(e1[j]); }
      if (col) for (let j = 0; j < 4; ++j) col[4 * ns + j] = un8(f[b + 15 + j]);
      rad[ns] = r * inv;
      ++ns;
    }
    const A = (data, comps) => ({ data: data.subarray(0, ns * comps), comps: comps });
    S = { p0: A(p0, 3), p1: A(p1, 3), normal: A(nrm, 3), radius: A(rad, 1),
          normal0: ends ? A(n0, 3) : null, normal1: ends ? A(n1, 3) : null, color: col ? A(col, 4) : null };
  }
  return { P: P, np: np, S: S, ns: ns };
}
