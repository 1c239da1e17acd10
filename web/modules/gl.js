// The WebGL2 context the splats need (float render targets), and the programs compiled from
// shaders.js with the renderer's constants filled in.
import { fail } from './dom.js';

export function createContext(canvas) {
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
  return { gl: gl, floatBlend: floatBlend, gpuName: gpuName };
}

// Shader constants that must equal the C++ renderer's (meta.constants, from viewer_page.cpp).
function withConstants(src, shaderConstants) {
  return src.replace(/@MAX_STRETCH@/g, glslFloat(shaderConstants.maxStretch))
            .replace(/@MIN_FACING@/g, glslFloat(shaderConstants.minFacing));
}
function glslFloat(x) {
  if (!Number.isFinite(x)) throw new Error('the page lacks a shader constant');
  const s = String(x);
  return /[.eE]/.test(s) ? s : s + '.0';
}

export function compile(gl, vs, fs, name, shaderConstants) {
  vs = withConstants(vs, shaderConstants);
  fs = withConstants(fs, shaderConstants);
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
