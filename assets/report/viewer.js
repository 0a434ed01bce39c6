// myriad's comparison viewer: plain JavaScript, no dependencies, no network.
// The data (see src/compare/html.rs): <script id="myriad-data"> holds the names, the error
// map's ramp, the metrics and the facts; <script data-image="k"> pieces hold image k as
// zlib-compressed half-float byte planes, in base64.
"use strict";
(async function () {
  const t0 = performance.now();
  const data = JSON.parse(document.getElementById("myriad-data").textContent);
  const t1 = performance.now();
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
  // An image's byte planes (see src/compare/html.rs), from its <script data-image> pieces,
  // decoded and inflated by the browser itself.
  async function decode(k) {
    const pieces = document.querySelectorAll(`script[data-image="${k}"]`);
    const b64 = Array.from(pieces, (p) => p.textContent).join("");
    const response = await fetch("data:application/octet-stream;base64," + b64);
    const stream = response.body.pipeThrough(new DecompressionStream("deflate"));
    return new Uint8Array(await new Response(stream).arrayBuffer());
  }
  const images = await Promise.all(data.images.map(async (im, k) => ({ name: im.name, caption: im.caption, planes: await decode(k) })));
  // Channel c of pixel i of an image.
  const value = (im, i, c) => HALF[(im.planes[c * N + i] << 8) | im.planes[(3 + c) * N + i]];
  const t2 = performance.now();

  // What is shown: which image, how, and where.
  const state = { index: 0, mode: "render", exposure: data.exposure, scale: 1, x: 0, y: 0 };
  // The image as large as the view holds it, centred (key f); key 0 shows it at 1:1.
  // A fitted image stays fitted when the window changes size, until the user zooms or pans.
  function fitView() {
    state.scale = Math.min(view.clientWidth / W, view.clientHeight / H);
    state.x = (view.clientWidth - W * state.scale) / 2;
    state.y = (view.clientHeight - H * state.scale) / 2;
    state.fitted = true;
  }
  fitView();
  window.addEventListener("resize", () => { if (state.fitted) { fitView(); place(); } });

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
    const a = images[state.index], ref = images[0], out = pixels.data;
    const k = Math.pow(2, state.exposure), [lo, hi] = data.decades;
    for (let i = 0; i < N; i++) {
      if (state.mode === "error") {
        let e = 0;
        for (let c = 0; c < 3; c++) {
          const x = value(a, i, c), y = value(ref, i, c);
          e += ((x - y) * (x - y)) / (y * y + data.epsilon);
        }
        e = Math.sqrt(e / 3);
        const [r, g, b] = ramp(e > 0 ? (Math.log10(e) - lo) / (hi - lo) : 0);
        out[4 * i] = r; out[4 * i + 1] = g; out[4 * i + 2] = b;
      } else {
        for (let c = 0; c < 3; c++) {
          const x = value(a, i, c);
          out[4 * i + c] = srgb8((state.mode === "diff" ? Math.abs(x - value(ref, i, c)) : x) * k);
        }
      }
      out[4 * i + 3] = 255;
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
      line.textContent = im.name.padEnd(12) + [0, 1, 2].map((c) => fmt(value(im, i, c))).join("") + "\n";
      readoutEl.appendChild(line);
    });
  }
  view.addEventListener("mousemove", (ev) => {
    const r = view.getBoundingClientRect();
    const mx = ev.clientX - r.left, my = ev.clientY - r.top;
    if (drag) {
      state.x = drag.x + mx - drag.mx;
      state.y = drag.y + my - drag.my;
      state.fitted = false;
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
    state.fitted = false;
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
    else if (k === "0") { state.scale = 1; state.x = 0; state.y = 0; state.fitted = false; place(); }
    else if (k === "f") { fitView(); place(); }
    else return;
    ev.preventDefault();
  });
  document.getElementById("help").textContent =
    "keys: ←/→ or space flip, 1–9 pick an image, r render, e relative error (against " + images[0].name +
    "), d |difference|, +/− exposure, f fit to the view, 0 actual size; wheel zooms, drag pans.";

  // The metrics table, sortable by any column.
  const metrics = document.getElementById("metrics");
  function table(sortBy, descending) {
    const t = data.table, rows = t.rows.slice();
    if (sortBy !== undefined) {
      const key = (row) => { const v = parseFloat(row[sortBy].text); return Number.isNaN(v) ? row[sortBy].text : v; };
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
    rows.forEach((r) => {
      const tr = el.insertRow();
      r.forEach((c) => {
        const td = tr.insertCell();
        td.textContent = c.text;
        if (c.mark) {
          td.className = "marked";
          td.append(" ", Object.assign(document.createElement("mark"), { textContent: c.mark }));
        }
      });
    });
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
  const t3 = performance.now();
  window.myriadTimes = [t0, t1 - t0, t2 - t1, t3 - t2];
  window.myriadReady = true;
})().catch((e) => { console.error("myriad viewer: " + e); document.body.prepend("The viewer failed: " + e); });
