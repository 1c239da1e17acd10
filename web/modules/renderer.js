// A frame of splats (Botsch, Hornung, Zwicker, Kobbelt 2005; the passes are listed in main.js):
// the float render targets, the uniforms of the camera and the options, the three passes.
import { V, cameraFrame } from './camera.js';

// Weights are 1/length^2 (§5.2.3.3); a constant factor keeps them near 1 in the float target
// (a hierarchy's: from the first node it loads, then kept).
export function meanRadiusOf(P, S) {
  let sum = 0, nr = 0;
  for (const arr of [P && P.radius, S && S.radius]) {
    if (!arr) continue;
    const step = Math.max(1, Math.floor(arr.data.length / 4096));
    for (let i = 0; i < arr.data.length; i += step) if (arr.data[i] > 0) { sum += arr.data[i]; ++nr; }
  }
  return nr ? sum / nr : 0;
}

// The renderer of the view: `view` holds the context (gl, canvas, floatBlend), the model and
// its bounding sphere, the page's defaults D, the state of the panel and the three programs.
export function createRenderer(view) {
  const { gl, canvas, state, sphere, D, floatBlend, model, pointProg, segProg, resolveProg } = view;
  const emptyVao = gl.createVertexArray();
  // the weight normalisation's mean splat radius: the model's, or a hierarchy's first node's
  const self = { meanRadius: model ? meanRadiusOf(model.points, model.segments) || 1 : 0 };

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

  const light = V.norm(D.light);

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
    const sig = D.reconstructionScale * self.meanRadius * state.radiusScale;
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

  // Waits for the GPU: gl.finish() returns at once in Chrome; reading a pixel back does not.
  const pixel = new Uint8Array(4);
  function sync() { gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, pixel); }

  self.renderFrame = renderFrame;
  self.sync = sync;
  return self;
}
