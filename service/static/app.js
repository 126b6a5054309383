// skelprune viewer: POST /v1/prune?sequence=true, then draw the answer and every step of
// the pruning sequence from the document alone (docs/viewer.md says what is exact).
"use strict";

const $ = (id) => document.getElementById(id);
const SVGNS = "http://www.w3.org/2000/svg";
const COLOURS = { shape: [150, 210, 150], error: [220, 40, 40], background: [255, 255, 255] };

const state = {
  input: null,      // {body, type, name}
  text: null,       // the document as received
  doc: null,
  elapsed: 0,       // request round trip, ms
  comps: [],        // per component: see prepare()
  selected: 0,
  width: 0,
  height: 0,
  cnt: null,        // per pixel: disks of the drawn skeletons covering it
  image: null,      // ImageData of shape and error ...
  pixels: null,     // ... as one word per pixel
};

function el(tag, attrs, parent) {
  const e = document.createElementNS(SVGNS, tag);
  for (const [k, v] of Object.entries(attrs || {})) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}

const fmt = (v, digits = 4) => (v === null || v === undefined ? "–" : Number(v).toFixed(digits));
const pct = (v) => (v === null || v === undefined ? "–" : (100 * v).toFixed(3) + " %");

// ------------------------------------------------------------------ input
function pick(file) {
  if (!file) return;
  const name = file.name || "shape";
  const isPng = file.type === "image/png" || /\.png$/i.test(name);
  const isJson = /json$/i.test(file.type) || /\.(geo)?json$/i.test(name);
  if (!isPng && !isJson) {
    showProblem({ title: "Unsupported file", detail: `${name}: send a PNG mask or a GeoJSON file (.png, .geojson, .json).` });
    return;
  }
  state.input = { body: file, type: isPng ? "image/png" : "application/geo+json", name };
  $("filename").textContent = name;
  $("run").disabled = false;
  run();
}

function options(extra) {
  const q = new URLSearchParams();
  q.set("beta", $("beta").value);
  q.set("method", $("method").value);
  if ($("method").value === "bayesian") q.set("coarse", $("coarse").value);
  for (const [k, v] of Object.entries(extra || {})) q.set(k, v);
  return q.toString();
}

async function post(query, accept) {
  return fetch(`/v1/prune?${query}`, {
    method: "POST", body: state.input.body,
    headers: { "Content-Type": state.input.type, Accept: accept },
  });
}

async function problemOf(resp) {
  let p = { title: `HTTP ${resp.status}`, status: resp.status };
  try {
    p = { ...p, ...(await resp.json()) };
  } catch (e) { /* not JSON: keep the status line */ }
  return p;
}

function showProblem(p) {
  const box = $("problem");
  box.replaceChildren();
  const head = document.createElement("strong");
  head.textContent = p.status ? `${p.title} (${p.status})` : p.title;
  box.appendChild(head);
  const lines = [];
  if (p.detail) lines.push(p.detail);
  for (const e of p.errors || []) lines.push(`${(e.loc || []).join(".")}: ${e.msg}`);
  box.appendChild(document.createTextNode(lines.join("\n")));
  box.hidden = false;
  $("status").textContent = "";
}

// A polygon's parts that the raster does not hold as they are (vanished, split, holes).
function showWarnings(warnings) {
  const box = $("warnings");
  box.textContent = warnings.length
    ? "Warning: " + warnings.map((w) => w.message).join("\nWarning: ")
    : "";
  box.hidden = warnings.length === 0;
}

async function run() {
  if (!state.input) return;
  $("problem").hidden = true;
  $("warnings").hidden = true;
  $("status").textContent = "Pruning…";
  $("run").disabled = true;
  const t0 = performance.now();
  let resp;
  try {
    resp = await post(options({ sequence: "true", curve: "true" }), "application/json");
  } catch (e) {
    showProblem({ title: "The service did not answer", detail: String(e) });
    $("run").disabled = false;
    return;
  }
  if (!resp.ok) {
    showProblem(await problemOf(resp));
    $("result").hidden = true;
    $("run").disabled = false;
    return;
  }
  state.text = await resp.text();
  state.elapsed = performance.now() - t0;
  state.doc = JSON.parse(state.text);
  $("run").disabled = false;
  $("status").textContent = "";
  showWarnings(state.doc.warnings || []);
  show();
}

