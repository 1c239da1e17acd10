// GLSL of the splats: the vertex stage sets up each splat's quad and kernel, the fragment stage
// evaluates the kernel and takes part in the three passes of a frame (see main.js).

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
export const POINT_VS = COMMON + `
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
export const SEGMENT_VS = COMMON + `
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

export const POINT_FS = FRAG_COMMON + `
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

export const SEGMENT_FS = FRAG_COMMON + `
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

export const RESOLVE_VS = `#version 300 es
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}
`;
export const RESOLVE_FS = `#version 300 es
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
