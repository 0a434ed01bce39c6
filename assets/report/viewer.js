// myriad's comparison viewer: plain JavaScript, no dependencies, no network.
// The data (see src/compare/html.rs) is in <script id="myriad-data">: every image as
// zlib-compressed half-float byte planes, the error map's ramp, the metrics and the facts.
"use strict";
(async function () {
  const data = JSON.parse(document.getElementById("myriad-data").textContent);
  const W = data.width, H = data.height, N = W * H;
  const canvas = document.getElementById("canvas");
  const view = document.getElementById("view");
  const ctx = canvas.getContext("2d");
  canvas.width = W;
  canvas.height = H;

  // Half float → float, by table.
  const HALF = new Float32Array(65536);
  for (let h = 0; h < 65536; h++) {
    const s = h & 0x8000 ? -1 : 1, e = (h >> 10) & 31, m = h & 1023;
    HALF[h] = e === 0 ? s * m * Math.pow(2, -24) : e === 31 ? (m ? NaN : s * Infinity) : s * (1 + m / 1024) * Math.pow(2, e - 15);
  }
  async function decode(b64) {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    const stream = new Blob([bytes]).stream().pipeThrough(new DecompressionStream("deflate"));
    const planes = new Uint8Array(await new Response(stream).arrayBuffer());
    const rgb = new Float32Array(3 * N);
    for (let c = 0; c < 3; c++) {
      const hi = c * N, lo = (3 + c) * N;
      for (let i = 0; i < N; i++) rgb[3 * i + c] = HALF[(planes[hi + i] << 8) | planes[lo + i]];
    }
    return rgb;
  }
  const images = await Promise.all(data.images.map(async (im) => ({ name: im.name, caption: im.caption, rgb: await decode(im.half) })));

  // What is shown: which image, how, and where.
  const state = { index: 0, mode: "render", exposure: data.exposure, scale: 1, x: 0, y: 0 };
  const fit = Math.min(view.clientWidth / W, view.clientHeight / H);
  if (fit < 1) state.scale = Math.pow(2, Math.floor(Math.log2(fit)));

  // The PNG previews' tonemap: exposure, clamp, sRGB curve, 8 bits.
  function srgb8(v) {
    if (!(v > 0)) return 0;
    if (v >= 1) return 255;
    const s = v <= 0.0031308 ? 12.92 * v : 1.055 * Math.pow(v, 1 / 2.4) - 0.055;
    return Math.floor(s * 255 + 0.5);
  }
  function ramp(t) {
    const R = data.ramp, x = Math.min(Math.max(t, 0), 1) * (R.length - 1);
    const i = Math.min(Math.floor(x), R.length - 2), f = x - i;
    return [0, 1, 2].map((c) => Math.floor((R[i][c] * (1 - f) + R[i + 1][c] * f) * 255 + 0.5));
  }
  const pixels = ctx.createImageData(W, H);
  function paint() {
    const a = images[state.index].rgb, ref = images[0].rgb, out = pixels.data;
    const k = Math.pow(2, state.exposure), [lo, hi] = data.decades;
    for (let i = 0; i < N; i++) {
      let r, g, b;
      if (state.mode === "render") {
        r = srgb8(a[3 * i] * k); g = srgb8(a[3 * i + 1] * k); b = srgb8(a[3 * i + 2] * k);
      } else if (state.mode === "diff") {
        r = srgb8(Math.abs(a[3 * i] - ref[3 * i]) * k);
        g = srgb8(Math.abs(a[3 * i + 1] - ref[3 * i + 1]) * k);
        b = srgb8(Math.abs(a[3 * i + 2] - ref[3 * i + 2]) * k);
      } else {
        let e = 0;
        for (let c = 0; c < 3; c++) {
          const x = a[3 * i + c], y = ref[3 * i + c];
          e += ((x - y) * (x - y)) / (y * y + data.epsilon);
        }
        e = Math.sqrt(e / 3);
        [r, g, b] = ramp(e > 0 ? (Math.log10(e) - lo) / (hi - lo) : 0);
      }
      out[4 * i] = r; out[4 * i + 1] = g; out[4 * i + 2] = b; out[4 * i + 3] = 255;
    }
    ctx.putImageData(pixels, 0, 0);
    place();
    bar();
  }
  function place() {
    canvas.style.width = W * state.scale + "px";
    canvas.style.height = H * state.scale + "px";
    canvas.style.left = state.x + "px";
    canvas.style.top = state.y + "px";
  }

  // Buttons: one per image, the modes, the exposure.
  const barEl = document.getElementById("bar");
  function bar() {
    barEl.replaceChildren();
    const button = (label, on, act, title) => {
      const b = document.createElement("button");
      b.textContent = label;
      b.title = title || "";
      if (on) b.className = "on";
      b.onclick = act;
      barEl.appendChild(b);
    };
    images.forEach((im, i) => button((i + 1) + " " + im.name, i === state.index, () => show(i), im.caption));
    barEl.appendChild(Object.assign(document.createElement("span"), { className: "gap" }));
    [["render", "r"], ["error", "e"], ["diff", "d"]].forEach(([m, key]) =>
      button(m === "error" ? "relative error (e)" : m === "diff" ? "|difference| (d)" : "render (r)", state.mode === m, () => mode(m), key));
    const label = document.createElement("label");
    label.textContent = " exposure ";
    const slider = Object.assign(document.createElement("input"), { type: "range", min: -10, max: 10, step: 0.1, value: state.exposure, id: "exposure" });
    slider.oninput = () => { state.exposure = parseFloat(slider.value); paint(); };
    label.appendChild(slider);
    label.appendChild(document.createTextNode(" " + (state.exposure >= 0 ? "+" : "") + state.exposure.toFixed(1) + " stops"));
    barEl.appendChild(label);
  }
  function show(i) { state.index = (i + images.length) % images.length; paint(); readout(); }
  function mode(m) { state.mode = m; paint(); }

  // The value under the cursor, in every image.
  const readoutEl = document.getElementById("readout");
  let cursor = null;
  const fmt = (v) => (Number.isFinite(v) ? v.toPrecision(4) : String(v)).padStart(10);
  function readout() {
    if (!cursor) return;
    const { px, py } = cursor;
    readoutEl.replaceChildren();
    if (px < 0 || py < 0 || px >= W || py >= H) return;
    readoutEl.appendChild(document.createTextNode(`pixel ${px}, ${py}\n`));
    const i = py * W + px;
    images.forEach((im, k) => {
      const line = document.createElement("span");
      line.className = k === state.index ? "on" : "";
      line.dataset.name = im.name;
      line.textContent = im.name.padEnd(12) + fmt(im.rgb[3 * i]) + fmt(im.rgb[3 * i + 1]) + fmt(im.rgb[3 * i + 2]) + "\n";
      readoutEl.appendChild(line);
    });
  }
  view.addEventListener("mousemove", (ev) => {
    const r = view.getBoundingClientRect();
    const mx = ev.clientX - r.left, my = ev.clientY - r.top;
    if (drag) {
      state.x = drag.x + mx - drag.mx;
      state.y = drag.y + my - drag.my;
      place();
    }
    cursor = { px: Math.floor((mx - state.x) / state.scale), py: Math.floor((my - state.y) / state.scale) };
    readout();
  });

  // Wheel zoom about the cursor, drag to pan.
  let drag = null;
  view.addEventListener("mousedown", (ev) => {
    const r = view.getBoundingClientRect();
    drag = { mx: ev.clientX - r.left, my: ev.clientY - r.top, x: state.x, y: state.y };
    ev.preventDefault();
  });
  window.addEventListener("mouseup", () => { drag = null; });
  view.addEventListener("wheel", (ev) => {
    ev.preventDefault();
    const r = view.getBoundingClientRect();
    const mx = ev.clientX - r.left, my = ev.clientY - r.top;
    const s = Math.min(Math.max(state.scale * (ev.deltaY < 0 ? 2 : 0.5), 1 / 64), 256);
    state.x = mx - ((mx - state.x) * s) / state.scale;
    state.y = my - ((my - state.y) * s) / state.scale;
    state.scale = s;
    place();
  }, { passive: false });

  // Keys: flip, modes, exposure, zoom.
  document.addEventListener("keydown", (ev) => {
    if (ev.target && ev.target.tagName === "INPUT" && ev.key.startsWith("Arrow")) return;
    const k = ev.key;
    if (k === "ArrowRight" || k === " ") show(state.index + 1);
    else if (k === "ArrowLeft") show(state.index - 1);
    else if (/^[1-9]$/.test(k) && +k <= images.length) show(+k - 1);
    else if (k === "r") mode("render");
    else if (k === "e") mode("error");
    else if (k === "d") mode("diff");
    else if (k === "+" || k === "=") { state.exposure += 0.5; paint(); }
    else if (k === "-") { state.exposure -= 0.5; paint(); }
    else if (k === "0") { state.scale = 1; state.x = 0; state.y = 0; place(); }
    else return;
    ev.preventDefault();
  });
  document.getElementById("help").textContent =
    "keys: ←/→ or space flip, 1–9 pick an image, r render, e relative error (against " + images[0].name +
    "), d |difference|, +/− exposure, 0 actual size; wheel zooms, drag pans.";

  // The metrics table, sortable by any column.
  const metrics = document.getElementById("metrics");
  function table(sortBy, descending) {
    const t = data.table, rows = t.rows.slice();
    if (sortBy !== undefined) {
      const key = (row) => { const v = parseFloat(row[sortBy]); return Number.isNaN(v) ? row[sortBy] : v; };
      rows.sort((a, b) => { const x = key(a), y = key(b); const o = x < y ? -1 : x > y ? 1 : 0; return descending ? -o : o; });
    }
    const el = document.createElement("table");
    const head = el.insertRow();
    t.columns.forEach((c, i) => {
      const th = document.createElement("th");
      th.textContent = c + (i === sortBy ? (descending ? " ▼" : " ▲") : "");
      th.onclick = () => table(i, i === sortBy ? !descending : false);
      head.appendChild(th);
    });
    rows.forEach((r) => { const tr = el.insertRow(); r.forEach((c) => { tr.insertCell().textContent = c; }); });
    metrics.replaceChildren(el);
  }
  if (data.table.columns.length) table();

  const facts = document.getElementById("facts");
  const dl = document.createElement("dl");
  data.facts.forEach(([k, v]) => {
    dl.appendChild(Object.assign(document.createElement("dt"), { textContent: k }));
    dl.appendChild(Object.assign(document.createElement("dd"), { textContent: v }));
  });
  facts.appendChild(dl);

  paint();
  window.myriadReady = true;
})().catch((e) => { console.error("myriad viewer: " + e); document.body.prepend("The viewer failed: " + e); });