// ---------------------------------------------------------------- geometry
// Everything is drawn in the raster's pixels (x = column, y = row), so the error can be
// painted exactly; the document's own coordinates are shown on hover.
function prepare(c) {
  const seq = c.sequence;
  const f = seq.frame;
  const col = (x) => Math.round((x - f.x0) / f.pixel_size);
  const row = (y) => Math.round((f.flip_y ? f.y0 - y : y - f.y0) / f.pixel_size);
  const r2 = (r) => Math.round((r / f.pixel_size) ** 2);
  const n = c.curve.length - 1;
  // S(0)'s pixels: col, row, squared radius, the step that removes each, the branch.
  const px = [], removed = [], owner = [], world = [];
  const add = (p, at, b) => {
    px.push([col(p[0]), row(p[1]), r2(p[2])]);
    removed.push(at === null ? Infinity : at);
    owner.push(b);
    world.push(p);
  };
  for (const b of seq.branches) for (const p of b.points.concat(b.off_path)) add(p, b.removed_at, b.id);
  for (const nd of seq.nodes) if (nd.kind === "junction") for (const p of nd.points) add(p, nd.removed_at, -1 - nd.id);
  const byStep = Array.from({ length: n + 2 }, () => []);
  removed.forEach((at, i) => { if (at !== Infinity) byStep[at].push(i); });
  const answer = new Map();  // "col,row" -> branch of the answer (for its margin)
  for (const b of c.skeleton.branches) for (const p of b.points) answer.set(`${col(p[0])},${row(p[1])}`, b);
  // The answer is S(chosen) with its tips cut (trim): the pixels of S(chosen) it left out.
  const kept = new Set(answer.keys());
  for (const b of c.skeleton.branches) for (const p of b.off_path) kept.add(`${col(p[0])},${row(p[1])}`);
  for (const nd of c.skeleton.nodes) for (const p of nd.points) kept.add(`${col(p[0])},${row(p[1])}`);
  const tipCut = [];
  px.forEach(([x, y], i) => { if (removed[i] > c.chosen_step && !kept.has(`${x},${y}`)) tipCut.push(i); });
  return {
    c, seq, n, px, removed, owner, world, byStep, answer, step: c.chosen_step,
    tipCut, tipKeys: new Set(tipCut.map((i) => `${px[i][0]},${px[i][1]}`)), tipsOff: false,
    col, row, pixels: null,
    lines: seq.branches.map((b) => branchLine(seq, b).map((p) => [col(p[0]), row(p[1])])),
    medial: seq.coarse_removed.map((p) => [col(p[0]), row(p[1])]),
    uncovered: seq.uncovered.map((p) => [col(p[0]), row(p[1])]),
  };
}

// The branch's path from its source node to its target node (as the GeoJSON lines).
function branchLine(seq, b) {
  const line = b.points.map((p) => p.slice());
  const src = seq.nodes[b.source], dst = seq.nodes[b.target];
  const at = (p, nd) => p[0] === nd.x && p[1] === nd.y;
  if (!at(line[0], src)) line.unshift([src.x, src.y, src.radius]);
  if (!at(line[line.length - 1], dst) || line.length === 1) line.push([dst.x, dst.y, dst.radius]);
  return line;
}

// The discrete disk |p - s|² < r², as the library paints it: fn(rowStart, x0, x1) per row.
function diskRows(W, H, cx, cy, r2, fn) {
  for (let dy = 0; dy * dy < r2; dy++) {
    const lim = r2 - dy * dy - 1;
    let w = Math.floor(Math.sqrt(lim));
    while ((w + 1) * (w + 1) <= lim) w++;
    while (w * w > lim) w--;
    const x0 = Math.max(cx - w, 0), x1 = Math.min(cx + w, W - 1);
    for (const y of dy === 0 ? [cy] : [cy - dy, cy + dy]) {
      if (y >= 0 && y < H) fn(y * W, x0, x1);
    }
  }
}

