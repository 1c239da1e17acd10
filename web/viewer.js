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
'use strict';
(function () {
  const $ = (id) => document.getElementById(id);

  function fail(message) {
    const e = $('error');
    e.textContent = 'linesurf view cannot draw this model:\n' + message;
    e.hidden = false;
    document.title = 'linesurf view: error';
    document.body.setAttribute('data-state', 'error');
  }

  // ---- model data -----------------------------------------------------------------------------

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

  function readMeta() {
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

  function loadModel(meta) {
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

  // ---- shaders ----------------------------------------------------------------------------------

  // Uniforms common to both splat kinds. Positions are in model units normalised to the bounding
  // sphere (centre 0, radius 1); every length below is in those units, pixels where stated.
  const COMMON = `#version 300 es
precision highp float;
precision highp int;
uniform mat3 uRot;        // camera from world rotation (rows: right, up, back)
uniform vec3 uTrans;      // camera from world translation
uniform vec2 uHalf;       // principal point (cx, cy) = half the viewport, pixels
uniform float uFocal;     // focal length, pixels: (height / 2) / tan(fovY / 2)
uniform float uNear, uFar;
uniform float uCutoff;    // resampling filter cut-off, standard deviations (RenderOptions::cutoffRadius)
uniform float uRecon;     // sigma_r / radius (RenderOptions::reconstructionScale)
uniform float uVh;        // screen prefilter variance, pixels^2 (RenderOptions::prefilterVariance)
uniform float uRadScale;  // splat size scale
uniform float uZThr;      // z threshold: multiple of the depth extent (RenderOptions::zThreshold, PerPrimitive)
uniform int uColorMode;   // 0 model colour, 1 primitive kind, 2 cluster
uniform vec3 uKindColor;
// The limits the software splats share (src/render), written into the page by viewer_page.cpp.
const float kMaxStretch = @MAX_STRETCH@;
const float kMinFacing = @MIN_FACING@;
vec4 clipFromCamera(vec3 p) {
  float A = -(uFar + uNear) / (uFar - uNear), B = -2.0 * uFar * uNear / (uFar - uNear);
  return vec4(uFocal / uHalf.x * p.x, uFocal / uHalf.y * p.y, A * p.z + B, -p.z);
}
vec3 clusterColor(float id) {
  uint h = uint(id) * 2654435761u;
  h ^= h >> 15; h *= 2246822519u; h ^= h >> 13;
  return vec3(float(h & 255u), float((h >> 8) & 255u), float((h >> 16) & 255u)) / 255.0 * 0.75 + 0.2;
}
`;

  const CULL = 'gl_Position = vec4(2.0, 2.0, 2.0, 1.0); return;';

  // Object-space EWA point splat (thesis §4.2.2), as preparePoint() in src/render/point_splat.cpp.
  const POINT_VS = COMMON + `
layout(location = 0) in vec3 aPos;
layout(location = 1) in vec3 aNrm;
layout(location = 2) in float aRad;
layout(location = 3) in vec4 aCol;
layout(location = 4) in float aCluster;
layout(location = 5) in vec3 aSNrm;  // shading normal, or zero: light by the plane normal
layout(location = 6) in float aMass; // the point's mass (1 when the model has none)
out vec2 vST;          // position in the cut-off ellipse, standard deviations
out vec3 vP;           // camera-space position
flat out vec3 vN;      // the lighting normal
flat out vec3 vAlbedo;
flat out float vScale; // mass / (r0 r1), §5.2.3.3
flat out float vThr;
void main() {
  vST = vec2(0.0); vP = vec3(0.0); vN = vec3(0.0, 0.0, 1.0); vAlbedo = vec3(0.0); vScale = 0.0; vThr = 0.0;
  vec3 c = uRot * aPos + uTrans;
  float d = -c.z;
  vec3 n = uRot * aNrm;
  float nn = length(n), cn = length(c);
  if (!(cn > 0.0)) { ${CULL} }
  vec3 toEye = -c / cn;
  n = nn > 0.0 ? n / nn : toEye;
  float facing = dot(n, toEye);
  if (!(facing >= kMinFacing)) { ${CULL} }  // back-facing (culled) or edge-on
  float radius = aRad * uRadScale;
  if (!(radius > 0.0)) { ${CULL} }
  float sigma = uRecon * radius, R = uCutoff;
  vec3 u = normalize(abs(n.x) < 0.9 ? cross(vec3(1.0, 0.0, 0.0), n) : cross(vec3(0.0, 1.0, 0.0), n));
  vec3 v = cross(n, u);
  float r0 = sigma, r1 = sigma;
  vec2 e0 = vec2(1.0, 0.0);
  if (d > 0.0) {
    // V = sigma_r^2 I + V_h (J^T J)^-1, J the local Jacobian of the projection (§4.2.2)
    vec3 gx = vec3(uFocal / d, 0.0, uFocal * c.x / (d * d));
    vec3 gy = vec3(0.0, -uFocal / d, -uFocal * c.y / (d * d));
    float j00 = dot(gx, u), j01 = dot(gx, v), j10 = dot(gy, u), j11 = dot(gy, v);
    float a = j00 * j00 + j10 * j10, b = j00 * j01 + j10 * j11, cc = j01 * j01 + j11 * j11;
    float det = a * cc - b * b;
    float va = sigma * sigma, vb = 0.0, vc = sigma * sigma;
    if (uVh > 0.0) {
      if (!(det > 0.0)) { ${CULL} }
      float k = uVh / det;
      va += k * cc; vb -= k * b; vc += k * a;
    }
    float mean = 0.5 * (va + vc), diff = 0.5 * (va - vc);
    float rad = sqrt(diff * diff + vb * vb);
    float l0 = mean + rad, l1 = max(mean - rad, 1e-30);
    if (abs(vb) > 1e-30 * (abs(va) + abs(vc)) && vb != 0.0) e0 = normalize(vec2(l0 - vc, vb));
    else e0 = va >= vc ? vec2(1.0, 0.0) : vec2(0.0, 1.0);
    r0 = min(sqrt(l0), kMaxStretch * sigma);
    r1 = min(sqrt(l1), kMaxStretch * sigma);
  }
  vec3 E0 = e0.x * u + e0.y * v;
  vec3 E1 = cross(n, E0);
  vec2 corner = vec2((gl_VertexID & 1) == 1 ? 1.0 : -1.0, (gl_VertexID & 2) == 2 ? 1.0 : -1.0);
  vec3 P = c + R * (corner.x * r0 * E0 + corner.y * r1 * E1);
  vST = R * corner;
  vP = P;
  // lit by the point's shading normal when the model has one (its plane stays n), on the viewer's
  // side of the plane as preparePoint flips it: a drawn plane faces the viewer (culled otherwise),
  // a point without a plane normal takes the shading normal's side facing the eye
  vN = n;
  vec3 m = uRot * aSNrm;
  float ml = length(m);
  if (ml > 0.0) {
    m /= ml;
    vN = nn > 0.0 || dot(m, c) <= 0.0 ? m : -m;
  }
  vScale = aMass / (r0 * r1);
  // depth half-extent of the cut-off ellipse plus the radius (delta-z, §6.2.3.2)
  vThr = uZThr * (R * sqrt(r0 * r0 * E0.z * E0.z + r1 * r1 * E1.z * E1.z) + radius);
  vAlbedo = uColorMode == 1 ? uKindColor : uColorMode == 2 ? (aCluster >= 0.0 ? clusterColor(aCluster) : aCol.rgb) : aCol.rgb;
  gl_Position = clipFromCamera(P);
}
`;

  // Line-segment splat (thesis §5): the footprint box of the strip in its own plane; the fragment
  // shader integrates the resampling Gaussian along the segment in closed form (ScreenSpace method
  // of src/render/segment_splat.cpp with one sub-segment: Gaussian across times a difference of
  // erf along, in the metric of the resampling covariance at the segment's middle).
  const SEGMENT_VS = COMMON + `
layout(location = 0) in vec3 aP0;
layout(location = 1) in vec3 aP1;
layout(location = 2) in vec3 aNrm;
layout(location = 3) in float aRad;
layout(location = 4) in vec4 aCol;
layout(location = 5) in vec3 aN0;
layout(location = 6) in vec3 aN1;
out vec2 vAB;          // (along, across) in the strip's plane, from p0
out vec3 vP;
flat out vec3 vN, vN0, vN1;
flat out vec3 vAlbedo;
flat out vec4 vK;      // skew, across, 1/m00, sqrt(m00 / 2)
flat out vec4 vS;      // scale0, slope, length, erf scale
flat out vec2 vThr;    // z thresholds at p0, p1
uniform bool uEndpointNormals;

// Symmetric 2x2 (m00, m01, m11) with eigenvalues clamped to [lo, hi] (clampEigen).
vec3 clampEigen(vec3 M, float lo, float hi) {
  float a = M.x, b = M.y, c = M.z;
  float mean = 0.5 * (a + c), diff = 0.5 * (a - c);
  float rad = sqrt(diff * diff + b * b);
  float l0 = mean + rad, l1 = mean - rad;
  if (l0 <= hi && l1 >= lo) return M;
  vec2 e0 = rad > 0.0 ? (abs(b) > 0.0 ? normalize(vec2(l0 - c, b)) : (a >= c ? vec2(1.0, 0.0) : vec2(0.0, 1.0)))
                      : vec2(1.0, 0.0);
  vec2 e1 = vec2(-e0.y, e0.x);
  l0 = clamp(l0, lo, hi); l1 = clamp(l1, lo, hi);
  return vec3(l0 * e0.x * e0.x + l1 * e1.x * e1.x, l0 * e0.x * e0.y + l1 * e1.x * e1.y,
              l0 * e0.y * e0.y + l1 * e1.y * e1.y);
}
// Resampling covariance sigma_r^2 I + V_h J^-1 J^-T at camera-space p of the strip (e, s),
// in (along, across) coordinates (§5.1.2; resamplingCovariance()).
vec3 covarianceAt(vec3 p, vec3 e, vec3 s, float sigma) {
  vec3 M = vec3(sigma * sigma, 0.0, sigma * sigma);
  float d = -p.z;
  float hi = (kMaxStretch * sigma) * (kMaxStretch * sigma);
  if (d > 0.0 && uVh > 0.0) {
    vec3 gx = vec3(uFocal / d, 0.0, uFocal * p.x / (d * d));
    vec3 gy = vec3(0.0, -uFocal / d, -uFocal * p.y / (d * d));
    float j00 = dot(gx, e), j01 = dot(gx, s), j10 = dot(gy, e), j11 = dot(gy, s);
    float a = j00 * j00 + j10 * j10, b = j00 * j01 + j10 * j11, c = j01 * j01 + j11 * j11;
    float det = a * c - b * b;
    if (det > 0.0 && !isinf(det)) M += uVh / det * vec3(c, -b, a);
    else return vec3(hi, 0.0, hi);
  }
  return clampEigen(M, sigma * sigma, hi);
}
float det2(vec3 M) { return M.x * M.z - M.y * M.y; }
void main() {
  vAB = vec2(0.0); vP = vec3(0.0); vN = vN0 = vN1 = vec3(0.0, 0.0, 1.0); vAlbedo = vec3(0.0);
  vK = vec4(0.0); vS = vec4(0.0); vThr = vec2(0.0);
  vec3 c0 = uRot * aP0 + uTrans, c1 = uRot * aP1 + uTrans;
  float radius = aRad * uRadScale;
  float L = length(c1 - c0);
  if (!(radius > 0.0) || !(L > 1e-6 * radius)) { ${CULL} }
  vec3 e = (c1 - c0) / L;
  vec3 n = uRot * aNrm;
  n -= dot(n, e) * e;
  if (!(length(n) > 1e-3)) {  // no usable normal: the strip facing the viewer
    vec3 toEye = -(c0 + 0.5 * L * e);
    n = toEye - dot(toEye, e) * e;
    if (!(length(n) > 0.0)) n = abs(e.x) < 0.9 ? cross(vec3(1.0, 0.0, 0.0), e) : cross(vec3(0.0, 1.0, 0.0), e);
  }
  n = normalize(n);
  float D = -dot(n, c0);
  if (D < 0.0) { ${CULL} }  // back-face culling: the strip faces away
  {
    float t = clamp(-dot(c0, e), 0.0, L);
    float dist = length(c0 + t * e);
    if (!(dist > 0.0) || D / dist < kMinFacing) { ${CULL} }
  }
  vec3 s = cross(e, n);
  float R = uCutoff, sigma = uRecon * radius, h = radius;
  vec3 M0 = covarianceAt(c0, e, s, sigma), M1 = covarianceAt(c1, e, s, sigma);
  vec3 M = covarianceAt(c0 + 0.5 * L * e, e, s, sigma);
  float dm = det2(M);
  vec3 Mi = vec3(M.z, -M.y, M.x) / dm;
  float scale0 = 1.0 / (h * sqrt(det2(M0))), scale1 = 1.0 / (h * sqrt(det2(M1)));
  float slope = (scale1 - scale0) / L;
  if (!(abs(slope) * L > 1e-4 * scale0)) slope = 0.0;
  float reach = R * sqrt(M.x);
  float aMin = min(0.0, -reach), aMax = max(L, L + reach), bMax = R * sqrt(M.z);
  vec2 corner = vec2((gl_VertexID & 1) == 1 ? aMax : aMin, (gl_VertexID & 2) == 2 ? bMax : -bMax);
  vec3 P = c0 + corner.x * e + corner.y * s;
  vAB = corner;
  vP = P;
  vN = n;
  vN0 = vN1 = n;
  if (uEndpointNormals && length(aN0) > 0.0 && length(aN1) > 0.0) {
    // smooth line model: shading normals at the ends, on the side of the plane normal (as the CPU)
    vec3 m0 = normalize(uRot * aN0), m1 = normalize(uRot * aN1);
    if (dot(n, m0 + m1) < 0.0) { m0 = -m0; m1 = -m1; }
    vN0 = m0; vN1 = m1;
  }
  float k = sqrt(0.5 * Mi.x);
  vK = vec4(Mi.y / Mi.x, Mi.z - Mi.y * Mi.y / Mi.x, 1.0 / Mi.x, k);
  vS = vec4(scale0, slope, L, 0.886226925 / k);
  vec2 g = vec2(e.z, s.z);
  vThr = uZThr * (R * sqrt(vec2(dot(g, vec2(M0.x * g.x + M0.y * g.y, M0.y * g.x + M0.z * g.y)),
                                dot(g, vec2(M1.x * g.x + M1.y * g.y, M1.y * g.x + M1.z * g.y)))) + radius);
  vAlbedo = uColorMode == 1 ? uKindColor : aCol.rgb;
  gl_Position = clipFromCamera(P);
}
`;

  // Fragment side shared by both kinds: Phong (FrameContext::shade) and the pass logic.
  const FRAG_COMMON = `#version 300 es
precision highp float;
precision highp int;
uniform float uCutoff;
uniform float uNear, uFar;
uniform int uPass;          // 0 visibility (depth + threshold), 1 accumulation
uniform float uWeightNorm;  // constant factor keeping weights near 1 (cancels in the division)
uniform bool uLighting;
uniform vec3 uLight;        // unit direction towards the light, camera space
uniform vec4 uMaterial;     // ambient, diffuse, specular, shininess
out vec4 outColor;
vec3 shade(vec3 albedo, vec3 n, vec3 p) {
  if (!uLighting) return albedo;
  float ndl = max(0.0, dot(n, uLight));
  vec3 c = albedo * (uMaterial.x + uMaterial.y * ndl);
  if (uMaterial.z > 0.0 && ndl > 0.0) {
    float pn = length(p);
    vec3 v = pn > 0.0 ? -p / pn : vec3(0.0, 0.0, 1.0);
    vec3 h = uLight + v;
    float hn = length(h);
    if (hn > 0.0) c += uMaterial.z * pow(max(0.0, dot(n, h / hn)), uMaterial.w);
  }
  return c;
}
// Linear depth -> depth buffer; [near, far] uses [0, 2/3) so a pushed-back depth stays below 1.
float depthValue(float d) { return clamp((d - uNear) / (1.5 * (uFar - uNear)), 0.0, 0.999); }
void emit(float w, float depth, float thr, vec3 color) {
  if (uPass == 0) {
    gl_FragDepth = depthValue(depth + thr);
    outColor = vec4(0.0);
  } else {
    gl_FragDepth = depthValue(depth);
    float ww = w * uWeightNorm;
    outColor = vec4(color * ww, ww);
  }
}
`;

  const POINT_FS = FRAG_COMMON + `
in vec2 vST;
in vec3 vP;
flat in vec3 vN;
flat in vec3 vAlbedo;
flat in float vScale;
flat in float vThr;
void main() {
  float q = dot(vST, vST);
  if (!(q <= uCutoff * uCutoff)) discard;
  float w = exp(-0.5 * q) * vScale;
  emit(w, -vP.z, vThr, uPass == 0 ? vec3(0.0) : shade(vAlbedo, vN, vP));
}
`;

  const SEGMENT_FS = FRAG_COMMON + `
in vec2 vAB;
in vec3 vP;
flat in vec3 vN, vN0, vN1;
flat in vec3 vAlbedo;
flat in vec4 vK;
flat in vec4 vS;
flat in vec2 vThr;
// erf, Abramowitz & Stegun 7.1.26 (|error| < 1.5e-7)
float erf1(float x) {
  float t = 1.0 / (1.0 + 0.3275911 * abs(x));
  float y = 1.0 - (((((1.061405429 * t - 1.453152027) * t) + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t * exp(-x * x);
  return x < 0.0 ? -y : y;
}
void main() {
  float a = vAB.x, b = vAB.y;
  float R2 = uCutoff * uCutoff;
  float skew = vK.x, across = vK.y, invM00 = vK.z, k = vK.w;
  float scale0 = vS.x, slope = vS.y, len = vS.z, erfScale = vS.w;
  // q(tau) = m00 (tau - tau*)^2 + qmin; the kernel at tau counts where q <= R^2 (screenSpaceWeight)
  float tauStar = a + skew * b;
  float qmin = b * b * across;
  if (!(qmin < R2)) discard;
  float delta = sqrt((R2 - qmin) * invM00);
  float t0 = max(0.0, tauStar - delta), t1 = min(len, tauStar + delta);
  if (!(t1 > t0)) discard;
  float u0 = k * (t0 - tauStar), u1 = k * (t1 - tauStar);
  float g = exp(-0.5 * qmin);
  float w = (scale0 + slope * tauStar) * erfScale * (erf1(u1) - erf1(u0)) * g;
  if (slope != 0.0) w += slope * invM00 * g * (exp(-u0 * u0) - exp(-u1 * u1));
  if (!(w > 0.0)) discard;
  float u = clamp(a / len, 0.0, 1.0);
  vec3 color = vec3(0.0);
  if (uPass == 1) {
    vec3 n = vN;
    if (vN0 != vN1) {  // smooth line model: endpoint normals interpolated along the segment
      vec3 m = mix(vN0, vN1, u);
      n = length(m) > 0.0 ? normalize(m) : vN;
    }
    color = shade(vAlbedo, n, vP);
  }
  emit(w, -vP.z, mix(vThr.x, vThr.y, u), color);
}
`;

  const RESOLVE_VS = `#version 300 es
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
`;
  const RESOLVE_FS = `#version 300 es
precision highp float;
uniform highp sampler2D uAccum;
uniform vec3 uBackground;
out vec4 outColor;
void main() {
  vec4 acc = texelFetch(uAccum, ivec2(gl_FragCoord.xy), 0);
  vec3 c = acc.a > 0.0 ? acc.rgb / acc.a : uBackground;
  outColor = vec4(clamp(c, 0.0, 1.0), 1.0);
}
`;

  // Shader constants that must equal the C++ renderer's (meta.constants, from viewer_page.cpp).
  let shaderConstants = {};
  function withConstants(src) {
    return src.replace(/@MAX_STRETCH@/g, glslFloat(shaderConstants.maxStretch))
              .replace(/@MIN_FACING@/g, glslFloat(shaderConstants.minFacing));
  }
  function glslFloat(x) {
    if (!Number.isFinite(x)) throw new Error('the page lacks a shader constant');
    const s = String(x);
    return /[.eE]/.test(s) ? s : s + '.0';
  }

  function compile(gl, vs, fs, name) {
    vs = withConstants(vs);
    fs = withConstants(fs);
    const prog = gl.createProgram();
    for (const [type, src] of [[gl.VERTEX_SHADER, vs], [gl.FRAGMENT_SHADER, fs]]) {
      const sh = gl.createShader(type);
      gl.shaderSource(sh, src);
      gl.compileShader(sh);
      if (!gl.getShaderParameter(sh, gl.COMPILE_STATUS) && !gl.isContextLost())
        throw new Error('the ' + name + ' shader does not compile: ' + gl.getShaderInfoLog(sh));
      gl.attachShader(prog, sh);
    }
    gl.linkProgram(prog);
    if (!gl.getProgramParameter(prog, gl.LINK_STATUS) && !gl.isContextLost())
      throw new Error('the ' + name + ' program does not link: ' + gl.getProgramInfoLog(prog));
    const uniforms = {};
    const n = gl.getProgramParameter(prog, gl.ACTIVE_UNIFORMS);
    for (let i = 0; i < n; ++i) {
      const info = gl.getActiveUniform(prog, i);
      uniforms[info.name] = gl.getUniformLocation(prog, info.name);
    }
    return { prog: prog, u: uniforms };
  }

  // ---- camera (include/linesurf/render/camera.h) ------------------------------------------------

  const V = {
    add: (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]],
    sub: (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]],
    mul: (a, s) => [a[0] * s, a[1] * s, a[2] * s],
    dot: (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2],
    cross: (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
    len: (a) => Math.hypot(a[0], a[1], a[2]),
    norm: (a) => { const l = Math.hypot(a[0], a[1], a[2]); return l > 0 ? [a[0] / l, a[1] / l, a[2] / l] : [0, 0, 0]; },
  };
  // Rodrigues rotation of v about unit axis k by angle t.
  function rotate(v, k, t) {
    const c = Math.cos(t), s = Math.sin(t);
    return V.add(V.add(V.mul(v, c), V.mul(V.cross(k, v), s)), V.mul(k, V.dot(k, v) * (1 - c)));
  }

  // Camera::lookAt + update(): rows right, trueUp, back; near/far as `linesurf render --eye`.
  function cameraFrame(cam, sphere) {
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
  function orbitCamera(sphere, azDeg, elDeg, fovDeg, width, height, upAxis) {
    const r = sphere.radius;
    const halfY = 0.5 * fovDeg * Math.PI / 180;
    const halfX = Math.atan(Math.tan(halfY) * width / height);
    const dist = 1.05 * r / Math.sin(Math.min(halfX, halfY));
    const az = azDeg * Math.PI / 180, el = elDeg * Math.PI / 180;
    const U = V.norm(upAxis), F = frontAxis(U), Rt = V.cross(U, F);
    const dir = V.add(V.mul(V.add(V.mul(F, Math.cos(az)), V.mul(Rt, Math.sin(az))), Math.cos(el)), V.mul(U, Math.sin(el)));
    return { eye: V.add(sphere.center, V.mul(dir, dist)), target: sphere.center.slice(), up: U.slice(), fov: fovDeg };
  }

  function parseFragment(hash) {
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
  const fmt = (x) => {
    const s = Number(x).toPrecision(7);
    return String(Number(s));
  };

  // ---- the viewer -------------------------------------------------------------------------------

  function main() {
    const meta = readMeta();
    const lodMode = !!meta.lod;
    const model = lodMode ? null : loadModel(meta);
    const D = meta.defaults;
    shaderConstants = meta.constants || {};
    const sphere = { center: meta.sphere.center, radius: meta.sphere.radius };
    const upAxis = D.upAxis;
    const canvas = $('gl');
    const gl = canvas.getContext('webgl2', { antialias: false, alpha: false, depth: false, preserveDrawingBuffer: true,
                                             powerPreference: 'high-performance' });
    if (!gl) throw new Error('this browser offers no WebGL2 (needed to draw splats on the GPU)');
    if (!gl.getExtension('EXT_color_buffer_float'))
      throw new Error('WebGL2 is there but without EXT_color_buffer_float (float render targets)');
    const floatBlend = !!gl.getExtension('EXT_float_blend');
    const debugInfo = gl.getExtension('WEBGL_debug_renderer_info');
    const gpuName = (() => {
      const raw = debugInfo ? String(gl.getParameter(debugInfo.UNMASKED_RENDERER_WEBGL)) : '';
      if (/swiftshader/i.test(raw)) return 'software GL (SwiftShader)';
      if (/llvmpipe|softpipe|software/i.test(raw)) return 'software GL';
      return raw.length > 48 ? raw.slice(0, 47) + '\u2026' : raw;
    })();
    canvas.addEventListener('webglcontextlost', (e) => { e.preventDefault(); fail('the WebGL context was lost'); });

    const pointProg = lodMode || model.np ? compile(gl, POINT_VS, POINT_FS, 'point splat') : null;
    const segProg = lodMode || model.ns ? compile(gl, SEGMENT_VS, SEGMENT_FS, 'segment splat') : null;
    const resolveProg = compile(gl, RESOLVE_VS, RESOLVE_FS, 'normalisation');

    // Buffers: one per attribute, each splat's values repeated at its 4 corner vertices, and an
    // index buffer of 2 triangles per splat (corner = gl_VertexID & 3). Not instancing: software
    // GL (SwiftShader) runs every instance as a draw of its own, ~30x slower. They are created
    // into `buffers` (to delete them with their batch); each returns its size in bytes.
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
    const defaultColor = D.defaultColor;
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
    const batches = model ? [makeBatch(model.points, model.np, model.segments, model.ns)] : [];
    const emptyVao = gl.createVertexArray();

    // Weights are 1/length^2 (§5.2.3.3); a constant factor keeps them near 1 in the float target
    // (a hierarchy's: from the first node it loads, then kept).
    function meanRadiusOf(P, S) {
      let sum = 0, nr = 0;
      for (const arr of [P && P.radius, S && S.radius]) {
        if (!arr) continue;
        const step = Math.max(1, Math.floor(arr.data.length / 4096));
        for (let i = 0; i < arr.data.length; i += step) if (arr.data[i] > 0) { sum += arr.data[i]; ++nr; }
      }
      return nr ? sum / nr : 0;
    }
    let meanRadius = model ? meanRadiusOf(model.points, model.segments) || 1 : 0;

    // Render targets: float accumulation + depth.
    let fbo = null, accumTex = null, depthRb = null, fbW = 0, fbH = 0;
    function ensureTargets(w, h) {
      if (fbo && fbW === w && fbH === h) return;
      if (fbo) { gl.deleteFramebuffer(fbo); gl.deleteTexture(accumTex); gl.deleteRenderbuffer(depthRb); }
      accumTex = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, accumTex);
      gl.texStorage2D(gl.TEXTURE_2D, 1, floatBlend ? gl.RGBA32F : gl.RGBA16F, w, h);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      depthRb = gl.createRenderbuffer();
      gl.bindRenderbuffer(gl.RENDERBUFFER, depthRb);
      gl.renderbufferStorage(gl.RENDERBUFFER, gl.DEPTH_COMPONENT32F, w, h);
      fbo = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, accumTex, 0);
      gl.framebufferRenderbuffer(gl.FRAMEBUFFER, gl.DEPTH_ATTACHMENT, gl.RENDERBUFFER, depthRb);
      const st = gl.checkFramebufferStatus(gl.FRAMEBUFFER);
      if (st !== gl.FRAMEBUFFER_COMPLETE) throw new Error('float render target unsupported (status 0x' + st.toString(16) + ')');
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      fbW = w; fbH = h;
    }

    // ---- state -------------------------------------------------------------------------------
    const params = parseFragment(location.hash);
    const state = {
      showPoints: params.points !== '0',
      showSegments: params.segments !== '0',
      lighting: params.light !== '0',
      colorMode: params.color === 'kind' ? 1 : params.color === 'cluster' ? 2 : 0,
      radiusScale: params.scale ? Math.min(4, Math.max(0.25, Number(params.scale) || 1)) : 1,
      camera: null,
    };
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

    // ---- level-of-detail streaming (`linesurf view MODEL.lod`) ---------------------------------
    // The page reads the hierarchy from its server: the preamble, then the JSON header and the node
    // table, then the blocks of the nodes each view needs (docs/file-format.md, "How the viewer
    // reads a hierarchy over HTTP"). Every frame chooses its cut as lod::selectNodes does; a node
    // not loaded yet is drawn through its nearest loaded ancestor, one that failed is left out (as
    // `linesurf render` leaves it out) and named in the panel.
    const lod = lodMode ? createLod(meta.lod) : null;
    function createLod(L) {
      const total = L.points + L.segments;
      const RECORD = 88, BLOCK_HEADER = 32, POINT_WORDS = 16, SEGMENT_WORDS = 25;
      const MAX_REQUEST_BYTES = 16 << 20, MAX_IN_FLIGHT = 4;
      const MIN_BUDGET = Math.min(total, 10000);
      const self = {
        budget: 0, adaptive: params.adaptive === '1',
        targetMs: Math.min(1000, Math.max(5, Number(params.frameMs) || 33)),
        cacheLimit: Math.max(64, Number(params.cache) || 1024) * 1048576,  // GPU bytes of cached nodes
        ready: false, nodes: null, parent: null, leaves: null, idHex: '',
        cache: new Map(),  // node -> batch, least recently drawn first
        cachedBytes: 0, loading: new Set(), failed: new Map(), queue: [], inFlight: 0, bytesFetched: 0,
        selection: null, complete: false, splats: 0, drawnNodes: 0, firstFrameMs: null, emaMs: 0, lastAdapt: 0,
      };
      const hex8 = (v) => (v >>> 0).toString(16).padStart(8, '0');
      const magic = (dv, at, text) => { for (let k = 0; k < 8; ++k) if (dv.getUint8(at + k) !== text.charCodeAt(k)) return false; return true; };
      self.setBudget = (n) => {
        n = Math.round(Number(n));
        self.budget = Number.isFinite(n) ? Math.min(Math.max(n, 1), 2 ** 40) : L.budget;
        $('budget').value = String(self.budget);
        params.budget = String(self.budget);
      };
      self.setBudget(params.budget ? Number(params.budget) : L.budget);

      // [start, end) of the file; the response may be short (checked by the caller).
      async function fetchRange(start, end) {
        const r = await fetch(L.url, { headers: { Range: `bytes=${start}-${end - 1}` }, cache: 'no-store' });
        if (r.status !== 206) throw new Error(`HTTP ${r.status}${r.statusText ? ' ' + r.statusText : ''} for bytes ${start}-${end - 1}`);
        const buf = await r.arrayBuffer();
        self.bytesFetched += buf.byteLength;
        return buf;
      }

      async function loadHeader() {
        const pre = await fetchRange(0, 32);
        if (pre.byteLength < 32) throw new Error(L.url + ': truncated preamble');
        const dv = new DataView(pre);
        if (!magic(dv, 0, 'LINESLOD')) throw new Error(L.url + ': not a linesurf level-of-detail hierarchy (no LINESLOD magic)');
        if (dv.getUint32(8, true) !== 1) throw new Error(L.url + ': version ' + dv.getUint32(8, true) + ' (this page reads version 1)');
        const jsonBytes = dv.getUint32(12, true);
        self.idLo = dv.getUint32(16, true);
        self.idHi = dv.getUint32(20, true);
        self.idHex = hex8(self.idHi) + hex8(self.idLo);
        if (self.idHex !== L.hierarchy) throw new Error(L.url + ': the server now holds hierarchy ' + self.idHex + ', not ' + L.hierarchy);
        const count = Number(dv.getBigUint64(24, true));
        if (!(count >= 1)) throw new Error(L.url + ': no nodes');
        const end = 32 + jsonBytes + count * RECORD;
        const rest = await fetchRange(32, end);
        if (rest.byteLength !== end - 32) throw new Error(L.url + ': truncated header or node table');
        let header;
        try { header = JSON.parse(new TextDecoder().decode(new Uint8Array(rest, 0, jsonBytes))); } catch (e) { header = null; }
        if (!header || header.format !== 'linesurf-lod') throw new Error(L.url + ': invalid JSON header');
        const t = new DataView(rest, jsonBytes);
        const nodes = new Array(count), parent = new Int32Array(count).fill(-1), leaves = [];
        for (let i = 0; i < count; ++i) {
          const r = i * RECORD;
          if (t.getUint32(r, true) !== self.idLo || t.getUint32(r + 4, true) !== self.idHi)
            throw new Error(L.url + ': node ' + i + ': its table record belongs to another hierarchy');
          const f = (k) => t.getFloat32(r + k, true);
          const bmin = [f(48), f(52), f(56)], bmax = [f(60), f(64), f(68)];
          const n = {
            offset: Number(t.getBigUint64(r + 8, true)), size: Number(t.getBigUint64(r + 16, true)),
            points: t.getUint32(r + 72, true), segments: t.getUint32(r + 76, true),
            firstChild: t.getUint32(r + 80, true), childCount: t.getUint8(r + 84), leaf: t.getUint8(r + 86) !== 0,
            center: V.mul(V.add(bmin, bmax), 0.5), radius: 0.5 * V.len(V.sub(bmax, bmin)),
          };
          n.count = n.points + n.segments;
          if (n.leaf !== (n.childCount === 0) || (!n.leaf && (n.firstChild <= i || n.firstChild + n.childCount > count)))
            throw new Error(L.url + ': node ' + i + ': invalid tree links in the node table');
          nodes[i] = n;
          if (n.leaf) leaves.push(i);
          for (let c = n.firstChild; c < n.firstChild + n.childCount; ++c) parent[c] = i;
        }
        self.nodes = nodes;
        self.parent = parent;
        self.leaves = leaves;
        self.ready = true;
      }
      self.start = () => {
        loadHeader().then(() => drawSoon(true), (e) => fail(e && e.message ? e.message : String(e)));
      };

      // lod::selectNodes (src/lod/lod_read.cpp) for the page's camera: a cut refined coarse to
      // fine, largest projected node first, while the total stays within the budget.
      function select() {
        const nodes = self.nodes;
        if (self.budget >= total) return { nodes: self.leaves, primitives: total };
        const cam = state.camera, w = canvas.width, h = canvas.height;
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
          if (sum + cost > self.budget) continue;  // stays coarse; smaller nodes may still fit
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

      // A node's block checked (magic, hierarchy id, node number and counts; not its checksum,
      // see docs/decisions.md) and decoded as viewer_page.cpp prepares a model's primitives.
      function decodeNode(i, buf) {
        const n = self.nodes[i], dv = new DataView(buf);
        if (!magic(dv, 0, 'LSLODND1')) throw new Error('its block is not a node block (wrong magic)');
        if (dv.getUint32(8, true) !== self.idLo || dv.getUint32(12, true) !== self.idHi)
          throw new Error(`its block belongs to another hierarchy (${hex8(dv.getUint32(12, true))}${hex8(dv.getUint32(8, true))}, this one is ${self.idHex}); refused`);
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
        if (!meanRadius) meanRadius = meanRadiusOf(P, S);
        return makeBatch(P, np, S, ns);
      }

      function failNode(i, why) {
        self.failed.set(i, why);
        console.warn(`node ${i} failed: ${why}`);
      }

      // One Range request for a run of nodes whose blocks lie back to back in the file.
      async function load(run) {
        const nodes = self.nodes, first = nodes[run[0]], last = nodes[run[run.length - 1]];
        const start = first.offset, end = last.offset + last.size;
        ++self.inFlight;
        for (const i of run) self.loading.add(i);
        let buf = null, err = null;
        try { buf = await fetchRange(start, end); } catch (e) { err = e && e.message ? e.message : String(e); }
        for (const i of run) {
          self.loading.delete(i);
          const n = nodes[i], at = n.offset - start;
          if (err) { failNode(i, err); continue; }
          if (buf.byteLength < at + n.size) {
            failNode(i, `short read (${Math.max(0, buf.byteLength - at)} of its ${n.size} bytes)`);
            continue;
          }
          try {
            const b = decodeNode(i, buf.slice(at, at + n.size));
            self.cache.set(i, b);
            self.cachedBytes += b.bytes;
          } catch (e) {
            failNode(i, e && e.message ? e.message : String(e));
          }
        }
        --self.inFlight;
        pump();
        drawSoon(self.inFlight === 0);
      }
      function pump() {
        while (self.inFlight < MAX_IN_FLIGHT && self.queue.length) load(self.queue.shift());
      }
      // The missing nodes' blocks, those lying back to back in the file coalesced into one request
      // of at most MAX_REQUEST_BYTES; the requests coarse first (the table is breadth first, so
      // by their lowest node number), whatever order the writer put the blocks in.
      function request(missing) {
        const nodes = self.nodes;
        missing.sort((a, b) => nodes[a].offset - nodes[b].offset);
        const runs = [];
        let run = null, runStart = 0, runEnd = 0;
        for (const i of missing) {
          const n = nodes[i];
          if (run && n.offset === runEnd && n.offset + n.size - runStart <= MAX_REQUEST_BYTES) {
            run.push(i);
            runEnd = n.offset + n.size;
          } else {
            run = [i];
            runs.push(run);
            runStart = n.offset;
            runEnd = n.offset + n.size;
          }
        }
        const first = new Map(runs.map((r) => [r, r.reduce((m, i) => Math.min(m, i), Infinity)]));
        runs.sort((a, b) => first.get(a) - first.get(b));
        self.queue = runs;  // what this view needs: requests queued for an older view are dropped
        pump();
      }

      // Least recently drawn first, while over the limit; never a node of this frame.
      function evict(keep) {
        for (const [i, b] of self.cache) {
          if (self.cachedBytes <= self.cacheLimit) break;
          if (keep.has(i)) continue;
          self.cache.delete(i);
          self.cachedBytes -= b.bytes;
          deleteBatch(b);
        }
      }

      // The batches of this frame.
      self.frame = () => {
        if (!self.ready) return [];
        const sel = select();
        self.selection = sel;
        const list = [], drawnNodes = new Set(), missing = [];
        let complete = true;
        for (const i of sel.nodes) {
          if (self.failed.has(i)) continue;
          let k = i;
          if (!self.cache.has(i)) {
            complete = false;
            if (!self.loading.has(i)) missing.push(i);
            do k = self.parent[k]; while (k >= 0 && !self.cache.has(k));
            if (k < 0) continue;
          }
          if (drawnNodes.has(k)) continue;
          drawnNodes.add(k);
          const b = self.cache.get(k);
          self.cache.delete(k);  // most recently drawn: to the end
          self.cache.set(k, b);
          list.push(b);
        }
        self.complete = complete;
        self.drawnNodes = list.length;
        self.splats = list.reduce((a, b) => a + b.np + b.ns, 0);
        request(missing);
        evict(drawnNodes);
        return list;
      };

      // After a frame: the panel, the test attributes and the adaptive budget.
      self.drawn = (list, ms) => {
        const body = document.body;
        const mb = (x) => (x / 1e6).toFixed(x < 1e7 ? 2 : 1) + ' MB';
        body.setAttribute('data-splats', String(self.splats));
        body.setAttribute('data-nodes', String(self.drawnNodes));
        body.setAttribute('data-nodes-loading', String(self.loading.size));
        body.setAttribute('data-bytes-fetched', String(self.bytesFetched));
        body.setAttribute('data-file-bytes', String(L.bytes));
        body.setAttribute('data-budget', String(self.budget));
        body.setAttribute('data-failed-nodes', [...self.failed.keys()].join(','));
        if (self.firstAnyMs === undefined && self.splats > 0) self.firstAnyMs = performance.now();
        if (self.ready && self.complete && self.firstFrameMs === null) {
          self.firstFrameMs = performance.now();
          body.setAttribute('data-first-frame-ms', self.firstFrameMs.toFixed(1));
          // The served page tells `linesurf view` its first frame (the browser's clock, from the
          // page's start), which prints it: a measure a headless run can read.
          if (location.protocol.startsWith('http')) {
            const q = `first=${self.firstAnyMs.toFixed(0)}&complete=${self.firstFrameMs.toFixed(0)}` +
              `&splats=${self.splats}&nodes=${self.drawnNodes}&bytes=${self.bytesFetched}`;
            fetch('report?' + q, { cache: 'no-store' }).catch(() => {});
          }
        }
        body.setAttribute('data-state', self.ready && self.complete ? 'drawn' : 'loading');
        $('lodStatus').textContent = `${self.splats.toLocaleString('en')} splats in ${self.drawnNodes} nodes` +
          (self.nodes ? ` of ${self.nodes.length}` : '') + `, ${self.loading.size} loading; ` +
          `${mb(self.bytesFetched)} of ${mb(L.bytes)} fetched, ${mb(self.cachedBytes)} on the GPU`;
        const failed = [...self.failed.entries()];
        $('lodFailures').hidden = !failed.length;
        $('lodFailures').textContent = failed.slice(0, 8).map(([i, why]) => `node ${i} failed: ${why}`).join('\n') +
          (failed.length > 8 ? `\n(and ${failed.length - 8} more)` : '');
        adapt(ms);
      };
      // Adaptive budget: the frame time (smoothed) kept near the target by scaling the budget by
      // target / time when over by 25% (at most halving), and by 1.2 when under 70% of it while
      // the budget, not the model, limits the cut. Measured on complete cuts only (a frame of
      // half-loaded nodes says little), and at most every 250 ms so that a change is seen first.
      function adapt(ms) {
        if (!self.adaptive || !self.complete || !(ms > 0)) return;
        self.emaMs = self.emaMs ? 0.6 * self.emaMs + 0.4 * ms : ms;
        const now = performance.now();
        if (now - self.lastAdapt >= 250) {
          self.lastAdapt = now;
          let next = self.budget;
          if (self.emaMs > 1.25 * self.targetMs) next = Math.floor(self.budget * Math.max(0.5, self.targetMs / self.emaMs));
          else if (self.emaMs < 0.7 * self.targetMs && self.selection && self.selection.primitives >= 0.9 * self.budget &&
                   self.budget < total) next = Math.ceil(self.budget * 1.2);
          next = Math.min(Math.max(next, MIN_BUDGET), Math.max(total, MIN_BUDGET));
          if (next !== self.budget) { self.setBudget(next); self.emaMs = 0; describeCamera(); }
        }
        setTimeout(requestDraw, 250);  // keep measuring while adaptive
      }

      $('lodControls').hidden = false;
      $('lodStatus').hidden = false;
      $('targetMs').textContent = String(self.targetMs);
      $('adaptive').checked = self.adaptive;
      $('budget').addEventListener('change', () => { self.setBudget($('budget').value); describeCamera(); requestDraw(); });
      $('adaptive').addEventListener('input', () => {
        self.adaptive = $('adaptive').checked;
        self.emaMs = 0;
        params.adaptive = self.adaptive ? '1' : '0';
        requestDraw();
      });
      return self;
    }

    // ---- drawing -----------------------------------------------------------------------------
    const light = V.norm(D.light);
    let lastFrameMs = 0, counts = { points: 0, segments: 0 };

    // Front-facing primitives in front of the camera (the GPU culls the others in its vertex stage).
    function countDrawn() {
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

    function setCommon(p, f, w, h) {
      const u = p.u;
      // world -> camera in normalised model units: x_n = (x - centre) / radius
      const rot = [f.right, f.up, f.back];
      const eyeN = V.mul(V.sub(state.camera.eye, sphere.center), 1 / sphere.radius);
      const trans = rot.map((row) => -V.dot(row, eyeN));
      // mat3 is column-major: column j holds rot[.][j]
      gl.uniformMatrix3fv(u.uRot, false, [rot[0][0], rot[1][0], rot[2][0], rot[0][1], rot[1][1], rot[2][1],
                                          rot[0][2], rot[1][2], rot[2][2]]);
      gl.uniform3fv(u.uTrans, trans);
      gl.uniform2f(u.uHalf, 0.5 * w, 0.5 * h);
      gl.uniform1f(u.uFocal, 0.5 * h / Math.tan(0.5 * state.camera.fov * Math.PI / 180));
      gl.uniform1f(u.uNear, f.near / sphere.radius);
      gl.uniform1f(u.uFar, f.far / sphere.radius);
      gl.uniform1f(u.uCutoff, D.cutoffRadius);
      gl.uniform1f(u.uRecon, D.reconstructionScale);
      gl.uniform1f(u.uVh, D.prefilterVariance);
      gl.uniform1f(u.uRadScale, state.radiusScale);
      gl.uniform1f(u.uZThr, D.zThreshold);
      gl.uniform1i(u.uColorMode, state.colorMode);
      const sig = D.reconstructionScale * meanRadius * state.radiusScale;
      gl.uniform1f(u.uWeightNorm, sig * sig);
      gl.uniform1i(u.uLighting, state.lighting ? 1 : 0);
      gl.uniform3fv(u.uLight, light);
      gl.uniform4f(u.uMaterial, D.ambient, D.diffuse, D.specular, D.shininess);
    }

    // One pass over the batches: all their points, then all their segments.
    function drawSplats(pass, f, w, h, list) {
      if (pointProg && state.showPoints) {
        gl.useProgram(pointProg.prog);
        setCommon(pointProg, f, w, h);
        gl.uniform1i(pointProg.u.uPass, pass);
        gl.uniform3f(pointProg.u.uKindColor, 0.62, 0.64, 0.68);
        for (const b of list) {
          if (!b.np) continue;
          gl.bindVertexArray(b.pointVao);
          gl.drawElements(gl.TRIANGLES, 6 * b.np, gl.UNSIGNED_INT, 0);
        }
      }
      if (segProg && state.showSegments) {
        gl.useProgram(segProg.prog);
        setCommon(segProg, f, w, h);
        gl.uniform1i(segProg.u.uPass, pass);
        gl.uniform3f(segProg.u.uKindColor, 0.93, 0.55, 0.18);
        for (const b of list) {
          if (!b.ns) continue;
          gl.uniform1i(segProg.u.uEndpointNormals, b.endpointNormals ? 1 : 0);
          gl.bindVertexArray(b.segVao);
          gl.drawElements(gl.TRIANGLES, 6 * b.ns, gl.UNSIGNED_INT, 0);
        }
      }
    }

    // The three passes over `list`, a list of batches (makeBatch).
    function renderFrame(list) {
      const w = canvas.width, h = canvas.height;
      ensureTargets(w, h);
      const f = cameraFrame(state.camera, sphere);
      gl.bindFramebuffer(gl.FRAMEBUFFER, fbo);
      gl.viewport(0, 0, w, h);
      gl.disable(gl.CULL_FACE);
      gl.enable(gl.DEPTH_TEST);
      gl.clearColor(0, 0, 0, 0);
      gl.clearDepth(1);
      gl.depthMask(true);
      gl.colorMask(true, true, true, true);
      gl.clear(gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT);
      // 1. visibility
      gl.disable(gl.BLEND);
      gl.colorMask(false, false, false, false);
      gl.depthFunc(gl.LESS);
      drawSplats(0, f, w, h, list);
      // 2. accumulation
      gl.colorMask(true, true, true, true);
      gl.depthMask(false);
      gl.depthFunc(gl.LEQUAL);
      gl.enable(gl.BLEND);
      gl.blendEquation(gl.FUNC_ADD);
      gl.blendFunc(gl.ONE, gl.ONE);
      drawSplats(1, f, w, h, list);
      // 3. normalisation
      gl.disable(gl.BLEND);
      gl.disable(gl.DEPTH_TEST);
      gl.depthMask(true);
      gl.bindFramebuffer(gl.FRAMEBUFFER, null);
      gl.viewport(0, 0, w, h);
      gl.useProgram(resolveProg.prog);
      gl.activeTexture(gl.TEXTURE0);
      gl.bindTexture(gl.TEXTURE_2D, accumTex);
      gl.uniform1i(resolveProg.u.uAccum, 0);
      gl.uniform3fv(resolveProg.u.uBackground, D.background.slice(0, 3));
      gl.bindVertexArray(emptyVao);
      gl.drawArrays(gl.TRIANGLES, 0, 3);
      gl.bindVertexArray(null);
    }

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

    // Waits for the GPU: gl.finish() returns at once in Chrome; reading a pixel back does not.
    const pixel = new Uint8Array(4);
    function sync() { gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel); }

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
      counts = countDrawn();
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
      const n = Math.max(1, Math.min(1000, parseInt(params.bench, 10) || 10));
      if (params.size) {
        const m = /^(\d+)x(\d+)$/.exec(params.size);
        if (m) { canvas.width = +m[1]; canvas.height = +m[2]; if (state.autoFramed) state.camera = defaultCamera(+m[1], +m[2]); }
      }
      draw();
      const list = lodMode ? lod.frame() : batches;
      const times = [];
      for (let i = 0; i < n; ++i) {
        const t0 = performance.now();
        renderFrame(list);
        sync();
        times.push(performance.now() - t0);
      }
      times.sort((a, b) => a - b);
      const med = times[Math.floor(times.length / 2)];
      const out = document.createElement('pre');
      out.id = 'bench';
      out.textContent = `bench frames=${n} size=${canvas.width}x${canvas.height} median_ms=${med.toFixed(2)} ` +
        `min_ms=${times[0].toFixed(2)} max_ms=${times[times.length - 1].toFixed(2)} ` +
        `points=${list.reduce((a, b) => a + b.np, 0)} segments=${list.reduce((a, b) => a + b.ns, 0)} ` +
        `renderer=${(gpuName || gl.getParameter(gl.RENDERER)).replace(/\s+/g, '_')}`;
      document.body.appendChild(out);
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
})();
