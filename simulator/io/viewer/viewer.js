// etorigami result viewer: canvas 2-D renderer (painter's algorithm), no external code.
// Data: the JSON in <script id="data"> written by simulator.io.viewer.
(function () {
  "use strict";
  const D = JSON.parse(document.getElementById("data").textContent);

  // ---------------------------------------------------------------- data
  function decode(text, Type) {
    const bin = atob(text);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return new Type(bytes.buffer);
  }
  const R = D.records.length, N = D.n_nodes, C = D.creases.length, NT = D.n_triangles;
  const qpos = decode(D.positions, Uint16Array);         // (R, N, 3) quantised in the bbox
  const qtemp = decode(D.temperature, Uint16Array);      // (R, N) quantised in t_range
  const tris = decode(D.triangles, Uint32Array);         // (NT, 3)
  const fold = decode(D.fold_angle, Float32Array);       // (R, C) [deg]
  const power = decode(D.power, Float32Array);           // (R, C) [mW]
  const ctemp = D.crease_temperature ? decode(D.crease_temperature, Float32Array) : null;
  const kind = decode(D.triangle_kind, Uint8Array);    // (NT,) 0 crease, 1 panel, 2 substrate
  const SUBSTRATE = 2;
  let nSubstrate = 0;
  for (let t = 0; t < NT; t++) if (kind[t] === SUBSTRATE) nSubstrate++;
  const lo = D.bbox[0], hi = D.bbox[1];
  const span = [0, 1, 2].map((k) => hi[k] - lo[k]);
  const mid = [0, 1, 2].map((k) => 0.5 * (lo[k] + hi[k]));
  const radius = 0.5 * Math.hypot(span[0], span[1], span[2]) || 1;
  const tlo = D.t_range[0], thi = D.t_range[1];

  // ---------------------------------------------------------------- colours
  const VIRIDIS = [[68, 1, 84], [71, 45, 123], [59, 82, 139], [44, 114, 142], [33, 145, 140],
                   [40, 174, 128], [94, 201, 98], [173, 220, 48], [253, 231, 37]];
  function colour(s, shade) {                     // s in [0, 1] -> [r, g, b] * shade
    const x = Math.min(Math.max(s, 0), 1) * (VIRIDIS.length - 1);
    const i = Math.min(Math.floor(x), VIRIDIS.length - 2), f = x - i;
    const a = VIRIDIS[i], b = VIRIDIS[i + 1];
    return [0, 1, 2].map((k) => Math.round((a[k] + f * (b[k] - a[k])) * shade));
  }
  const rgb = (c) => "rgb(" + c[0] + "," + c[1] + "," + c[2] + ")";

  // ---------------------------------------------------------------- state
  const HOME = { yaw: -0.6, elev: 0.6, zoom: 1 };
  const view = Object.assign({}, HOME);
  let rec = 0, crease = 0, playing = false, pending = false;
  const el = (id) => document.getElementById(id);
  const scene = el("scene"), ctx = scene.getContext("2d");
  const slider = el("slider"), playButton = el("play"), select = el("crease");

  // ---------------------------------------------------------------- geometry
  const L = 3;                                    // subdivision of each triangle (colour interpolation)
  const BARY = [], SUB = [];
  const idx = (i, j) => BARY.findIndex((b) => b[0] === i && b[1] === j);
  for (let i = 0; i <= L; i++) for (let j = 0; j <= L - i; j++) BARY.push([i, j, L - i - j]);
  for (let i = 0; i < L; i++) {
    for (let j = 0; j < L - i; j++) {
      SUB.push([idx(i, j), idx(i + 1, j), idx(i, j + 1)]);
      if (i + j <= L - 2) SUB.push([idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)]);
    }
  }
  const cam = new Float64Array(3 * N), scr = new Float64Array(2 * N), temp = new Float64Array(N);

  function project() {                           // nodes of the current record -> camera, screen
    const W = scene.width, H = scene.height;
    const cy = Math.cos(view.yaw), sy = Math.sin(view.yaw);
    const ce = Math.cos(view.elev), se = Math.sin(view.elev);
    const scale = 0.5 * Math.min(W, H) * view.zoom, dist = 4;
    const base = rec * N * 3;
    for (let n = 0; n < N; n++) {
      const p = [0, 1, 2].map((k) => (lo[k] + qpos[base + 3 * n + k] / 65535 * span[k] - mid[k]) / radius);
      const x1 = p[0] * cy - p[1] * sy, y1 = p[0] * sy + p[1] * cy;
      const up = y1 * se + p[2] * ce, depth = y1 * ce - p[2] * se;
      cam[3 * n] = x1; cam[3 * n + 1] = up; cam[3 * n + 2] = depth;
      const f = scale * dist / (dist + depth);
      scr[2 * n] = 0.5 * W + f * x1; scr[2 * n + 1] = 0.5 * H - f * up;
      temp[n] = tlo + qtemp[rec * N + n] / 65535 * (thi - tlo);
    }
  }

  function triangle(t) {                          // fill triangle t with interpolated colours
    const a = tris[3 * t], b = tris[3 * t + 1], c = tris[3 * t + 2];
    const u = [0, 1, 2].map((k) => cam[3 * b + k] - cam[3 * a + k]);
    const v = [0, 1, 2].map((k) => cam[3 * c + k] - cam[3 * a + k]);
    const nx = u[1] * v[2] - u[2] * v[1], ny = u[2] * v[0] - u[0] * v[2], nz = u[0] * v[1] - u[1] * v[0];
    const shade = 0.55 + 0.45 * Math.abs(nz) / (Math.hypot(nx, ny, nz) || 1);
    const pts = BARY.map((w) => {
      const s = (q) => (w[0] * q[a] + w[1] * q[b] + w[2] * q[c]) / L;
      return [(w[0] * scr[2 * a] + w[1] * scr[2 * b] + w[2] * scr[2 * c]) / L,
              (w[0] * scr[2 * a + 1] + w[1] * scr[2 * b + 1] + w[2] * scr[2 * c + 1]) / L, s(temp)];
    });
    ctx.lineWidth = 0.8;
    const grey = kind[t] === SUBSTRATE ? rgb([0, 1, 2].map(() => Math.round(178 * shade))) : null;
    for (const s of SUB) {
      const P = s.map((i) => pts[i]);
      const style = grey ||
        rgb(colour(((P[0][2] + P[1][2] + P[2][2]) / 3 - tlo) / ((thi - tlo) || 1), shade));
      ctx.beginPath(); ctx.moveTo(P[0][0], P[0][1]); ctx.lineTo(P[1][0], P[1][1]);
      ctx.lineTo(P[2][0], P[2][1]); ctx.closePath();
      ctx.fillStyle = style; ctx.strokeStyle = style; ctx.fill(); ctx.stroke();
    }
    outline(t, "rgba(20,25,35,0.28)", 0.7);
  }

  function outline(t, style, width) {
    const a = tris[3 * t], b = tris[3 * t + 1], c = tris[3 * t + 2];
    ctx.beginPath(); ctx.moveTo(scr[2 * a], scr[2 * a + 1]); ctx.lineTo(scr[2 * b], scr[2 * b + 1]);
    ctx.lineTo(scr[2 * c], scr[2 * c + 1]); ctx.closePath();
    ctx.strokeStyle = style; ctx.lineWidth = width; ctx.stroke();
  }

  function draw() {
    pending = false;
    const dpr = window.devicePixelRatio || 1;
    const W = Math.max(1, Math.round(scene.clientWidth * dpr)), H = Math.max(1, Math.round(scene.clientHeight * dpr));
    if (scene.width !== W || scene.height !== H) { scene.width = W; scene.height = H; }
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.fillStyle = "#f4f5f7"; ctx.fillRect(0, 0, W, H);
    project();
    const order = Array.from({ length: NT }, (_, t) => t);
    const depth = order.map((t) => cam[3 * tris[3 * t] + 2] + cam[3 * tris[3 * t + 1] + 2] + cam[3 * tris[3 * t + 2] + 2]);
    order.sort((s, t) => depth[t] - depth[s]);    // far to near
    for (const t of order) triangle(t);
    if (D.crease_triangles) {
      for (let k = 0; k < 6; k++) outline(6 * crease + k, "#e0267d", 2.5 * dpr);
    }
    scaleBar(W, H, dpr);
    panels();
  }
  const request = () => { if (!pending) { pending = true; requestAnimationFrame(draw); } };

  // ---------------------------------------------------------------- length scale
  let scaleLabel = "";
  function niceLength(target) {                   // 1, 2 or 5 times a power of ten [m]
    const p = Math.pow(10, Math.floor(Math.log10(target)));
    for (const m of [5, 2, 1]) if (m * p <= target) return m * p;
    return p;
  }
  function lengthText(m) {
    return m >= 1e-3 ? fmt(m * 1e3, m >= 1e-2 ? 0 : 1) + " mm" : fmt(m * 1e6, m >= 1e-6 ? 0 : 2) + " \u00b5m";
  }
  function scaleBar(W, H, dpr) {                  // bar of a round length, at the depth of the centre
    const pxPerMetre = 0.5 * Math.min(W, H) * view.zoom / radius;
    const length = niceLength(140 * dpr / pxPerMetre), px = length * pxPerMetre;
    const x0 = 16 * dpr, y0 = H - 34 * dpr;
    ctx.strokeStyle = "#1d2330"; ctx.lineWidth = 2 * dpr; ctx.beginPath();
    ctx.moveTo(x0, y0 - 5 * dpr); ctx.lineTo(x0, y0); ctx.lineTo(x0 + px, y0); ctx.lineTo(x0 + px, y0 - 5 * dpr);
    ctx.stroke();
    scaleLabel = lengthText(length);
    ctx.fillStyle = "#1d2330"; ctx.font = (12 * dpr) + "px sans-serif";
    ctx.fillText(scaleLabel, x0 + 4 * dpr, y0 - 8 * dpr);
  }

  // ---------------------------------------------------------------- labels and side panels
  const fmt = (x, d) => (x === null || x === undefined || !isFinite(x) ? "-"
    : (Math.abs(x) < 0.5 * Math.pow(10, -d) ? 0 : Number(x)).toFixed(d));   // no "-0.0"

  function panels() {
    let tmin = Infinity, tmax = -Infinity, ptot = 0;
    for (let n = 0; n < N; n++) { tmin = Math.min(tmin, temp[n]); tmax = Math.max(tmax, temp[n]); }
    for (let c = 0; c < C; c++) ptot += power[rec * C + c];
    const time = D.time && D.time[rec] !== null ? " \u00b7 t " + fmt(D.time[rec], 4) + " s"
      : "";                                          // quasi-static records have no time
    el("record").textContent = "record " + D.records[rec] + "/" + (D.n_records - 1) + " \u00b7 " +
      D.stage[rec] + " increment " + D.increment[rec] + time + " \u00b7 total power (all creases) " +
      fmt(ptot, 2) + " mW \u00b7 nodes " + fmt(tmin, 1) + "\u2013" + fmt(tmax, 1) + " \u00b0C";
    const k = rec * C + crease;
    el("crease-info").innerHTML = "crease " + D.creases[crease] + ": fold angle <b id=\"fold\">" +
      fmt(fold[k], 2) + "</b>&deg;<br>" + "temperature (this crease) " +
      fmt(ctemp ? ctemp[k] : null, 1) + " &deg;C<br>power (this crease) <span id=\"crease-power\">" +
      fmt(power[k], 3) + "</span> mW";
    spark();
  }

  function spark() {                              // fold angle of the picked crease over the records
    const cv = el("spark"), dpr = window.devicePixelRatio || 1;
    cv.width = Math.round(cv.clientWidth * dpr); cv.height = Math.round(cv.clientHeight * dpr);
    const g = cv.getContext("2d"), W = cv.width, H = cv.height, pad = 6 * dpr, left = 44 * dpr;
    g.clearRect(0, 0, W, H);
    let a = Infinity, b = -Infinity;
    for (let r = 0; r < R; r++) { a = Math.min(a, fold[r * C + crease]); b = Math.max(b, fold[r * C + crease]); }
    if (b - a < 1e-9) { a -= 1; b += 1; }
    const X = (r) => left + (W - left - pad) * (R > 1 ? r / (R - 1) : 0);
    const Y = (f) => H - pad - (H - 2 * pad) * (f - a) / (b - a);
    g.strokeStyle = "#3b528b"; g.lineWidth = 1.5 * dpr; g.beginPath();
    for (let r = 0; r < R; r++) g[r ? "lineTo" : "moveTo"](X(r), Y(fold[r * C + crease]));
    g.stroke();
    g.fillStyle = "#e0267d"; g.beginPath();
    g.arc(X(rec), Y(fold[rec * C + crease]), 3.5 * dpr, 0, 2 * Math.PI); g.fill();
    g.fillStyle = "#5b6475"; g.font = (11 * dpr) + "px sans-serif";
    g.fillText(fmt(b, 1) + "\u00b0", 0, pad + 4 * dpr); g.fillText(fmt(a, 1) + "\u00b0", 0, H - pad + 4 * dpr);
    g.strokeStyle = "#d5d9e0"; g.lineWidth = dpr; g.beginPath();
    g.moveTo(left, pad); g.lineTo(left, H - pad); g.lineTo(W - pad, H - pad); g.stroke();
  }

  function colourbar() {
    const cv = el("colorbar"), g = cv.getContext("2d"), top = 28, bottom = cv.height - 10, x = 6, w = 16;
    for (let y = top; y <= bottom; y++) {
      g.fillStyle = rgb(colour((bottom - y) / (bottom - top), 1)); g.fillRect(x, y, w, 1);
    }
    g.strokeStyle = "#1d2330"; g.strokeRect(x + 0.5, top + 0.5, w, bottom - top);
    g.fillStyle = "#1d2330"; g.font = "12px sans-serif"; g.fillText("T [\u00b0C]", 2, 13);
    for (let i = 0; i <= 4; i++) {
      const y = bottom - i * (bottom - top) / 4, t = tlo + i * (thi - tlo) / 4;
      g.fillRect(x + w, Math.round(y), 4, 1);
      g.fillText(fmt(t, thi - tlo < 10 ? 2 : 1), x + w + 7, y + 4);
    }
  }

  // ---------------------------------------------------------------- controls
  function setRecord(r) {
    rec = Math.min(Math.max(Math.round(r), 0), R - 1);
    slider.value = String(rec);
    request();
  }
  function pick(c) { crease = Math.min(Math.max(c, 0), C - 1); select.value = String(crease); request(); }
  function setPlaying(on) {
    playing = on;
    playButton.innerHTML = on ? "&#10074;&#10074; Pause" : "&#9654; Play";
    if (on) { if (rec >= R - 1) setRecord(0); requestAnimationFrame(tick); }
  }
  let last = null, carry = 0;
  function tick(now) {                            // whole history in about 8 s
    if (!playing) { last = null; return; }
    if (last !== null) {
      carry += (now - last) / 1000 * Math.max(R / 8, 1);
      const step = Math.floor(carry);
      if (step > 0) { carry -= step; setRecord(rec + step); }
      if (rec >= R - 1) { last = null; setPlaying(false); return; }
    }
    last = now;
    requestAnimationFrame(tick);
  }
  function creaseScreen(c) {                      // mean screen position of crease c [CSS px]
    const dpr = window.devicePixelRatio || 1;
    let x = 0, y = 0;
    for (let k = 0; k < 18; k++) { const n = tris[18 * c + k]; x += scr[2 * n]; y += scr[2 * n + 1]; }
    return [x / 18 / dpr, y / 18 / dpr];
  }
  function pickAt(px, py) {
    if (!D.crease_triangles) return;
    project();
    let best = -1, bestD = 30;
    for (let c = 0; c < C; c++) {
      const s = creaseScreen(c), d = Math.hypot(s[0] - px, s[1] - py);
      if (d < bestD) { best = c; bestD = d; }
    }
    if (best >= 0) pick(best);
  }

  function wire() {
    slider.max = String(R - 1);
    slider.addEventListener("input", () => setRecord(Number(slider.value)));
    playButton.addEventListener("click", () => setPlaying(!playing));
    D.creases.forEach((id, c) => {
      const o = document.createElement("option");
      o.value = String(c); o.textContent = "crease " + id;     // the id of creases.csv and the CLI
      select.appendChild(o);
    });
    select.addEventListener("change", () => pick(Number(select.value)));
    let drag = null;
    scene.addEventListener("pointerdown", (e) => {
      drag = { x: e.clientX, y: e.clientY, moved: false }; scene.setPointerCapture(e.pointerId);
    });
    scene.addEventListener("pointermove", (e) => {
      if (!drag) return;
      const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
      if (!drag.moved && Math.hypot(dx, dy) < 4) return;
      drag.moved = true; scene.classList.add("dragging");
      view.yaw += 0.01 * dx;
      view.elev = Math.min(Math.max(view.elev + 0.01 * dy, -1.55), 1.55);
      drag.x = e.clientX; drag.y = e.clientY; request();
    });
    scene.addEventListener("pointerup", (e) => {
      if (drag && !drag.moved) {
        const r = scene.getBoundingClientRect(); pickAt(e.clientX - r.left, e.clientY - r.top);
      }
      drag = null; scene.classList.remove("dragging");
    });
    scene.addEventListener("wheel", (e) => {
      e.preventDefault();
      view.zoom = Math.min(Math.max(view.zoom * Math.exp(-0.0015 * e.deltaY), 0.2), 20); request();
    }, { passive: false });
    scene.addEventListener("dblclick", () => { Object.assign(view, HOME); request(); });
    window.addEventListener("resize", request);
  }

  // ---------------------------------------------------------------- start
  const status = el("status");
  status.textContent = D.status + (D.message ? ": " + D.message : "");
  if (D.status && D.status !== "converged") status.classList.add("failed");
  if (R < D.n_records) {
    el("thinned").textContent = "Showing " + R + " of " + D.n_records +
      " records (evenly thinned to keep the page small).";
  }
  if (nSubstrate) el("legend").textContent = "grey: substrate (held at room temperature)";
  wire();
  colourbar();
  pick(D.start_crease);
  setRecord(D.start_record);
  draw();
  window.viewer = {
    ready: true, records: R, creases: C, startRecord: D.start_record, substrate: nSubstrate,
    get scale() { return scaleLabel; },
    get record() { return rec; }, get crease() { return crease; }, get playing() { return playing; },
    get view() { return Object.assign({}, view); },
    setRecord: (r) => { setRecord(r); draw(); }, pick: (c) => { pick(c); draw(); },
    foldAngle: (c) => fold[rec * C + c], creaseScreen: (c) => { project(); return creaseScreen(c); },
  };
})();