function paintDisk(cnt, W, H, cx, cy, r2, delta) {
  diskRows(W, H, cx, cy, r2, (base, x0, x1) => {
    for (let x = x0; x <= x1; x++) cnt[base + x] += delta;
  });
}

// ------------------------------------------------------------------ drawing
function show() {
  const doc = state.doc;
  const W = (state.width = doc.width), H = (state.height = doc.height);
  state.comps = doc.components.map(prepare);
  state.selected = 0;
  state.cnt = new Int32Array(W * H);
  const cnt = state.cnt;
  for (const k of state.comps) {
    k.px.forEach(([x, y, r2]) => paintDisk(cnt, W, H, x, y, r2, 1));
    k.shape = [];   // the shape's pixels: R(S(0)) and what S(0) misses
  }
  const owner = new Int32Array(W * H).fill(-1);
  state.comps.forEach((k, ci) => {
    // a component's pixels: its start's disks (they lie in its own shape) and its misses
    for (const [x, y, r2] of k.px) {
      diskRows(W, H, x, y, r2, (base, x0, x1) => owner.fill(ci, base + x0, base + x1 + 1));
    }
    for (const [x, y] of k.uncovered) owner[y * W + x] = ci;
  });
  owner.forEach((ci, i) => { if (ci >= 0) state.comps[ci].shape.push(i); });
  for (const k of state.comps) {
    k.shape = Int32Array.from(k.shape);
    const target = k.step;
    k.step = 0;
    moveTo(k, target, false);
  }
  $("view").setAttribute("viewBox", `-0.5 -0.5 ${W} ${H}`);
  const raster = $("raster");
  raster.width = W; raster.height = H;
  state.image = raster.getContext("2d").createImageData(W, H);
  state.pixels = new Uint32Array(state.image.data.buffer);
  // a tall shape fits the window's height
  $("stage").style.maxWidth = `calc(80vh * ${W / H})`;
  const choice = $("component");
  choice.replaceChildren(...state.comps.map((k, i) => new Option(`${i + 1} (area ${k.c.area})`, i)));
  $("component-choice").hidden = state.comps.length < 2;
  $("result").hidden = false;
  drawMedial();
  select(0);
}

function select(ci) {
  state.selected = ci;
  const k = state.comps[ci];
  const slider = $("step");
  slider.max = k.n;
  slider.value = k.step;
  drawAll();
}

// S(k) of a component: the count of covering disks follows the removals step by step.
function moveTo(k, target, redraw = true) {
  const W = state.width, H = state.height, cnt = state.cnt;
  target = Math.max(0, Math.min(k.n, target));
  cutTips(k, false);
  while (k.step < target) {
    k.step++;
    for (const i of k.byStep[k.step]) paintDisk(cnt, W, H, k.px[i][0], k.px[i][1], k.px[i][2], -1);
  }
  while (k.step > target) {
    for (const i of k.byStep[k.step]) paintDisk(cnt, W, H, k.px[i][0], k.px[i][1], k.px[i][2], 1);
    k.step--;
  }
  cutTips(k, k.step === k.c.chosen_step);
  if (redraw) drawAll();
}

// At the chosen step the answer's cut tips are off the skeleton (and their disks off R).
function cutTips(k, off) {
  if (k.tipsOff === off) return;
  const W = state.width, H = state.height;
  for (const i of k.tipCut) paintDisk(state.cnt, W, H, k.px[i][0], k.px[i][1], k.px[i][2], off ? -1 : 1);
  k.tipsOff = off;
}

// One 32-bit RGBA word per pixel, in the platform's byte order (ImageData is RGBA bytes).
const LITTLE = new Uint8Array(new Uint32Array([1]).buffer)[0] === 1;
const word = ([r, g, b]) => (LITTLE ? ((255 << 24) | (b << 16) | (g << 8) | r) >>> 0
  : ((r << 24) | (g << 16) | (b << 8) | 255) >>> 0);
const WORDS = { shape: word(COLOURS.shape), error: word(COLOURS.error), background: word(COLOURS.background) };

