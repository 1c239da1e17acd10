// Benchmark (#bench=N in the URL fragment, #size=WxH optional): N frames, each one finished
// on the GPU, and their median time, written into the page as <pre id="bench">.

// `ctx`: the fragment's params, the canvas, the state, the viewer's defaultCamera and draw,
// frame() giving the batches of a frame, the renderer, the GPU's name and the context.
export function runBench(ctx) {
  const { params, canvas, state, defaultCamera, draw, frame, renderer, gpuName, gl } = ctx;
  const { renderFrame, sync } = renderer;
  const n = Math.max(1, Math.min(1000, parseInt(params.bench, 10) || 10));
  if (params.size) {
    const m = /^(\d+)x(\d+)$/.exec(params.size);
    if (m) { canvas.width = +m[1]; canvas.height = +m[2]; if (state.autoFramed) state.camera = defaultCamera(+m[1], +m[2]); }
  }
  draw();
  const list = frame();
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
}
