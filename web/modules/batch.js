// The GPU's copy of splats: a batch holds the points and segments of one draw in vertex arrays.
//
// Buffers: one per attribute, each splat's values repeated at its 4 corner vertices, and an
// index buffer of 2 triangles per splat (corner = gl_VertexID & 3). Not instancing: software
// GL (SwiftShader) runs every instance as a draw of its own, ~30x slower. They are created
// into `buffers` (to delete them with their batch); each returns its size in bytes.
export function createBatches(gl, defaultColor) {
  function attrib(loc, arr, normalized, buffers) {
    const src = arr.data, c = arr.comps, n = src.length / c;
    const dst = new src.constructor(src.length * 4);
    for (let i = 0; i < n; ++i)
      for (let v = 0; v < 4; ++v)
        for (let j = 0; j < c; ++j) dst[(4 * i + v) * c + j] = src[i * c + j];
    const buf = gl.createBuffer();
    buffers.push(buf);
    gl.bindBuffer(gl.ARRAY_BUFFER, buf);
    gl.bufferData(gl.ARRAY_BUFFER, dst, gl.STATIC_DRAW);
    const type = src instanceof Float32Array ? gl.FLOAT : src instanceof Int16Array ? gl.SHORT : gl.UNSIGNED_BYTE;
    gl.enableVertexAttribArray(loc);
    gl.vertexAttribPointer(loc, c, type, normalized, 0, 0);
    return dst.byteLength;
  }
  function quadIndices(n, buffers) {
    const idx = new Uint32Array(6 * n);
    for (let i = 0, k = 0; i < n; ++i, k += 6) {
      const b = 4 * i;
      idx[k] = b; idx[k + 1] = b + 1; idx[k + 2] = b + 2; idx[k + 3] = b + 2; idx[k + 4] = b + 1; idx[k + 5] = b + 3;
    }
    const buf = gl.createBuffer();
    buffers.push(buf);
    gl.bindBuffer(gl.ELEMENT_ARRAY_BUFFER, buf);
    gl.bufferData(gl.ELEMENT_ARRAY_BUFFER, idx, gl.STATIC_DRAW);
    return idx.byteLength;
  }
  // A batch: the points and segments of one draw (the whole model, or one node of a hierarchy),
  // each kind in a vertex array of its own. P and S hold typed arrays as loadModel() gives them.
  function makeBatch(P, np, S, ns) {
    const b = { np: np, ns: ns, pointVao: null, segVao: null, endpointNormals: false, buffers: [], bytes: 0 };
    const B = b.buffers;
    if (np) {
      b.pointVao = gl.createVertexArray();
      gl.bindVertexArray(b.pointVao);
      b.bytes += attrib(0, P.position, false, B) + attrib(1, P.normal, true, B) + attrib(2, P.radius, false, B);
      if (P.color) b.bytes += attrib(3, P.color, true, B);
      else { gl.disableVertexAttribArray(3); gl.vertexAttrib4f(3, defaultColor[0], defaultColor[1], defaultColor[2], 1); }
      if (P.cluster) b.bytes += attrib(4, P.cluster, false, B);
      else { gl.disableVertexAttribArray(4); gl.vertexAttrib1f(4, -1); }
      if (P.shadingNormal) b.bytes += attrib(5, P.shadingNormal, true, B);
      else { gl.disableVertexAttribArray(5); gl.vertexAttrib3f(5, 0, 0, 0); }
      if (P.mass) b.bytes += attrib(6, P.mass, false, B);
      else { gl.disableVertexAttribArray(6); gl.vertexAttrib1f(6, 1); }
      b.bytes += quadIndices(np, B);
    }
    if (ns) {
      b.segVao = gl.createVertexArray();
      gl.bindVertexArray(b.segVao);
      b.bytes += attrib(0, S.p0, false, B) + attrib(1, S.p1, false, B) + attrib(2, S.normal, true, B) +
        attrib(3, S.radius, false, B);
      if (S.color) b.bytes += attrib(4, S.color, true, B);
      else { gl.disableVertexAttribArray(4); gl.vertexAttrib4f(4, defaultColor[0], defaultColor[1], defaultColor[2], 1); }
      b.endpointNormals = !!(S.normal0 && S.normal1);
      if (b.endpointNormals) b.bytes += attrib(5, S.normal0, true, B) + attrib(6, S.normal1, true, B);
      else { gl.disableVertexAttribArray(5); gl.disableVertexAttribArray(6); }
      b.bytes += quadIndices(ns, B);
    }
    gl.bindVertexArray(null);
    return b;
  }
  function deleteBatch(b) {
    if (b.pointVao) gl.deleteVertexArray(b.pointVao);
    if (b.segVao) gl.deleteVertexArray(b.segVao);
    for (const buf of b.buffers) gl.deleteBuffer(buf);
    b.buffers = [];
  }
  return { makeBatch: makeBatch, deleteBatch: deleteBatch };
}