function drawRaster() {
  const cnt = state.cnt, px = state.pixels;
  px.fill(WORDS.background);
  for (const k of state.comps) {
    let missing = 0;
    for (const i of k.shape) {
      if (cnt[i] > 0) px[i] = WORDS.shape;
      else { px[i] = WORDS.error; missing++; }
    }
    k.errorPixels = missing;
  }
  $("raster").getContext("2d").putImageData(state.image, 0, 0);
}

function ownerAt(seq, b, step) {
  let br = seq.branches[b];
  while (br.absorbed_at !== null && br.absorbed_at <= step) br = seq.branches[br.absorbed_into];
  return br.id;
}

const aliveAt = (item, step) => item.removed_at === null || item.removed_at > step;

function unit() {  // one screen pixel, in the viewBox's units
  const box = $("view").getBoundingClientRect();
  return box.width ? state.width / box.width : 1;
}

function drawSkeletons() {
  const gb = $("branches"), gn = $("nodes"), gl = $("labels");
  gb.replaceChildren(); gn.replaceChildren(); gl.replaceChildren();
  const u = unit();
  state.comps.forEach((k, ci) => {
    const seq = k.seq, step = k.step;
    const groups = new Map();
    for (const b of seq.branches) {
      if (!aliveAt(b, step)) continue;
      const o = ownerAt(seq, b.id, step);
      if (!groups.has(o)) groups.set(o, []);
      groups.get(o).push(b.id);
    }
    const chosen = step === k.c.chosen_step;
    for (const [o, members] of groups) {
      const g = el("g", { class: "branch", "data-component": ci, "data-branch": o }, gb);
      let longest = members[0];
      for (const b of members) {
        const line = chosen ? k.lines[b].filter((p) => !k.tipKeys.has(`${p[0]},${p[1]}`)) : k.lines[b];
        el("polyline", {
          points: line.map((p) => p.join(",")).join(" "),
          "stroke-width": 2, "vector-effect": "non-scaling-stroke",
        }, g);
        if (k.lines[b].length > k.lines[longest].length) longest = b;
      }
      const ans = chosen ? answerBranch(k, members) : null;
      if (ans) g.dataset.margin = ans.margin === null ? "" : ans.margin;
      if (ans && ans.margin !== null && $("show-margins").checked) {
        const line = k.lines[longest];
        const [x, y] = line[Math.floor(line.length / 2)];
        const t = el("text", { x: x + 3 * u, y: y - 3 * u, "font-size": 11 * u, "stroke-width": 3 * u }, gl);
        t.textContent = ans.margin.toFixed(3);
      }
    }
    for (const nd of seq.nodes) {
      let show = false;
      if (nd.kind === "junction") show = nd.dissolved_at === null || nd.dissolved_at > step;
      else show = seq.branches.some((b) => (b.source === nd.id || b.target === nd.id) && aliveAt(b, step));
      if (!show) continue;
      let [x, y] = [k.col(nd.x), k.row(nd.y)];
      if (chosen && nd.kind === "endpoint" && k.tipKeys.has(`${x},${y}`)) {
        // the cut tip's endpoint: the answer's endpoint nearest to it
        let best = Infinity;
        for (const a of k.c.skeleton.nodes) {
          if (a.kind !== "endpoint") continue;
          const [ax, ay] = [k.col(a.x), k.row(a.y)];
          const d = (ax - k.col(nd.x)) ** 2 + (ay - k.row(nd.y)) ** 2;
          if (d < best) { best = d; [x, y] = [ax, ay]; }
        }
      }
      el("circle", { class: nd.kind, cx: x, cy: y, r: (nd.kind === "junction" ? 4 : 3.5) * u }, gn);
    }
  });
}

function answerBranch(k, members) {
  for (const b of members) {
    for (const p of k.seq.branches[b].points) {
      const a = k.answer.get(`${k.col(p[0])},${k.row(p[1])}`);
      if (a) return a;
    }
  }
  return null;
}

