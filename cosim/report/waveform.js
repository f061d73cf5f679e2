/* The waveform of a cosim run page: every row of the run in one Bokeh figure, drawn from the
 * data the page holds (script#cosim-wave) and the side files it loads when zoomed in.
 *
 * Rows are bands of the figure, y in pixels from the top. What each row shows is worked out
 * here for the visible window only (numbers in ticks of the trace's resolution):
 *   value rows   the records held until the next one (a step line; a bit also shaded when high;
 *                an int with named states or a constant row also labelled), from the finest level
 *                that suits the window;
 *   pulse trains the pulses when at most `cap` are visible (cosimPulses, the rule of
 *                cosim.pulses), else the rate (pulses/s, signed by direction);
 *   violations   a marker per violation in the top band, a dashed line through every row.
 * The view (window and rows) is kept in the URL: #t=<from ms>,<to ms>&rows=<name>,<name>...
 */
(function () {
  "use strict";
  const W = {};
  window.cosimWave = W;
  const loaded = {}, requested = {};
  const BINS = 1200;  // slices of the window a crowded row is drawn in (about its pixels)
  let B = null, D = null, shown = [], custom = false, layout = [], total = 0, scheduled = false;
  let laneNames = {}, firstDrawn = false, hashTimer = null, current = -1, applyingHash = false;

  function bytesOf(s) {  // base64 to bytes (natively where the browser can)
    if (Uint8Array.fromBase64) return Uint8Array.fromBase64(s);
    const bin = atob(s), bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    return bytes;
  }
  function decode(s) {
    const bytes = bytesOf(s);
    return new Float64Array(bytes.buffer, bytes.byteOffset, bytes.length / 8);
  }
  function decodeAny(x) {  // float64 in base64, or {i4: int32 in base64}, as a Float64Array
    if (typeof x === "string") return decode(x);
    const bytes = bytesOf(x.i4);
    return Float64Array.from(new Int32Array(bytes.buffer, bytes.byteOffset, bytes.length / 4));
  }
  function decodeAll(obj) {
    const out = {};
    for (const k in obj) out[k] = decodeAny(obj[k]);
    return out;
  }
  async function unpack(p) {  // an array of a side file (cosim.report.levels.pack)
    const stream = new Blob([bytesOf(p.z)]).stream().pipeThrough(new DecompressionStream("deflate"));
    const raw = await new Response(stream).arrayBuffer();
    if (p.enc === "f") return new Float64Array(raw);
    const steps = new Int32Array(raw), out = new Float64Array(p.n);
    let acc = p.first;
    if (p.n) out[0] = acc;
    for (let i = 0; i < steps.length; i++) { acc += steps[i]; out[i + 1] = acc; }
    return out;
  }
  window.cosimData = async function (key, arrays) {
    const out = {};
    for (const k in arrays) out[k] = await unpack(arrays[k]);
    loaded["waveform/" + key] = out;
    schedule();
  };
  function need(file) {
    if (loaded[file]) return loaded[file];
    if (!requested[file]) {
      requested[file] = true;
      const s = document.createElement("script");
      s.src = file;
      document.head.appendChild(s);
    }
    return null;
  }

  // -- time in words ---------------------------------------------------------------------------
  function unitFor(spanNs) {
    return spanNs >= 2e9 ? ["s", 1e9] : spanNs >= 2e6 ? ["ms", 1e6] : spanNs >= 2e3 ? ["us", 1e3] : ["ns", 1];
  }
  const NUMBER = new Intl.NumberFormat("en", {maximumFractionDigits: 9});
  W.timeText = function (ticks, spanTicks) {
    const ns = ticks * (D === null ? ensure() : D).nsPerTick;
    const [u, f] = unitFor(Math.abs(spanTicks === undefined ? ns : spanTicks * D.nsPerTick));
    return NUMBER.format(Number((ns / f).toPrecision(12))) + " " + u;
  };
  function msText(ticks) {
    return String(Number((ticks * D.nsPerTick / 1e6).toFixed(6)));
  }
  function valueText(row, v) {
    if (v === null || v === undefined) return "no record yet";
    if (Number.isNaN(v)) return "NaN";
    if (row.states && row.states[v] !== undefined) return row.states[v] + " (" + v + ")";
    const text = Number.isInteger(v) ? v.toLocaleString("en") : Number(v.toPrecision(6)).toLocaleString("en", {maximumFractionDigits: 6});
    return row.unit ? text + " " + row.unit : text;
  }

  // -- layout ------------------------------------------------------------------------------------
  function bandHeight(row) {  // (the same as cosim.report.waveform's)
    if (row.quiet || row.constant) return D.bandPx.constant;
    if (row.kind === "int" && row.states) return D.bandPx.states;
    return D.bandPx[row.kind];
  }
  function relayout() {
    layout = [];
    let y = 0;
    const checks = D.checks.filter((c) => c.marks > 0);
    if (D.marks.length) {
      layout.push({band: "violations", top: 0, h: 14 + 16 * checks.length, checks: checks});
      y += layout[0].h;
    }
    for (const name of shown) {
      const row = D.byName[name];
      const h = bandHeight(row);
      layout.push({band: "row", row: row, top: y, h: h});
      y += h;
    }
    const folded = D.quiet.filter((n) => shown.indexOf(n) < 0);
    if (folded.length) {
      layout.push({band: "quiet", top: y, h: D.quietPx, names: folded});
      y += D.quietPx;
    }
    total = Math.max(y, 20);
    const ticks = [], labels = {};
    for (const lane of layout) {
      const mid = lane.top + lane.h / 2;
      ticks.push(mid);
      labels[mid] = lane.band === "row" ? lane.row.name : lane.band === "violations" ? "violations"
        : folded.length + " quiet signals";
    }
    B.yr.setv({start: total, end: 0});
    laneNames = labels;
    B.ticker.ticks = ticks;
    const box = document.getElementById("cosim-plot");  // the figure fills it (stretch_both)
    if (box && box.style.height !== (total + D.margin) + "px") box.style.height = (total + D.margin) + "px";
    const bands = {y0: [], y1: [], color: []};
    layout.forEach((lane, k) => {
      bands.y0.push(lane.top); bands.y1.push(lane.top + lane.h);
      bands.color.push(lane.band === "violations" ? "#fdeaea" : lane.row && lane.row.checked ? "#fff6e0"
        : k % 2 ? "#f4f6f8" : "#ffffff");
    });
    B.bands.data = bands;
  }

  // -- data of a row for a window ----------------------------------------------------------------
  function lowerBound(a, x) { let lo = 0, hi = a.length; while (lo < hi) { const m = (lo + hi) >> 1; if (a[m] < x) lo = m + 1; else hi = m; } return lo; }
  function upperBound(a, x) { let lo = 0, hi = a.length; while (lo < hi) { const m = (lo + hi) >> 1; if (a[m] <= x) lo = m + 1; else hi = m; } return lo; }

  function overviewFits(span) {  // are the page's own slices (the overview) about a pixel wide, or finer?
    return D.end / D.buckets <= span / BINS;
  }
  function pickLevel(row, span) {  // the coarsest level whose slices are about a pixel wide, or finer
    const want = span / BINS;
    for (const level of row.detail) if (level.w <= want) return level;
    return row.detail[row.detail.length - 1];
  }
  function blocksIn(level, a, b) { return level.blocks.filter((bl) => bl[1] >= a && bl[0] <= b); }
  function gather(level, a, b, keys) {  // the loaded blocks of a level in [a, b], or null while loading
    const parts = [];
    let missing = false;
    for (const bl of blocksIn(level, a, b)) {
      const data = need(bl[2]);
      if (data === null) missing = true; else parts.push(data);
    }
    if (missing) return null;
    const out = {};
    for (const k of keys) {
      const n = parts.reduce((s, p) => s + p[k].length, 0), arr = new Float64Array(n);
      let o = 0;
      for (const p of parts) { arr.set(p[k], o); o += p[k].length; }
      out[k] = arr;
    }
    return out;
  }
  function valuePoints(row, a, b) {
    if (!row.detail.length || overviewFits(b - a)) return {t: row.t, v: row.v};
    const level = pickLevel(row, b - a);
    const got = gather(level, a, b, ["t", "v"]);
    if (got === null || got.t.length === 0) return {t: row.t, v: row.v};
    // the part after the last block still holds the last value: close with the overview's end
    return {t: Float64Array.from([...got.t, row.t[row.t.length - 1]]), v: Float64Array.from([...got.v, got.v[got.v.length - 1]])};
  }
  function valueAt(row, pts, x) {
    const i = upperBound(pts.t, x) - 1;
    return i < 0 ? null : pts.v[i];
  }

  // -- drawing -----------------------------------------------------------------------------------
  function schedule() {
    if (scheduled || B === null) return;
    scheduled = true;
    requestAnimationFrame(() => { scheduled = false; draw(); });
  }
  function draw() {
    const a = B.xr.start, b = B.xr.end, span = Math.max(b - a, 1);
    const px = span / Math.max(B.fig.inner_width || 1200, 100);  // ticks per pixel
    const lines = {xs: [], ys: [], color: []};
    const quads = {left: [], right: [], bottom: [], top: [], color: [], alpha: []};
    const texts = {x: [], y: [], text: [], color: []};
    const marksY = {t: [], y: [], check: [], when: [], value: [], limit: [], detail: []};
    for (const lane of layout) {
      if (lane.band === "violations") {
        for (const m of D.marks) {
          const k = lane.checks.findIndex((c) => c.number === m.check);
          marksY.t.push(m.t); marksY.y.push(lane.top + 10 + 16 * k); marksY.check.push(m.name);
          marksY.when.push(W.timeText(m.t)); marksY.value.push(m.value); marksY.limit.push(m.limit);
          marksY.detail.push(m.detail);
        }
        lane.checks.forEach((c, k) => {
          texts.x.push(a + 4 * px); texts.y.push(lane.top + 10 + 16 * k);
          texts.text.push("check " + c.number + ": " + c.name); texts.color.push("#b01c1c");
        });
        continue;
      }
      if (lane.band === "quiet") {
        texts.x.push(a + 4 * px); texts.y.push(lane.top + lane.h / 2);
        texts.text.push(lane.names.map((n) => D.byName[n].kind === "pulse" ? n + ": no pulses"
          : n + " = " + valueText(D.byName[n], D.byName[n].value)).join(", "));
        texts.color.push("#666");
        continue;
      }
      const row = lane.row, top = lane.top + 4, h = lane.h - 8;
      if (row.kind === "pulse") drawTrain(row, top, h, a, b, px, quads, lines, texts);
      else drawValue(row, top, h, a, b, px, lines, quads, texts);
    }
    B.lines.data = lines;
    B.quads.data = quads;
    B.texts.data = texts;
    B.markPoints.data = marksY;
    W.draws = (W.draws || 0) + 1;
    if (!firstDrawn) {
      firstDrawn = true;
      requestAnimationFrame(() => requestAnimationFrame(() => { performance.mark("cosim-first-draw"); W.drawn = true; }));
    }
  }

  function yOf(row, v, top, h) {
    if (row.high === row.low) return top + h / 2;
    return top + (row.high - v) / (row.high - row.low) * h;
  }
  function drawValue(row, top, h, a, b, px, lines, quads, texts) {
    if (row.quiet || row.constant) {
      const y = top + h / 2;
      lines.xs.push([Math.max(row.first, 0), row.t[row.t.length - 1]]); lines.ys.push([y, y]); lines.color.push("#555");
      texts.x.push(Math.max(a, row.first) + 4 * px); texts.y.push(y - 6);
      texts.text.push("= " + valueText(row, row.value)); texts.color.push("#333");
      return;
    }
    const pts = valuePoints(row, a, b), t = pts.t, v = pts.v;
    let i0 = Math.max(upperBound(t, a) - 1, 0);
    const i1 = Math.min(lowerBound(t, b) + 1, t.length);
    const xs = [], ys = [];
    for (let i = i0; i < i1; i++) {
      const y = Number.isNaN(v[i]) ? NaN : yOf(row, v[i], top, h);
      const next = i + 1 < t.length ? t[i + 1] : t[i];
      xs.push(t[i], next); ys.push(y, y);
    }
    lines.xs.push(xs); lines.ys.push(ys); lines.color.push(row.kind === "bit" ? "#2a9d3f" : "#333333");
    const labelled = row.states || row.kind === "bit";
    if (row.kind === "bit" && i1 - i0 < 2 * BINS) {
      for (let i = i0; i < i1 - 1; i++) {
        if (v[i] > 0) { quads.left.push(t[i]); quads.right.push(t[i + 1]); quads.bottom.push(top + h); quads.top.push(top); quads.color.push("#2a9d3f"); quads.alpha.push(0.18); }
      }
    }
    if (row.states && i1 - i0 < 5000) {  // a named state on each change wide enough to read it
      for (let i = i0; i < i1 - 1; i++) {
        const from = Math.max(t[i], a), to = Math.min(t[i + 1], b);
        const text = row.states[v[i]] !== undefined ? row.states[v[i]] : String(v[i]);
        if ((to - from) / px > 7 * text.length + 8) {
          texts.x.push(from + 4 * px); texts.y.push(Math.min(yOf(row, v[i], top, h) + (v[i] === row.high ? 10 : -6), top + h));
          texts.text.push(text); texts.color.push("#1f4e79");
        }
      }
    }
    if (!labelled) {  // the value scale
      texts.x.push(a + 4 * px); texts.y.push(top + 6); texts.text.push(valueText(row, row.high)); texts.color.push("#888");
      texts.x.push(a + 4 * px); texts.y.push(top + h - 2); texts.text.push(valueText(row, row.low)); texts.color.push("#888");
    }
  }

  function trainRates(row, a, b) {  // {left, right, rate} for the window, from the finest suitable level loaded
    if (!row.detail.length || overviewFits(b - a)) return {left: row.left, right: row.right, rate: row.rate};
    const levels = row.detail.filter((l) => l.w > 0);
    let use = null;
    const want = (b - a) / BINS;
    for (const level of levels) {
      const got = gather(level, a, b, ["left", "rate"]);
      if (got !== null) use = {level: level, data: got};
      if (level.w <= want) break;
    }
    if (use === null) return {left: row.left, right: row.right, rate: row.rate, exact: false};
    const right = use.data.left.map((x) => x + use.level.w);
    return {left: use.data.left, right: right, rate: use.data.rate, w: use.level.w};
  }
  function drawTrain(row, top, h, a, b, px, quads, lines, texts) {
    const zero = yOf(row, 0, top, h);
    let pulses = null;
    if (row.seg) {
      pulses = cosimPulses(row.seg, a, b, D.cap);
    } else if (row.detail.length) {
      const r = trainRates(row, a, b);
      let n = 0;
      const i0 = Math.max(upperBound(r.left, a) - 1, 0), i1 = lowerBound(r.left, b);
      const perTick = 1 / 1e9 / D.nsPerTick;
      for (let i = i0; i < i1; i++) n += Math.abs(r.rate[i]) * (r.right[i] - r.left[i]) * perTick;
      if (n <= D.cap) {
        const seg = gather(row.detail[row.detail.length - 1], a, b, ["t0", "duration", "count", "dir", "width"]);
        if (seg !== null) pulses = cosimPulses(seg, a, b, D.cap);
      }
    }
    row.showing = pulses === null ? "rate" : "pulses";
    row.drawnPulses = pulses === null ? null : Array.from(pulses.t);
    if (pulses !== null) {
      for (let i = 0; i < pulses.t.length; i++) {
        quads.left.push(pulses.t[i]); quads.right.push(pulses.t[i] + pulses.width[i]);
        quads.bottom.push(top + h); quads.top.push(top + 2);
        quads.color.push(pulses.dir[i] === 1 ? D.up : D.down); quads.alpha.push(0.9);
      }
      texts.x.push(a + 4 * px); texts.y.push(top + 6); texts.text.push(pulses.t.length + " pulses in view"); texts.color.push("#888");
      return;
    }
    const r = trainRates(row, a, b);
    const i0 = Math.max(upperBound(r.left, a) - 1, 0), i1 = lowerBound(r.left, b);
    if (i1 - i0 > BINS) {  // more blocks than pixels: each pixel's pulses over its width (the mean rate there)
      const width = (b - a) / BINS, up = new Float64Array(BINS), down = new Float64Array(BINS);
      for (let i = i0; i < i1; i++) {
        const area = r.rate[i] * (r.right[i] - r.left[i]), k = Math.floor((Math.max(r.left[i], a) - a) / width);
        if (k < 0 || k >= BINS) continue;
        if (area >= 0) up[k] += area; else down[k] += area;
      }
      for (let k = 0; k < BINS; k++) {
        for (const area of [up[k], down[k]]) {
          if (area === 0) continue;
          quads.left.push(a + k * width); quads.right.push(a + (k + 1) * width);
          quads.bottom.push(zero); quads.top.push(yOf(row, area / width, top, h));
          quads.color.push(area >= 0 ? D.up : D.down); quads.alpha.push(0.45);
        }
      }
    } else {
      for (let i = i0; i < i1; i++) {
        if (r.right[i] < a) continue;
        quads.left.push(r.left[i]); quads.right.push(r.right[i]);
        quads.bottom.push(zero); quads.top.push(yOf(row, r.rate[i], top, h));
        quads.color.push(r.rate[i] >= 0 ? D.up : D.down); quads.alpha.push(0.45);
      }
    }
    lines.xs.push([a, b]); lines.ys.push([zero, zero]); lines.color.push("#bbb");
    texts.x.push(a + 4 * px); texts.y.push(top + 6);
    texts.text.push(row.pulses ? valueText({unit: "pulses/s"}, row.high) + " (rate)" : "no pulses");
    texts.color.push("#888");
  }

  // -- hover readout -----------------------------------------------------------------------------
  W.laneName = function (tick) {
    const name = laneNames[tick];
    return name === undefined ? "" : name.length > 34 ? "\u2026" + name.slice(name.length - 33) : name;
  };
  W.hover = function (x, y) {
    const out = document.getElementById("cosim-readout");
    if (!out || D === null) return;
    const lane = layout.find((l) => y >= l.top && y < l.top + l.h);
    let text = "t = " + W.timeText(x, B.xr.end - B.xr.start);
    if (lane && lane.band === "row") {
      const row = lane.row;
      if (row.kind === "pulse") {
        const r = trainRates(row, B.xr.start, B.xr.end), i = upperBound(r.left, x) - 1;
        const rate = i >= 0 && r.right[i] > x ? r.rate[i] : 0;
        text += "   " + row.name + ": " + valueText({unit: "pulses/s"}, Number(rate.toPrecision(6))) +
          (row.showing === "pulses" ? " (its pulses drawn one by one)" : "");
      } else {
        const pts = row.quiet || row.constant ? {t: row.t, v: row.v} : valuePoints(row, B.xr.start, B.xr.end);
        text += "   " + row.name + " = " + valueText(row, valueAt(row, pts, x));
      }
      if (row.desc) text += "   (" + row.desc + ")";
    }
    out.textContent = text;
  };

  // -- the view: window, rows, URL ---------------------------------------------------------------
  function setWindow(a, b) {
    const lo = 0, hi = D.end;
    const span = Math.min(Math.max(b - a, 10), hi - lo);
    a = Math.min(Math.max(a, lo), hi - span);
    B.xr.setv({start: a, end: a + span});
  }
  W.showTicks = function (t) {
    const half = Math.max(Math.min((B.xr.end - B.xr.start) / 2, D.end / 40), 5);
    setWindow(t - half, t + half);
  };
  W.showNs = function (tNs) { W.showTicks(tNs / D.nsPerTick); };
  W.whole = function () { setWindow(0, D.end); };
  W.setRows = function (names) {
    if (names === null) { shown = D.defaultRows.slice(); custom = false; }
    else { shown = D.order.filter((n) => names.indexOf(n) >= 0); custom = true; }
    relayout(); syncBoxes(); schedule(); saveHash();
  };
  W.showCheck = function (number) {
    const c = D.checks.find((k) => k.number === number);
    if (!c) return;
    W.setRows(c.rows.length ? c.rows : null);
    if (c.first !== null) { current = D.marks.findIndex((m) => m.t === c.first); W.showTicks(c.first); say(); }
  };
  function say() {
    const out = document.getElementById("cosim-violation");
    if (!out) return;
    if (current < 0 || current >= D.marks.length) { out.textContent = ""; return; }
    const m = D.marks[current];
    out.textContent = "violation " + (current + 1) + " of " + D.marks.length + ": check " + m.check + " (" + m.name +
      ") at " + W.timeText(m.t) + ": " + m.value + " vs limit " + m.limit + (m.detail ? " (" + m.detail + ")" : "");
  }
  W.violation = function (which) {  // "first", "next", "previous"
    if (!D.marks.length) return;
    const mid = (B.xr.start + B.xr.end) / 2;
    const known = current >= 0 && current < D.marks.length && D.marks[current].t >= B.xr.start &&
      D.marks[current].t <= B.xr.end;  // the one shown last is still in view: step from it
    if (which === "first") current = 0;
    else if (known) current = Math.max(0, Math.min(D.marks.length - 1, current + (which === "next" ? 1 : -1)));
    else if (which === "next") {
      const k = D.marks.findIndex((m) => m.t > mid + 0.5);
      current = k < 0 ? D.marks.length - 1 : k;
    } else {
      let k = -1;
      D.marks.forEach((m, i) => { if (m.t < mid - 0.5) k = i; });
      current = k < 0 ? 0 : k;
    }
    W.showTicks(D.marks[current].t);
    say();
  };
  function saveHash() {
    if (applyingHash) return;
    clearTimeout(hashTimer);
    hashTimer = setTimeout(() => {
      let hash = "#t=" + msText(B.xr.start) + "," + msText(B.xr.end);
      if (custom) hash += "&rows=" + shown.map(encodeURIComponent).join(",");
      if (location.hash !== hash) history.replaceState(null, "", hash);
    }, 150);
  }
  function applyHash() {
    const params = new URLSearchParams(location.hash.replace(/^#/, ""));
    applyingHash = true;
    if (params.has("rows")) {
      const names = params.get("rows").split(",").map(decodeURIComponent).filter((n) => D.byName[n]);
      shown = D.order.filter((n) => names.indexOf(n) >= 0); custom = true;
    }
    relayout(); syncBoxes();
    if (params.has("t")) {
      const [a, b] = params.get("t").split(",").map(Number);
      if (Number.isFinite(a) && Number.isFinite(b) && b > a) setWindow(a * 1e6 / D.nsPerTick, b * 1e6 / D.nsPerTick);
    }
    applyingHash = false;
    return params.has("t") || params.has("rows");
  }
  W.lanes = function () {  // what is drawn, top to bottom: for a reader's tools and the browser test
    return layout.map((l) => ({name: l.band === "row" ? l.row.name : l.band, top: l.top, h: l.h,
                               showing: l.row ? l.row.showing || "values" : l.band,
                               pulses: l.row ? l.row.drawnPulses || null : null,
                               names: l.names || null}));
  };
  W.viewState = function () { return {start: B.xr.start, end: B.xr.end, rows: shown.slice()}; };
  function syncBoxes() {
    for (const box of document.querySelectorAll("input.cosim-row")) box.checked = shown.indexOf(box.value) >= 0;
  }
  W.toggle = function (box) {
    const names = shown.filter((n) => n !== box.value);
    if (box.checked) names.push(box.value);
    W.setRows(names);
  };

  // -- start -------------------------------------------------------------------------------------
  function ensure() {  // the page's data, decoded once (the axis may ask for it before the figure is ready)
    if (D !== null) return D;
    D = JSON.parse(document.getElementById("cosim-wave").textContent);
    D.byName = {};
    for (const row of D.rows) {
      for (const k of ["t", "v", "left", "right", "rate"]) if (row[k] !== undefined) row[k] = decodeAny(row[k]);
      if (row.seg) row.seg = decodeAll(row.seg);
      D.byName[row.name] = row;
    }
    D.order = D.rows.map((r) => r.name);
    return D;
  }
  W.init = function (models) {
    performance.mark("cosim-draw-start");
    B = models;
    ensure();
    performance.mark("cosim-decoded");
    B.xr.setv({bounds: [0, D.end]});
    B.spans.data = {t: D.marks.map((m) => m.t)};
    shown = D.defaultRows.slice();
    if (!applyHash()) { relayout(); setWindow(D.start, D.stop); }
    window.addEventListener("hashchange", () => { if (applyHash()) schedule(); });
    performance.mark("cosim-laid-out");
    draw();
    performance.mark("cosim-drawn-data");
  };
  W.changed = function () { schedule(); saveHash(); };
})();
