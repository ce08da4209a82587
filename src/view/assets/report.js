// The interactive toolpath view of an ngcflat report page. Plain script, no
// library: the scene's arrays are decoded from the page's inline data and
// drawn on a 2-D canvas with an orthographic camera.
(function () {
  'use strict';
  const D = JSON.parse(document.getElementById('ngcflat-data').textContent);
  const S = D.scene;
  const $ = (id) => document.getElementById(id);

  function bytes(b64) {
    const bin = atob(b64);
    const u = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) u[i] = bin.charCodeAt(i);
    return u.buffer;
  }
  const V = new Float32Array(bytes(S.vertices));
  const mStart = new Uint32Array(bytes(S.start));
  const mEnd = new Uint32Array(bytes(S.end));
  const mKind = new Uint8Array(bytes(S.kind));
  const mTool = new Uint16Array(bytes(S.tool));
  const mFeed = new Float32Array(bytes(S.feed));
  const mT0 = new Float64Array(bytes(S.t0));
  const mDur = new Float32Array(bytes(S.dur));
  const mLine = new Uint32Array(bytes(S.line));
  const mLines = new Uint32Array(bytes(S.lines));
  const mSeq = new Uint32Array(bytes(S.seq));
  const mCount = new Uint32Array(bytes(S.count));
  const mFile = new Uint32Array(bytes(S.file));
  const mSrc = new Uint32Array(bytes(S.src_line));
  const mChain = new Uint32Array(bytes(S.chain));
  const mViol = new Uint32Array(bytes(S.viol));
  const N = mStart.length;
  const NV = V.length / 3;
  const texts = new Map(S.texts);
  const KIND = ['rapid', 'feed', 'probe', 'spindle-synchronised'];

  // Per-move Z range, for the depth slider.
  const mZlo = new Float32Array(N);
  const mZhi = new Float32Array(N);
  for (let k = 0; k < N; k++) {
    let lo = Infinity, hi = -Infinity;
    for (let v = mStart[k]; v <= mEnd[k]; v++) {
      const z = V[3 * v + 2];
      if (z < lo) lo = z;
      if (z > hi) hi = z;
    }
    mZlo[k] = lo;
    mZhi[k] = hi;
  }

  // Bounds of what is drawn (the envelope when known).
  const bmin = [Infinity, Infinity, Infinity];
  const bmax = [-Infinity, -Infinity, -Infinity];
  if (D.envelope) {
    for (let i = 0; i < 3; i++) { bmin[i] = D.envelope[0][i]; bmax[i] = D.envelope[1][i]; }
  } else {
    for (let v = 0; v < NV; v++) {
      for (let i = 0; i < 3; i++) {
        const x = V[3 * v + i];
        if (x < bmin[i]) bmin[i] = x;
        if (x > bmax[i]) bmax[i] = x;
      }
    }
  }
  if (!isFinite(bmin[0])) { bmin.fill(0); bmax.fill(0); }
  const zLow = bmin[2], zHigh = bmax[2];

  // ---- formatting
  function hms(s) {
    if (!isFinite(s)) return '–';
    const neg = s < 0; s = Math.abs(s);
    const h = Math.floor(s / 3600), m = Math.floor((s % 3600) / 60);
    const sec = (s % 60).toFixed(1).padStart(4, '0');
    return (neg ? '-' : '') + h + ':' + String(m).padStart(2, '0') + ':' + sec;
  }
  const num = (x) => (Math.round(x * 1000) / 1000).toString();
  function esc(s) {
    return String(s).replace(/[&<>"]/g, (c) => ({ '&': '&amp;', '<': '&lt;', '>': '&gt;', '"': '&quot;' }[c]));
  }
  const fileName = (i) => (i < S.files.length ? S.files[i] : '?');

  // ---- state
  const st = {
    colour: 'tool',
    rapids: true,
    limits: true,
    envelope: true,
    toolOn: S.tools.map(() => true),
    zlo: zLow,
    zhi: zHigh,
    time: Infinity, // everything done
    selected: [],
    hover: -1,
    playing: false,
  };
  const timed = S.total_time > 0;
  const endTime = timed ? S.total_time : N;

  // ---- colours
  const TOOL_COLOURS = ['#1f5fbf', '#2a9d3a', '#b8860b', '#8e3bb5', '#008b8b', '#c2185b', '#5d4037', '#33691e', '#283593', '#e65100'];
  const toolColour = (i) => TOOL_COLOURS[i % TOOL_COLOURS.length];
  function ramp(t) {
    // blue → cyan → green → yellow → red
    t = Math.min(1, Math.max(0, t));
    const stops = [[40, 70, 200], [0, 170, 200], [40, 170, 40], [220, 180, 0], [210, 30, 30]];
    const x = t * (stops.length - 1);
    const i = Math.min(stops.length - 2, Math.floor(x));
    const f = x - i;
    const c = stops[i].map((a, j) => Math.round(a + (stops[i + 1][j] - a) * f));
    return 'rgb(' + c.join(',') + ')';
  }
  const RAMP_STEPS = 16;
  let feedLo = Infinity, feedHi = -Infinity;
  for (let k = 0; k < N; k++) {
    const f = mFeed[k];
    if (isFinite(f) && (mKind[k] & 3) !== 0) {
      if (f < feedLo) feedLo = f;
      if (f > feedHi) feedHi = f;
    }
  }
  const toolUsed = S.tools.map(() => false);
  for (let k = 0; k < N; k++) toolUsed[mTool[k]] = true;
  // Colour bucket of every move for the current colouring.
  const bucket = new Uint16Array(N);
  let bucketColours = [];
  function recolour() {
    if (st.colour === 'tool') {
      bucketColours = S.tools.map((_, i) => toolColour(i));
      for (let k = 0; k < N; k++) bucket[k] = mTool[k];
    } else {
      bucketColours = [];
      for (let i = 0; i < RAMP_STEPS; i++) bucketColours.push(ramp(i / (RAMP_STEPS - 1)));
      for (let k = 0; k < N; k++) {
        let t;
        if (st.colour === 'feed') {
          t = feedHi > feedLo ? (mFeed[k] - feedLo) / (feedHi - feedLo) : 0.5;
        } else {
          const z = 0.5 * (mZlo[k] + mZhi[k]);
          t = zHigh > zLow ? (z - zLow) / (zHigh - zLow) : 0.5;
        }
        bucket[k] = isFinite(t) ? Math.round(t * (RAMP_STEPS - 1)) : 0;
      }
    }
    legend();
  }
  function legend() {
    let h = '<span class="sw" style="border-top:2px dashed #e0702a;height:0"></span>rapid' +
      '<span class="sw" style="border-top:2px dotted #8e24aa;height:0"></span>probe';
    if (st.colour === 'tool') {
      S.tools.forEach((t, i) => { if (toolUsed[i]) h += '<span class="sw" style="background:' + toolColour(i) + '"></span>T' + t; });
    } else {
      const [lo, hi, unit] = st.colour === 'feed' ? [feedLo, feedHi, ' mm/min'] : [zLow, zHigh, ' mm'];
      h += '<span class="sw" style="background:linear-gradient(90deg,' + ramp(0) + ',' + ramp(0.5) + ',' + ramp(1) + ');width:6em"></span>' +
        (isFinite(lo) ? esc(num(lo)) + ' … ' + esc(num(hi)) + unit : 'none');
    }
    $('legend').innerHTML = h;
  }

  // ---- visibility
  function visible(k) {
    const kind = mKind[k] & 3;
    if (kind === 0 && !st.rapids) return false;
    if (!st.toolOn[mTool[k]]) return false;
    if (mZhi[k] < st.zlo || mZlo[k] > st.zhi) return false;
    return true;
  }
  // Moves started by the timeline's time.
  function doneCount() {
    if (st.time >= endTime) return N;
    if (!timed) return Math.max(0, Math.min(N, Math.floor(st.time)));
    // First move starting after the time.
    let lo = 0, hi = N;
    while (lo < hi) {
      const mid = (lo + hi) >> 1;
      if (mT0[mid] <= st.time) lo = mid + 1; else hi = mid;
    }
    return lo;
  }

  // ---- camera (orthographic)
  const cam = { yaw: 0, pitch: Math.PI / 2, scale: 1, target: [0, 0, 0] };
  const canvas = $('view');
  const ctx = canvas.getContext('2d');
  let W = 1, H = 1, dpr = 1;
  function basis() {
    const cy = Math.cos(cam.yaw), sy = Math.sin(cam.yaw);
    const cp = Math.cos(cam.pitch), sp = Math.sin(cam.pitch);
    const e = [sy * cp, -cy * cp, sp];
    const r = [cy, sy, 0];
    const u = [e[1] * r[2] - e[2] * r[1], e[2] * r[0] - e[0] * r[2], e[0] * r[1] - e[1] * r[0]];
    return { r, u, e };
  }
  const SX = new Float32Array(NV);
  const SY = new Float32Array(NV);
  function project() {
    const { r, u } = basis();
    const t = cam.target, s = cam.scale, cx = W / 2, cy = H / 2;
    for (let v = 0; v < NV; v++) {
      const x = V[3 * v] - t[0], y = V[3 * v + 1] - t[1], z = V[3 * v + 2] - t[2];
      SX[v] = cx + (x * r[0] + y * r[1] + z * r[2]) * s;
      SY[v] = cy - (x * u[0] + y * u[1] + z * u[2]) * s;
    }
  }
  function toScreen(p) {
    const { r, u } = basis();
    const t = cam.target;
    const x = p[0] - t[0], y = p[1] - t[1], z = p[2] - t[2];
    return [W / 2 + (x * r[0] + y * r[1] + z * r[2]) * cam.scale, H / 2 - (x * u[0] + y * u[1] + z * u[2]) * cam.scale];
  }
  function fit(lo, hi) {
    lo = lo || bmin; hi = hi || bmax;
    cam.target = [0, 1, 2].map((i) => (lo[i] + hi[i]) / 2);
    const { r, u } = basis();
    let w = 0, h = 0;
    for (let c = 0; c < 8; c++) {
      const p = [0, 1, 2].map((i) => ((c >> i) & 1 ? hi[i] : lo[i]) - cam.target[i]);
      w = Math.max(w, Math.abs(p[0] * r[0] + p[1] * r[1] + p[2] * r[2]));
      h = Math.max(h, Math.abs(p[0] * u[0] + p[1] * u[1] + p[2] * u[2]));
    }
    cam.scale = Math.min((W * 0.45) / Math.max(w, 1e-3), (H * 0.42) / Math.max(h, 1e-3));
    if (!isFinite(cam.scale) || cam.scale <= 0) cam.scale = 1;
  }
  const VIEWS = {
    top: [0, Math.PI / 2],
    front: [0, 0],
    side: [Math.PI / 2, 0],
    iso: [Math.PI / 4, Math.atan(1 / Math.SQRT2)],
  };
  function setView(name) {
    if (name !== 'fit') { cam.yaw = VIEWS[name][0]; cam.pitch = VIEWS[name][1]; }
    fit();
    draw();
  }

  // ---- drawing
  function box(lo, hi, colour, dash) {
    const c = [];
    for (let i = 0; i < 8; i++) c.push(toScreen([i & 1 ? hi[0] : lo[0], i & 2 ? hi[1] : lo[1], i & 4 ? hi[2] : lo[2]]));
    ctx.strokeStyle = colour;
    ctx.setLineDash(dash);
    ctx.beginPath();
    for (const [a, b] of [[0, 1], [2, 3], [4, 5], [6, 7], [0, 2], [1, 3], [4, 6], [5, 7], [0, 4], [1, 5], [2, 6], [3, 7]]) {
      ctx.moveTo(c[a][0], c[a][1]);
      ctx.lineTo(c[b][0], c[b][1]);
    }
    ctx.stroke();
    ctx.setLineDash([]);
  }
  function limitBox() {
    if (!D.limits.length) return null;
    const lo = bmin.slice(), hi = bmax.slice();
    let any = false;
    for (const l of D.limits) {
      if (l.min != null) { lo[l.axis] = l.min; any = true; }
      if (l.max != null) { hi[l.axis] = l.max; any = true; }
    }
    return any ? [lo, hi] : null;
  }
  function axes() {
    const o = toScreen([0, 0, 0]);
    const len = 40 / cam.scale;
    const cols = ['#d32f2f', '#388e3c', '#1565c0'];
    for (let i = 0; i < 3; i++) {
      const p = [0, 0, 0]; p[i] = len;
      const q = toScreen(p);
      ctx.strokeStyle = cols[i];
      ctx.lineWidth = 2;
      ctx.beginPath(); ctx.moveTo(o[0], o[1]); ctx.lineTo(q[0], q[1]); ctx.stroke();
      ctx.fillStyle = cols[i];
      ctx.fillText('XYZ'[i], q[0] + 3, q[1] - 3);
    }
    ctx.lineWidth = 1;
  }
  // The tool's position at the timeline's time.
  function toolAt() {
    if (st.time >= endTime || N === 0) return null;
    const done = doneCount();
    const k = Math.max(0, done - 1);
    let f = 1;
    if (timed && mDur[k] > 0) f = Math.min(1, Math.max(0, (st.time - mT0[k]) / mDur[k]));
    const a = mStart[k], b = mEnd[k];
    const x = a + (b - a) * f;
    const i = Math.min(b, Math.floor(x)), j = Math.min(b, i + 1), g = x - i;
    const p = [0, 1, 2].map((c) => V[3 * i + c] + (V[3 * j + c] - V[3 * i + c]) * g);
    return { k, p, f, seg: i, g };
  }
  let frame = 0;
  function draw() {
    frame = 0;
    ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
    ctx.clearRect(0, 0, W, H);
    ctx.font = '12px sans-serif';
    project();
    if (st.envelope && isFinite(bmin[0])) box(bmin, bmax, 'rgba(90,90,90,0.55)', [4, 3]);
    const lb = limitBox();
    if (st.limits && lb) box(lb[0], lb[1], 'rgba(200,0,0,0.6)', []);
    axes();
    const done = doneCount();
    const at = toolAt();
    const feedPaths = bucketColours.map(() => new Path2D());
    const rapid = new Path2D();
    const probe = new Path2D();
    let shown = 0;
    for (let k = 0; k < done; k++) {
      if (!visible(k)) continue;
      shown++;
      const kind = mKind[k] & 3;
      const p = kind === 0 ? rapid : kind === 2 ? probe : feedPaths[bucket[k]];
      const a = mStart[k];
      let b = mEnd[k];
      const partial = at && k === at.k;
      if (partial) b = at.seg;
      p.moveTo(SX[a], SY[a]);
      for (let v = a + 1; v <= b; v++) p.lineTo(SX[v], SY[v]);
      if (partial) {
        const q = toScreen(at.p);
        p.lineTo(q[0], q[1]);
      }
    }
    ctx.lineWidth = 1.2;
    ctx.lineJoin = 'round';
    feedPaths.forEach((p, i) => { ctx.strokeStyle = bucketColours[i]; ctx.stroke(p); });
    ctx.strokeStyle = '#8e24aa';
    ctx.lineWidth = 2;
    ctx.setLineDash([2, 3]);
    ctx.stroke(probe);
    ctx.lineWidth = 1;
    ctx.strokeStyle = 'rgba(224,112,42,0.85)';
    ctx.setLineDash([5, 4]);
    ctx.stroke(rapid);
    ctx.setLineDash([]);
    // Selected and hovered moves on top.
    const hi = (k, colour, width) => {
      const p = new Path2D();
      p.moveTo(SX[mStart[k]], SY[mStart[k]]);
      for (let v = mStart[k] + 1; v <= mEnd[k]; v++) p.lineTo(SX[v], SY[v]);
      ctx.strokeStyle = colour;
      ctx.lineWidth = width;
      ctx.stroke(p);
    };
    for (const k of st.selected) hi(k, 'rgba(255,200,0,0.9)', 5);
    for (const k of st.selected) hi(k, '#000', 1.5);
    if (st.hover >= 0) hi(st.hover, 'rgba(0,0,0,0.6)', 3);
    if (at) {
      const q = toScreen(at.p);
      ctx.fillStyle = 'rgba(220,0,0,0.85)';
      ctx.beginPath(); ctx.arc(q[0], q[1], 5, 0, 2 * Math.PI); ctx.fill();
    }
    st.shown = shown;
    $('visible').textContent = shown + ' of ' + N + ' moves shown' + (done < N ? ' (' + done + ' reached by the timeline)' : '') + '.';
  }
  function redraw() { if (!frame) frame = requestAnimationFrame(draw); }

  function resize() {
    const rect = canvas.getBoundingClientRect();
    dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, rect.width), h = Math.max(1, rect.height);
    const first = W === 1;
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
    W = w; H = h;
    if (first) setView(bmax[1] - bmin[1] < 1e-9 && bmax[0] - bmin[0] > 0 ? 'front' : 'iso'); else draw();
  }

  // ---- picking
  function segDist(px, py, ax, ay, bx, by) {
    const dx = bx - ax, dy = by - ay;
    const l2 = dx * dx + dy * dy;
    let t = l2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / l2 : 0;
    t = Math.max(0, Math.min(1, t));
    const x = ax + t * dx - px, y = ay + t * dy - py;
    return x * x + y * y;
  }
  function pick(px, py) {
    const done = doneCount();
    let best = -1, bd = 64; // 8 px
    for (let k = 0; k < done; k++) {
      if (!visible(k)) continue;
      for (let v = mStart[k]; v < mEnd[k]; v++) {
        const d = segDist(px, py, SX[v], SY[v], SX[v + 1], SY[v + 1]);
        if (d <= bd) { bd = d; best = k; }
      }
      if (mStart[k] === mEnd[k]) {
        const d = segDist(px, py, SX[mStart[k]], SY[mStart[k]], SX[mStart[k]], SY[mStart[k]]);
        if (d <= bd) { bd = d; best = k; }
      }
    }
    return best;
  }

  // ---- the move's story
  function chainText(k) {
    const c = mChain[k];
    if (c === 0xffffffff) return 'not recorded (too many distinct call chains)';
    const ch = S.chains[c] || [];
    if (!ch.length) return '';
    return ch.map(([f, l]) => fileName(f) + ':' + l).join(' ← ');
  }
  function lineText(k) {
    // The text is kept once per output line.
    return texts.get(mLine[k]);
  }
  function point(v) { return '(' + [0, 1, 2].map((i) => num(V[3 * v + i])).join(', ') + ')'; }
  function story(k) {
    const kind = mKind[k] & 3;
    const rows = [];
    const row = (a, b) => rows.push('<dt>' + a + '</dt><dd>' + b + '</dd>');
    const what = KIND[kind] + ((mKind[k] & 4) ? ' (arc)' : '');
    row('move', (mSeq[k] + 1) + ' of ' + S.detail.program_moves + ', ' + what +
      (mCount[k] > 1 ? '; drawn as one with the next ' + (mCount[k] - 1) + ' moves' : ''));
    const t = lineText(k);
    row('output line', mLine[k] + (mLines[k] ? '–' + (mLine[k] + mLines[k]) : '') +
      (t !== undefined ? ': <code id="out-text">' + esc(t) + '</code>' : ''));
    row('source', '<span id="src-loc">' + esc(fileName(mFile[k]) + ':' + mSrc[k]) + '</span>');
    const ch = chainText(k);
    row('called from', ch ? '<span id="src-chain">' + esc(ch) + '</span>' : '<span class="none">the main program</span>');
    row('tool', 'T' + S.tools[mTool[k]]);
    if (kind !== 0) row('feed', isFinite(mFeed[k]) ? num(mFeed[k]) : '–');
    row('time', (mKind[k] & 8) ? 'not timed (' + esc(kind === 0 ? 'start not known, or no maximum velocity given' : 'no feed rate') + '), starts at ' + hms(mT0[k]) :
      'starts at ' + hms(mT0[k]) + ', takes ' + (mDur[k] < 60 ? mDur[k].toFixed(2) + ' s' : hms(mDur[k])));
    row('from', point(mStart[k]));
    row('to', point(mEnd[k]));
    if (mViol[k]) row('<span class="warn">limit</span>', '<span class="warn">' + esc(S.violations[mViol[k] - 1].message) + '</span>');
    return '<dl>' + rows.join('') + '</dl>';
  }
  function select(ks, zoom) {
    st.selected = ks;
    const info = $('info');
    if (!ks.length) {
      info.innerHTML = '<p class="hint">Nothing selected.</p>';
    } else {
      info.innerHTML = (ks.length > 1 ? '<p>' + ks.length + ' moves selected; the first:</p>' : '') + story(ks[0]);
    }
    if (zoom && ks.length) {
      const lo = [Infinity, Infinity, Infinity], hi = [-Infinity, -Infinity, -Infinity];
      for (const k of ks) for (let v = mStart[k]; v <= mEnd[k]; v++) for (let i = 0; i < 3; i++) {
        lo[i] = Math.min(lo[i], V[3 * v + i]); hi[i] = Math.max(hi[i], V[3 * v + i]);
      }
      const pad = Math.max(1, 0.1 * Math.max(hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]));
      fit(lo.map((x) => x - pad), hi.map((x) => x + pad));
    }
    draw();
  }

  // ---- pointer input: drag turns, right/shift/two-finger drag pans, wheel/pinch zooms
  const pointers = new Map();
  let drag = null;
  canvas.addEventListener('contextmenu', (e) => e.preventDefault());
  canvas.addEventListener('pointerdown', (e) => {
    canvas.setPointerCapture(e.pointerId);
    pointers.set(e.pointerId, [e.offsetX, e.offsetY]);
    drag = { x: e.offsetX, y: e.offsetY, moved: 0, pan: e.button === 2 || e.button === 1 || e.shiftKey, pinch: null };
    if (pointers.size === 2) drag.pinch = pinchState();
    canvas.style.cursor = 'grabbing';
  });
  function pinchState() {
    const [a, b] = [...pointers.values()];
    return { d: Math.hypot(a[0] - b[0], a[1] - b[1]), m: [(a[0] + b[0]) / 2, (a[1] + b[1]) / 2] };
  }
  function pan(dx, dy) {
    const { r, u } = basis();
    for (let i = 0; i < 3; i++) cam.target[i] -= (dx * r[i] - dy * u[i]) / cam.scale;
  }
  function zoomAt(x, y, f) {
    const { r, u } = basis();
    const ox = (x - W / 2) / cam.scale, oy = (H / 2 - y) / cam.scale;
    const q = [0, 1, 2].map((i) => cam.target[i] + ox * r[i] + oy * u[i]);
    cam.scale *= f;
    const nx = (x - W / 2) / cam.scale, ny = (H / 2 - y) / cam.scale;
    cam.target = [0, 1, 2].map((i) => q[i] - nx * r[i] - ny * u[i]);
  }
  canvas.addEventListener('pointermove', (e) => {
    if (!drag) { hoverAt(e.offsetX, e.offsetY); return; }
    if (!pointers.has(e.pointerId)) return;
    pointers.set(e.pointerId, [e.offsetX, e.offsetY]);
    if (pointers.size >= 2 && drag.pinch) {
      const p = pinchState();
      zoomAt(p.m[0], p.m[1], p.d / Math.max(1, drag.pinch.d));
      pan(p.m[0] - drag.pinch.m[0], p.m[1] - drag.pinch.m[1]);
      drag.pinch = p;
      drag.moved += 10;
      redraw();
      return;
    }
    const dx = e.offsetX - drag.x, dy = e.offsetY - drag.y;
    drag.x = e.offsetX; drag.y = e.offsetY;
    drag.moved += Math.abs(dx) + Math.abs(dy);
    if (drag.moved < 4) return;
    if (drag.pan) pan(dx, dy);
    else {
      cam.yaw -= dx * 0.008;
      cam.pitch = Math.max(-Math.PI / 2, Math.min(Math.PI / 2, cam.pitch + dy * 0.008));
    }
    redraw();
  });
  function endPointer(e) {
    pointers.delete(e.pointerId);
    if (!drag) return;
    if (pointers.size === 0) {
      if (drag.moved < 4 && e.type === 'pointerup') {
        const k = pick(e.offsetX, e.offsetY);
        select(k >= 0 ? [k] : [], false);
      }
      drag = null;
      canvas.style.cursor = 'grab';
    } else {
      drag.pinch = null;
    }
  }
  canvas.addEventListener('pointerup', endPointer);
  canvas.addEventListener('pointercancel', endPointer);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    zoomAt(e.offsetX, e.offsetY, Math.exp(-e.deltaY * 0.0015));
    redraw();
  }, { passive: false });
  const hoverBox = $('hover');
  function hoverAt(x, y) {
    const k = pick(x, y);
    if (k === st.hover) return;
    st.hover = k;
    if (k >= 0) {
      const t = lineText(k);
      hoverBox.textContent = 'line ' + mLine[k] + (t !== undefined ? ': ' + t : '') + '\n' +
        fileName(mFile[k]) + ':' + mSrc[k] + (chainText(k) ? ' ← ' + chainText(k) : '');
      hoverBox.style.left = Math.min(x + 14, W - 200) + 'px';
      hoverBox.style.top = (y + 14) + 'px';
      hoverBox.hidden = false;
    } else hoverBox.hidden = true;
    redraw();
  }
  canvas.addEventListener('pointerleave', () => { hoverBox.hidden = true; if (st.hover >= 0) { st.hover = -1; redraw(); } });
  canvas.addEventListener('keydown', (e) => {
    const step = 40;
    const keys = { ArrowLeft: () => pan(step, 0), ArrowRight: () => pan(-step, 0), ArrowUp: () => pan(0, step), ArrowDown: () => pan(0, -step),
      '+': () => zoomAt(W / 2, H / 2, 1.25), '-': () => zoomAt(W / 2, H / 2, 0.8) };
    if (keys[e.key]) { keys[e.key](); e.preventDefault(); redraw(); }
  });

  // ---- controls
  document.querySelectorAll('#viewbar button').forEach((b) => b.addEventListener('click', () => setView(b.dataset.view)));
  $('colour').addEventListener('change', (e) => { st.colour = e.target.value; recolour(); draw(); });
  $('show-rapids').addEventListener('change', (e) => { st.rapids = e.target.checked; draw(); });
  $('show-limits').addEventListener('change', (e) => { st.limits = e.target.checked; draw(); });
  $('show-envelope').addEventListener('change', (e) => { st.envelope = e.target.checked; draw(); });
  {
    const box = $('tools');
    S.tools.forEach((t, i) => {
      if (!toolUsed[i]) return;
      const l = document.createElement('label');
      l.innerHTML = '<input type="checkbox" checked data-tool="' + i + '"><span class="sw" style="background:' + toolColour(i) + '"></span>T' + esc(t);
      l.firstChild.addEventListener('change', (e) => { st.toolOn[i] = e.target.checked; draw(); });
      box.appendChild(l);
    });
  }
  const zAt = (v) => zLow + (zHigh - zLow) * (v / 1000);
  function zInput() {
    let lo = +$('zlo').value, hi = +$('zhi').value;
    if (lo > hi) { if (this === $('zlo')) $('zhi').value = hi = lo; else $('zlo').value = lo = hi; }
    st.zlo = lo === 0 ? -Infinity : zAt(lo);
    st.zhi = hi === 1000 ? Infinity : zAt(hi);
    $('zlo-val').textContent = num(zAt(lo));
    $('zhi-val').textContent = num(zAt(hi));
    redraw();
  }
  $('zlo').addEventListener('input', zInput);
  $('zhi').addEventListener('input', zInput);
  st.zlo = -Infinity; st.zhi = Infinity;
  $('zlo-val').textContent = num(zLow);
  $('zhi-val').textContent = num(zHigh);

  // ---- timeline
  const slider = $('time');
  function showTime() {
    const t = Math.min(st.time, endTime);
    if (timed) {
      $('elapsed').textContent = hms(t);
      $('remaining').textContent = hms(endTime - t);
    } else {
      $('elapsed').textContent = 'move ' + Math.floor(t);
      $('remaining').textContent = (N - Math.floor(t)) + ' moves';
    }
    const done = doneCount();
    const k = Math.max(0, done - 1);
    const cur = $('current');
    if (N === 0) { cur.textContent = 'No moves.'; return; }
    const txt = lineText(k);
    cur.innerHTML = (done >= N && st.time >= endTime ? 'Last move: ' : 'Executing: ') + 'output line ' + mLine[k] +
      (txt !== undefined ? ' <code>' + esc(txt) + '</code>' : '') + ' from ' + esc(fileName(mFile[k]) + ':' + mSrc[k]) +
      (chainText(k) ? ' ← ' + esc(chainText(k)) : '');
  }
  slider.addEventListener('input', () => {
    st.time = (+slider.value / +slider.max) * endTime;
    if (+slider.value === +slider.max) st.time = Infinity;
    showTime();
    redraw();
  });
  let last = 0;
  function tick(ts) {
    if (!st.playing) return;
    const dt = last ? (ts - last) / 1000 : 0;
    last = ts;
    const speed = timed ? +$('speed').value : Math.max(1, N / 20);
    st.time = Math.min(endTime, st.time + dt * speed);
    slider.value = Math.round((st.time / endTime) * +slider.max);
    if (st.time >= endTime) { st.time = Infinity; stop(); }
    showTime();
    draw();
    if (st.playing) requestAnimationFrame(tick);
  }
  function stop() { st.playing = false; $('play').textContent = '▶'; }
  $('play').addEventListener('click', () => {
    if (st.playing) { stop(); return; }
    if (st.time >= endTime) st.time = 0;
    st.playing = true; last = 0;
    $('play').textContent = '❚❚';
    requestAnimationFrame(tick);
  });

  // ---- lists: violations, warnings, level of detail
  function link(text, ks) {
    const li = document.createElement('li');
    if (ks.length) {
      const a = document.createElement('a');
      a.textContent = text;
      a.tabIndex = 0;
      a.addEventListener('click', () => select(ks, true));
      li.appendChild(a);
      if (ks.length > 1) li.appendChild(document.createTextNode(' (' + ks.length + ' moves)'));
    } else {
      li.textContent = text;
    }
    return li;
  }
  {
    const ul = $('violations');
    const byViol = new Map();
    for (let k = 0; k < N; k++) if (mViol[k]) byViol.set(mViol[k], k);
    S.violations.forEach((v, i) => ul.appendChild(link('output line ' + v.line + ': ' + v.message, byViol.has(i + 1) ? [byViol.get(i + 1)] : [])));
    if (S.detail.violations_not_listed) ul.appendChild(link('and ' + S.detail.violations_not_listed + ' more moves outside the limits (not listed)', []));
    if (!ul.children.length) {
      const li = document.createElement('li');
      li.className = 'none';
      li.textContent = !D.limits.length ? 'No travel limits were given (--limits, --ini, --grbl-settings).'
        : S.detail.limits_unchecked ? S.detail.limits_unchecked + ' moves could not be checked: the machine position is not known (--zero-start, --var-file or -D).'
          : 'None: every move stays inside the limits.';
      ul.appendChild(li);
    } else if (S.detail.limits_unchecked) {
      ul.appendChild(link(S.detail.limits_unchecked + ' moves could not be checked: the machine position is not known.', []));
    }
    const wl = $('warnings');
    for (const w of D.warnings) {
      const ks = [];
      if (w.file != null) {
        for (let k = 0; k < N; k++) {
          if ((fileName(mFile[k]) === w.file && mSrc[k] === w.line) ||
            (S.chains[mChain[k]] || []).some(([f, l]) => fileName(f) === w.file && l === w.line)) ks.push(k);
        }
      }
      const where = w.file != null ? w.file + ':' + w.line + ': ' : '';
      wl.appendChild(link(where + w.code + ' ' + w.message + (w.file != null && !ks.length ? ' (no move drawn from it)' : ''), ks));
    }
    if (!D.warnings.length) {
      const li = document.createElement('li');
      li.className = 'none';
      li.textContent = 'None.';
      wl.appendChild(li);
    }
  }
  {
    const d = S.detail;
    const parts = [];
    if (d.merged_moves) parts.push(d.merged_moves + ' moves are drawn merged with their neighbours (same kind and tool, shared points left out)');
    if (d.left_out_moves) parts.push(d.left_out_moves + ' moves are left out');
    if (d.left_out_points) parts.push(d.left_out_points + ' points inside arcs and merged moves are left out');
    if (d.unknown_moves) parts.push(d.unknown_moves + ' moves from or to a position that is not known are not drawn');
    $('lod').textContent = parts.length
      ? 'To keep this page small, ' + parts.join('; ') + '. ' + d.drawn_moves + ' of ' + d.program_moves +
        ' moves are drawn. Never left out: the points where the toolpath reaches its lowest and highest X, Y and Z, and moves outside the travel limits.'
      : 'Every one of the ' + d.program_moves + ' moves is drawn.';
    const tt = D.time;
    const untimed = tt.untimed_feed_moves + tt.untimed_rapid_moves;
    $('summary').textContent = d.program_moves + ' moves, ' + S.tools.length + ' tool' + (S.tools.length === 1 ? '' : 's') +
      ', estimated time ' + (untimed ? 'at least ' + hms(tt.total_s) + ' (' + untimed + ' moves not timed)' : hms(tt.total_s)) +
      (d.drawn_moves < d.program_moves ? '; ' + d.drawn_moves + ' moves drawn' : '') + '.';
  }

  // ---- start
  recolour();
  window.addEventListener('resize', resize);
  resize();
  showTime();

  // For tests and scripting: the scene's numbers and a few actions.
  window.ngcflat = {
    moves: N,
    programMoves: S.detail.program_moves,
    totalTime: S.total_time,
    shown: () => { draw(); return st.shown; },
    visibleMoves: () => { const out = []; const d = doneCount(); for (let k = 0; k < d; k++) if (visible(k)) out.push(k); return out; },
    lineOf: (k) => mLine[k],
    moveOfLine: (line) => { for (let k = 0; k < N; k++) if (mLine[k] === line) return k; return -1; },
    screenPoint: (k) => {
      draw();
      const a = mStart[k], b = mEnd[k];
      const v = a + Math.floor((b - a) / 2);
      const w = Math.min(b, v + 1);
      const r = canvas.getBoundingClientRect();
      return [r.left + (SX[v] + SX[w]) / 2, r.top + (SY[v] + SY[w]) / 2];
    },
    selected: () => st.selected.slice(),
    setView,
  };
})();