function drawMedial() {
  const g = $("medial");
  g.replaceChildren();
  if (!$("show-medial").checked) return;
  for (const k of state.comps) for (const [x, y] of k.medial) el("rect", { class: "medial", x: x - 0.35, y: y - 0.35, width: 0.7, height: 0.7 }, g);
}

function counts(k) {
  const step = k.step, seq = k.seq;
  const owners = new Set();
  let endpoints = 0;
  const ends = new Set(seq.nodes.filter((n) => n.kind === "endpoint").map((n) => n.id));
  for (const b of seq.branches) {
    if (!aliveAt(b, step)) continue;
    owners.add(ownerAt(seq, b.id, step));
    endpoints += ends.has(b.source) + (ends.has(b.target) && b.target !== b.source);
  }
  return { branches: owners.size, endpoints };
}

function drawNumbers() {
  const k = state.comps[state.selected], c = k.c, doc = state.doc;
  const cur = c.curve[k.step];
  const alpha = c.alpha;
  const { branches, endpoints } = counts(k);
  const rows = [
    ["shape", `${doc.width} × ${doc.height} px, area ${c.area} px`],
    ["method / coarse / β", `${doc.method} / ${doc.coarse ?? "none"} / ${doc.beta}`],
    ["α", fmt(alpha)],
    ["chosen step", `${c.chosen_step} of ${k.n}`],
    ["RER", pct(c.rer)],
    ["SS", fmt(c.ss)],
    ["λ", fmt(c.objective)],
    ["answer: endpoints / branches", `${c.skeleton.endpoints.length} / ${c.skeleton.branches.length}`],
    ["medial axis: endpoints / branches", `${c.medial_axis.endpoints} / ${c.medial_axis.branches}`],
    ["medial axis RER", pct(c.medial_axis.rer)],
    ["time (request round trip)", `${state.elapsed.toFixed(0)} ms`],
    ["sep", ""],
    [`step ${k.step}: AR`, pct(cur.ar)],
    [`step ${k.step}: α·AR / LR / λ`, `${alpha === null ? "–" : fmt(alpha * cur.ar)} / ${fmt(cur.lr)} / ${fmt(cur.objective)}`],
    [`step ${k.step}: endpoints / branches`, `${endpoints} / ${branches}`],
    [`step ${k.step}: error pixels`, `${k.errorPixels}`],
  ];
  const table = $("numbers");
  table.replaceChildren();
  let sep = false;
  for (const [name, value] of rows) {
    if (name === "sep") { sep = true; continue; }
    const tr = table.insertRow();
    if (sep) { tr.className = "sep"; sep = false; }
    const th = document.createElement("th");
    th.textContent = name;
    tr.appendChild(th);
    tr.insertCell().textContent = value;
  }
  const info = $("step-info");
  info.textContent = `step ${k.step} of ${k.n}` + (k.step === c.chosen_step ? " (the answer)" : "") +
    ` — ${branches} branch${branches === 1 ? "" : "es"}, ${endpoints} endpoint${endpoints === 1 ? "" : "s"}`;
  Object.assign(info.dataset, {
    step: k.step, branches, endpoints, errorPixels: k.errorPixels,
    expectedErrorPixels: Math.round(cur.ar * c.area),
  });
  const start = k.seq.start === "coarse"
    ? "Step 0 is the coarse skeleton (coarse=dce): the coarse stage removes branches of the medial axis before the sequence begins, and those removals are not steps (tick the box under the image to see their pixels). "
    : "Step 0 is the medial axis. ";
  const dce = doc.method === "dce"
    ? "With method=dce the steps are the DCE pruning's removals, in its order, and the answer is the last; λ is shown for comparison, it did not choose. "
    : "The answer is the step with the smallest λ (ties to the later step), then further while the next step raises λ by less than min_margin" +
      (doc.trim ? "; its end branches are then cut back from their tips to the point of least λ, which the chosen step shows. " : ". ");
  if (c.alpha === null) {
    $("sequence-note").textContent = start + "This component has no end branch to prune (or a mean end-path length of 0): α is undefined, the sequence has only step 0, and λ is LR alone.";
    return;
  }
  $("sequence-note").textContent = start + dce +
    "Each step removes one end branch; where that leaves a junction with two branches, they become one. The drawing at every step and its red error follow exactly from the document.";
}

