// Level-of-detail streaming (`linesurf view MODEL.lod`), the client of the hierarchy's server.
// The page reads the hierarchy from its server: the preamble, then the JSON header and the node
// table, then the blocks of the nodes each view needs (docs/file-format.md, "How the viewer
// reads a hierarchy over HTTP"). Every frame chooses its cut as lod::selectNodes does; a node
// not loaded yet is drawn through its nearest loaded ancestor, one that failed is left out (as
// `linesurf render` leaves it out) and named in the panel.
import { V } from './camera.js';
import { $, fail } from './dom.js';
import { RECORD, decodeNodeBlock, hex8, magic } from './lod_format.js';
import { selectNodes } from './lod_select.js';
import { meanRadiusOf } from './renderer.js';

// The hierarchy L (meta.lod) for the view of `ctx`: the fragment's params, the panel's state, the
// canvas, the bounding sphere, the shader constants, the renderer, its batches (makeBatch,
// deleteBatch) and the viewer's drawSoon, describeCamera and requestDraw.
export function createLod(L, ctx) {
  const { params, state, canvas, sphere, shaderConstants, renderer, makeBatch, deleteBatch } = ctx;
  const { drawSoon, describeCamera, requestDraw } = ctx;
  const total = L.points + L.segments;
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
    const version = dv.getUint32(8, true);
    if (version !== 1 && version !== 2) throw new Error(L.url + ': version ' + version + ' (this page reads versions 1 and 2)');
    const jsonBytes = dv.getUint32(12, true);
    self.idLo = dv.getUint32(16, true);
    self.idHi = dv.getUint32(20, true);
    self.idHex = hex8(self.idHi) + hex8(self.idLo);
    if (self.idHex !== L.hierarchy) throw new Error(L.url + ': the server now holds hierarchy ' + self.idHex + ', not ' + L.hierarchy);
    const count = Number(dv.getBigUint64(24, true));
    if (!(count >= 1)) throw new Error(L.url + ': no nodes');
    // Version 2 appends the table checksum (the server's reader checked it before serving).
    const end = 32 + jsonBytes + count * RECORD + (version >= 2 ? 8 : 0);
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

  function decodeNode(i, buf) {
    const { P, np, S, ns } = decodeNodeBlock(self, i, buf, L, sphere, shaderConstants);
    if (!renderer.meanRadius) renderer.meanRadius = meanRadiusOf(P, S);
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
    const sel = selectNodes(self, total, state.camera, canvas.width, canvas.height, sphere);
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