function drawCurve() {
  const k = state.comps[state.selected], c = k.c;
  const svg = $("curve");
  svg.replaceChildren();
  const L = 44, R = 410, T = 14, B = 190;
  const n = Math.max(k.n, 1);
  const alpha = c.alpha;
  const series = [
    ["lambda", "λ", c.curve.map((s) => s.objective)],
    ["lr", "LR", c.curve.map((s) => s.lr)],
  ];
  if (alpha !== null) series.push(["ar", "α·AR", c.curve.map((s) => alpha * s.ar)]);
  const top = Math.max(...series.flatMap((s) => s[2])) || 1;  // all 0: nothing pruned
  const X = (i) => L + (R - L) * (i / n);
  const Y = (v) => B - (B - T) * (v / top);
  for (const f of [0, 0.5, 1]) {
    el("line", { class: "grid", x1: L, x2: R, y1: Y(f * top), y2: Y(f * top) }, svg);
    el("text", { x: L - 4, y: Y(f * top) + 4, "text-anchor": "end" }, svg).textContent = (f * top).toFixed(2);
  }
  el("line", { class: "axis", x1: L, x2: R, y1: B, y2: B }, svg);
  el("line", { class: "axis", x1: L, x2: L, y1: T, y2: B }, svg);
  for (const [cls, , ys] of series) {
    el("polyline", { class: cls, points: ys.map((v, i) => `${X(i).toFixed(1)},${Y(v).toFixed(1)}`).join(" ") }, svg);
  }
  el("line", { class: "chosen", x1: X(c.chosen_step), x2: X(c.chosen_step), y1: T, y2: B }, svg);
  el("line", { class: "current", x1: X(k.step), x2: X(k.step), y1: T, y2: B, id: "curve-current" }, svg);
  el("text", { x: L, y: B + 14, "text-anchor": "middle" }, svg).textContent = "0";
  el("text", { x: R, y: B + 14, "text-anchor": "middle" }, svg).textContent = String(k.n);
  const left = c.chosen_step <= n / 2;
  el("text", { x: X(c.chosen_step) + (left ? 4 : -4), y: T + 10, "text-anchor": left ? "start" : "end" },
     svg).textContent = `chosen: step ${c.chosen_step}`;
  el("text", { x: (L + R) / 2, y: B + 28, "text-anchor": "middle" }, svg).textContent = "step (branches removed)";
  series.forEach(([cls, name], i) => {
    const x = L + i * 70, y = B + 44;
    el("line", { class: cls, x1: x, x2: x + 16, y1: y - 4, y2: y - 4 }, svg);
    el("text", { x: x + 20, y }, svg).textContent = name;
  });
  const pickStep = (ev) => {
    const box = svg.getBoundingClientRect();
    const sx = ((ev.clientX - box.left) / box.width) * 420;
    setStep(Math.round(((sx - L) / (R - L)) * n));
  };
  svg.onmousedown = (ev) => { pickStep(ev); svg.onmousemove = (e) => e.buttons && pickStep(e); };
}

function clearHover() {
  $("hover-disk").replaceChildren();
  $("hover").textContent = "Hover over the skeleton for its radius.";
}

function drawAll() {
  clearHover();  // what it showed belongs to the step before
  drawRaster();
  drawSkeletons();
  drawNumbers();
  drawCurve();
  $("step").value = state.comps[state.selected].step;
}

function setStep(step) {
  moveTo(state.comps[state.selected], step);
}

// ------------------------------------------------------------------- hover
function hover(ev) {
  if (!state.comps.length) return;
  const svg = $("view");
  const pt = new DOMPoint(ev.clientX, ev.clientY).matrixTransform(svg.getScreenCTM().inverse());
  const u = unit();
  let best = null, bestD = (10 * u) ** 2;
  state.comps.forEach((k, ci) => {
    k.px.forEach(([x, y], i) => {
      if (k.removed[i] <= k.step) return;
      const d = (x - pt.x) ** 2 + (y - pt.y) ** 2;
      if (d < bestD) { bestD = d; best = { k, ci, i }; }
    });
  });
  clearHover();
  const g = $("hover-disk");
  document.querySelectorAll(".branch.hovered").forEach((e) => e.classList.remove("hovered"));
  if (!best) return;
  const { k, ci, i } = best;
  const [x, y, r2] = k.px[i];
  const [wx, wy, wr] = k.world[i];
  el("circle", { class: "disk", cx: x, cy: y, r: Math.sqrt(r2), "stroke-width": 1.5, "vector-effect": "non-scaling-stroke" }, g);
  el("circle", { class: "centre", cx: x, cy: y, r: 2.5 * u }, g);
  let text = `x ${wx}, y ${wy}: radius ${fmt(wr, 3)}`;
  const b = k.owner[i];
  if (b >= 0) {
    const o = ownerAt(k.seq, b, k.step);
    const br = k.seq.branches[o];
    const at = br.removed_at === null ? "never removed" : `removed at step ${br.removed_at}`;
    text += ` — branch ${o}, ${at}`;
    const ans = k.step === k.c.chosen_step ? k.answer.get(`${x},${y}`) : null;
    if (ans) text += `; margin ${ans.margin === null ? "none" : fmt(ans.margin)}`;
    const e = document.querySelector(`.branch[data-component="${ci}"][data-branch="${o}"]`);
    if (e) e.classList.add("hovered");
  } else {
    text += " — junction";
  }
  $("hover").textContent = text;
}

// --------------------------------------------------------------- downloads
async function download(kind) {
  if (!state.input) return;
  const stem = state.input.name.replace(/\.[^.]*$/, "") || "shape";
  let blob;
  if (kind === "json") {
    blob = new Blob([state.text], { type: "application/json" });
  } else {
    const accept = kind === "png" ? "image/png" : "application/geo+json";
    const resp = await post(options(), accept);
    if (!resp.ok) { showProblem(await problemOf(resp)); return; }
    blob = await resp.blob();
  }
  const a = document.createElement("a");
  a.href = URL.createObjectURL(blob);
  a.download = `${stem}.${kind === "json" ? "json" : kind === "png" ? "overlay.png" : "geojson"}`;
  document.body.appendChild(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}

// ------------------------------------------------------------------ wiring
function init() {
  const drop = $("drop");
  $("file").addEventListener("change", (e) => pick(e.target.files[0]));
  for (const t of ["dragenter", "dragover"]) drop.addEventListener(t, (e) => { e.preventDefault(); drop.classList.add("over"); });
  for (const t of ["dragleave", "drop"]) drop.addEventListener(t, () => drop.classList.remove("over"));
  drop.addEventListener("drop", (e) => { e.preventDefault(); pick(e.dataTransfer.files[0]); });
  $("controls").addEventListener("submit", (e) => { e.preventDefault(); run(); });
  for (const id of ["method", "coarse"]) $(id).addEventListener("change", run);
  $("method").addEventListener("change", () => { $("coarse").disabled = $("method").value === "dce"; });
  $("beta").addEventListener("change", run);
  $("step").addEventListener("input", (e) => setStep(Number(e.target.value)));
  $("component").addEventListener("change", (e) => select(Number(e.target.value)));
  $("show-medial").addEventListener("change", drawMedial);
  $("show-margins").addEventListener("change", drawSkeletons);
  $("view").addEventListener("mousemove", hover);
  window.addEventListener("resize", () => state.comps.length && drawSkeletons());
  document.addEventListener("keydown", (e) => {
    if (!state.comps.length || (e.target instanceof Element && e.target.matches("input, select, textarea"))) return;
    const k = state.comps[state.selected];
    const to = { ArrowLeft: k.step - 1, ArrowRight: k.step + 1, Home: 0, End: k.n }[e.key];
    if (to !== undefined) { e.preventDefault(); setStep(to); }
  });
  for (const b of document.querySelectorAll("[data-download]")) b.addEventListener("click", () => download(b.dataset.download));
}

init();
