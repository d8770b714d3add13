// softevo dashboard: runs, one run live (curve, population, diversity, 3D replay), sweeps.
// Plain ES module; uPlot (global) draws the charts, three.js the replay. Everything it shows
// comes from the REST API of the server that serves it. `window.softevo` exposes the chart data
// and the replay's state, so tests (and curious users) can read what is drawn.
import * as THREE from "three";
import { OrbitControls } from "three/addons/OrbitControls.js";

const softevo = (window.softevo = { charts: {}, dots: 0, replay: null, view: null });
const view = document.getElementById("view");
const tokenInput = document.getElementById("token");
tokenInput.value = localStorage.getItem("softevo-token") || "";
tokenInput.addEventListener("change", () => {
  localStorage.setItem("softevo-token", tokenInput.value);
  tokenInput.classList.remove("wanted");
});

let cleanup = [];
function onLeave(fn) { cleanup.push(fn); }

async function api(path, options = {}) {
  const headers = { ...(options.headers || {}) };
  if (options.body) headers["Content-Type"] = "application/json";
  if (tokenInput.value && options.method && options.method !== "GET") {
    headers.Authorization = `Bearer ${tokenInput.value}`;
  }
  const response = await fetch(path, { ...options, headers });
  const body = response.headers.get("content-type")?.includes("json") ? await response.json() : null;
  if (!response.ok) {
    const detail = body?.detail;
    const text = Array.isArray(detail)
      ? detail.map((d) => `${(d.loc || []).slice(1).join(".")}: ${d.msg}`).join("; ")
      : detail || response.statusText;
    if (response.status === 401 || response.status === 403) {
      tokenInput.classList.add("wanted");  // the server wants a token: point at the field
      tokenInput.focus();
    }
    throw new Error(`${response.status}: ${text}`);
  }
  return body;
}

const h = (tag, attrs = {}, ...children) => {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (key.startsWith("on")) node.addEventListener(key.slice(2), value);
    else if (value !== undefined && value !== null && value !== false) node.setAttribute(key, value);
  }
  for (const child of children.flat()) {
    if (child !== null && child !== undefined) node.append(child.nodeType ? child : String(child));
  }
  return node;
};
const fmt = (value, digits = 4) => (value === null || value === undefined ? "–" : Number(value).toFixed(digits));
const box = (shape) => (shape ? shape.join("×") : "–");
const status = (s) => h("span", { class: `status ${s}` }, s);
const progressBar = (done, total) =>
  h("span", {}, h("span", { class: "bar" }, h("i", { style: `width:${(100 * done) / Math.max(1, total)}%` })),
    `${done}/${total}`);

// -- routing ---------------------------------------------------------------------------------------

async function route() {
  for (const fn of cleanup.splice(0)) fn();
  softevo.charts = {};
  softevo.dots = 0;
  const hash = location.hash.replace(/^#/, "") || "/";
  let match;
  try {
    if ((match = hash.match(/^\/runs\/(\d+)$/))) await runView(Number(match[1]));
    else if ((match = hash.match(/^\/sweeps\/(\d+)$/))) await sweepView(Number(match[1]));
    else await runsView();
  } catch (error) {
    view.replaceChildren(h("p", { class: "error" }, String(error.message || error)));
  }
}
window.addEventListener("hashchange", route);

// -- the runs --------------------------------------------------------------------------------------

async function runsView() {
  softevo.view = "runs";
  const presets = await api("/presets");
  const message = h("span", { class: "muted", id: "start-message" });
  const form = h("form", { class: "start", id: "start-form" },
    h("label", {}, "preset", h("select", { name: "preset" },
      presets.map((p) => h("option", { value: p.name, title: p.description }, p.name)))),
    h("label", {}, "bounding box", h("input", { name: "shape", placeholder: "e.g. 5x5x3", size: 8 })),
    h("label", {}, "seed", h("input", { name: "seed", type: "number", value: 1, min: 0 })),
    h("label", {}, "population", h("input", { name: "population", type: "number", min: 2, placeholder: "preset" })),
    h("label", {}, "generations", h("input", { name: "generations", type: "number", min: 1, placeholder: "preset" })),
    h("button", { class: "primary", type: "submit" }, "Start run"), message);
  form.addEventListener("submit", async (event) => {
    event.preventDefault();
    const data = new FormData(form);
    const request = { preset: data.get("preset"), seed: Number(data.get("seed") || 0) };
    const shape = String(data.get("shape") || "").trim();
    if (shape) request.shape = shape.toLowerCase().split("x").map(Number);
    for (const key of ["population", "generations"]) if (data.get(key)) request[key] = Number(data.get(key));
    try {
      const run = await api("/runs", { method: "POST", body: JSON.stringify(request) });
      message.className = "muted";
      message.textContent = `run ${run.id} queued`;
      await refresh();
    } catch (error) {
      message.className = "error";
      message.textContent = error.message;
    }
  });
  const table = h("table", { id: "runs" });
  view.replaceChildren(
    h("div", { class: "panel" }, h("h3", {}, "Start a run"), form),
    h("div", { class: "panel" }, h("h3", {}, "Runs"), table));

  async function refresh() {
    const page = await api("/runs?limit=100");
    table.replaceChildren(
      h("tr", {}, ["run", "status", "progress", "best speed (m/s)", "preset", "box", "seed", "sweep", ""].map((t) => h("th", {}, t))),
      ...page.items.map((run) => h("tr", { "data-run": run.id },
        h("td", {}, h("a", { href: `#/runs/${run.id}` }, `#${run.id}`)),
        h("td", {}, status(run.status)),
        h("td", {}, progressBar(run.progress.generation, run.progress.generations)),
        h("td", { class: "num" }, fmt(run.progress.best_fitness)),
        h("td", {}, run.preset || "–"),
        h("td", {}, box(run.config.shape)),
        h("td", { class: "num" }, run.seed),
        h("td", {}, run.sweep_id ? h("a", { href: `#/sweeps/${run.sweep_id}` }, `sweep ${run.sweep_id}`) : "–"),
        h("td", {}, ["queued", "running"].includes(run.status) ? cancelButton(run.id, refresh) : ""))));
    if (!page.items.length) table.append(h("tr", {}, h("td", { colspan: 9, class: "muted" }, "No runs yet: start one above.")));
  }
  await refresh();
  const timer = setInterval(() => refresh().catch(() => {}), 2000);
  onLeave(() => clearInterval(timer));
}

function cancelButton(runId, after) {
  return h("button", {
    onclick: async (event) => {
      event.target.disabled = true;
      try { await api(`/runs/${runId}/cancel`, { method: "POST" }); }
      catch (error) { alert(error.message); }
      await after();
    },
  }, "Cancel");
}

// -- one run ---------------------------------------------------------------------------------------

// generations are whole numbers: ticks at 1, 2, 5, 10, ... apart, never at 0.5
const GENERATION_AXIS = { label: "generation", incrs: [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000] };

const CURVE_SERIES = [
  { key: "best_so_far", label: "best so far", stroke: "#1d232a", width: 2 },
  { key: "best", label: "best", stroke: "#2f6fb5" },
  { key: "mean", label: "mean", stroke: "#e67e22", dash: [6, 4] },
  { key: "median", label: "median", stroke: "#2e8b57", dash: [2, 3] },
];

function chart(id, title, options, data, parent) {
  const holder = h("div", { class: "panel", id }, h("h3", {}, title));
  parent.append(holder);
  const width = () => Math.max(300, holder.clientWidth - 26);
  const plot = new uPlot({ width: width(), height: 260, ...options }, data, holder);
  // the grid reflows as panels are added and the window resizes: follow the panel's width
  const observer = new ResizeObserver(() => {
    if (Math.abs(plot.width - width()) > 1) plot.setSize({ width: width(), height: plot.height });
  });
  observer.observe(holder);
  onLeave(() => observer.disconnect());
  softevo.charts[id] = plot;
  return plot;
}

async function runView(runId) {
  softevo.view = "run";
  softevo.replay = softevo.dots = softevo.failedDots = null;  // nothing of the last view's
  let run = await api(`/runs/${runId}`);
  const population = run.config.population;
  const summary = h("div", { id: "summary" });
  const charts = h("div", { class: "grid" });
  const replayPanel = h("div", { class: "panel", id: "replay" });
  const settings = h("pre", { class: "settings" }, JSON.stringify(run.config, null, 2));
  view.replaceChildren(
    h("h2", {}, `Run #${runId}`, " ", h("span", { class: "muted" }, `${run.preset || "custom"}, ${box(run.config.shape)}, seed ${run.seed}`)),
    summary, charts,
    h("div", { class: "grid" }, replayPanel,
      h("div", { class: "panel" }, h("h3", {}, "Settings"), settings)));

  const showSummary = () => summary.replaceChildren(h("div", { class: "panel" },
    status(run.status), " ", progressBar(run.progress.generation, run.progress.generations),
    ` best ${fmt(run.progress.best_fitness)} m/s`,
    run.progress.best_generation !== null ? ` (generation ${run.progress.best_generation})` : "",
    `, ${run.progress.evaluations} simulations, ${run.progress.saved} from the cache`,
    run.progress.eta_seconds ? `, about ${Math.round(run.progress.eta_seconds)} s left` : "",
    run.error ? h("div", { class: "error" }, run.error) : "",
    " ", ["queued", "running"].includes(run.status) ? cancelButton(runId, async () => { run = await api(`/runs/${runId}`); showSummary(); }) : "",
    h("div", { class: "links" },
      h("a", { href: `/runs/${runId}/curve?format=csv` }, "curve (CSV)"),
      h("a", { href: `/runs/${runId}/best` }, "best robot file"),
      h("a", { href: `/runs/${runId}/figures/curve.png` }, "curve (PNG)"),
      h("a", { href: `/runs/${runId}/figures/population.png` }, "population (PNG)"),
      h("a", { href: `/runs/${runId}/figures/diversity.png` }, "diversity (PNG)"),
      run.sweep_id ? h("a", { href: `#/sweeps/${run.sweep_id}` }, `sweep ${run.sweep_id}`) : "")));
  showSummary();

  // the data the charts draw, grown generation by generation
  let curve = (await api(`/runs/${runId}/curve`)).generations;
  const individuals = [];
  // committed generations only, in pages of 5000 in (generation, index) order: a long run opens
  // in a few requests, not one per generation
  async function loadGenerations() {
    const committed = curve.length ? curve[curve.length - 1].generation : -1;
    while (individuals.length < (committed + 1) * population) {
      const page = await api(`/runs/${runId}/individuals?offset=${individuals.length}&limit=5000`);
      const items = page.items.filter((item) => item.generation <= committed);
      individuals.push(...items);
      if (items.length < page.items.length || page.items.length === 0) break;
    }
  }
  await loadGenerations();

  const curveData = () => [curve.map((r) => r.generation), ...CURVE_SERIES.map((s) => curve.map((r) => r[s.key]))];
  const curvePlot = chart("curve", "Learning curve (m/s)", {
    scales: { x: { time: false } },
    axes: [GENERATION_AXIS, { label: "speed (m/s)", size: 60 }],
    series: [{ label: "generation" }, ...CURVE_SERIES.map((s) => ({ label: s.label, stroke: s.stroke, width: s.width || 1.5, dash: s.dash }))],
  }, curveData(), charts);

  // population dot plot: x = generation, spread a little by index; failed ones in red at 0
  const dotData = () => {
    const x = [], ok = [], failed = [];
    for (const item of individuals) {
      x.push(item.generation + (item.index / population - 0.5) * 0.7);
      ok.push(item.fitness === null ? null : item.fitness);
      // failed: no speed, whether simulated in this generation or reused from the cache
      failed.push(item.fitness === null ? 0 : null);
    }
    softevo.dots = individuals.length;
    softevo.failedDots = individuals.filter((i) => i.fitness === null).length;
    return [x, ok, failed];
  };
  const dotPlot = chart("population", "Population: every individual (click one to replay it)", {
    scales: { x: { time: false, range: (u, min, max) => [Math.round(min) - 0.6, Math.round(max) + 0.6] } },
    cursor: { drag: { x: false, y: false } },
    axes: [GENERATION_AXIS, { label: "speed (m/s)", size: 60 }],
    series: [{ label: "generation", value: (u, v) => (v === null ? "–" : Math.round(v)) },
      { label: "speed", stroke: "#2f6fb5", paths: () => null, points: { show: true, size: 4, fill: "#2f6fb5" } },
      { label: "failed", stroke: "#c0392b", paths: () => null, points: { show: true, size: 6, fill: "#c0392b" } }],
  }, dotData(), charts);
  // capture phase on the root: uPlot stops the click's propagation on its plotting area
  dotPlot.root.addEventListener("click", (event) => {
    const rect = dotPlot.over.getBoundingClientRect();
    const px = event.clientX - rect.left, py = event.clientY - rect.top;
    let best = null, bestDistance = 12 * 12;
    dotPlot.data[0].forEach((xv, i) => {
      const yv = dotPlot.data[1][i] ?? dotPlot.data[2][i];
      if (yv === null || yv === undefined) return;
      const dx = dotPlot.valToPos(xv, "x") - px, dy = dotPlot.valToPos(yv, "y") - py;
      if (dx * dx + dy * dy < bestDistance) { bestDistance = dx * dx + dy * dy; best = individuals[i]; }
    });
    if (!best) return;
    replay.best = null;  // a picked individual stays on screen while the run goes on
    replay.load(`/runs/${runId}/individuals/${best.id}/replay`,
      () => `individual ${best.id} (generation ${best.generation}, ${best.operator}, ${best.fitness === null ? "failed" : `${fmt(best.fitness)} m/s`})`)
      .catch((error) => replayPanel.append(h("p", { class: "error" }, error.message)));
  }, true);

  const diversityPlot = chart("diversity", "Diversity", {
    scales: { x: { time: false }, y: { range: (u, min, max) => [0, Math.max(max, 0.01)] } },
    axes: [GENERATION_AXIS, { label: "diversity", size: 60 }],
    series: [{ label: "generation" }, { label: "diversity", stroke: "#8e44ad", width: 1.5 }],
  }, [curve.map((r) => r.generation), curve.map((r) => r.diversity)], charts);

  const replay = new Replay(replayPanel);
  onLeave(() => replay.dispose());
  const showBest = async () => {
    const label = ["completed", "failed", "cancelled"].includes(run.status) ? "the fastest robot" : "the fastest robot so far";
    // named from the replay itself: a better robot may have been committed since `run` was read
    const data = await replay.load(`/runs/${runId}/best/replay`, (d) => `${label} (generation ${d.generation})`);
    replay.best = data.generation;
  };
  if (run.progress.best_fitness !== null) {
    await showBest();
  } else {
    replayPanel.append(h("p", { class: "muted" }, "The replay appears once a generation is done."));
  }

  // live: one server-sent event per committed generation, then `end`
  if (!["completed", "failed", "cancelled"].includes(run.status)) {
    const events = new EventSource(`/runs/${runId}/events`);
    onLeave(() => events.close());
    const update = async () => {
      run = await api(`/runs/${runId}`);
      curve = (await api(`/runs/${runId}/curve`)).generations;
      await loadGenerations();
      curvePlot.setData(curveData());
      dotPlot.setData(dotData());
      diversityPlot.setData([curve.map((r) => r.generation), curve.map((r) => r.diversity)]);
      showSummary();
      // follow the fastest robot as it changes, unless the user picked an individual
      const stale = !replay.loaded || (replay.best !== null && replay.best !== run.progress.best_generation);
      if (stale && run.progress.best_fitness !== null) {
        replayPanel.querySelector("p.muted")?.remove();
        await showBest();
      }
    };
    // events come in bursts (a reconnect replays every generation): redraw at most twice a second
    let dirty = false, busy = false;
    const timer = setInterval(async () => {
      if (!dirty || busy) return;
      dirty = false;
      busy = true;
      try { await update(); } catch (error) { /* the next event retries */ }
      busy = false;
    }, 500);
    onLeave(() => clearInterval(timer));
    const queue = () => { dirty = true; };
    events.addEventListener("generation", queue);
    events.addEventListener("status", queue);
    events.addEventListener("end", () => { events.close(); queue(); });
  }
}

// -- the 3D replay ---------------------------------------------------------------------------------

const PASSIVE_SOFT = new THREE.Color("#9bc59d"), PASSIVE_HARD = new THREE.Color("#4a4f55");
const IN_PHASE = new THREE.Color("#d1495b"), ANTI_PHASE = new THREE.Color("#2f6fb5");

class Replay {
  constructor(panel) {
    this.panel = panel;
    this.loaded = false;
    this.best = null;  // the generation of the best robot shown, null for a picked individual
    this.state = { frame: 0, frames: 0, time: 0, playing: false, speed: 1, renderer: null, label: "" };
    softevo.replay = this.state;
  }

  async load(url, label) {
    const data = await api(`${url}?fps=30`);
    this.data = data;
    this.loaded = true;
    this.build(label(data));
    return data;
  }

  build(label) {
    const data = this.data;
    this.dispose();
    const title = h("h3", {}, "Replay: ", label, data.speed !== null ? ` · ${fmt(data.speed)} m/s` : " · unstable");
    const holder = h("div", { id: "replay-canvas" });
    const play = h("button", { id: "replay-play" }, "Pause");
    const slider = h("input", { type: "range", min: 0, max: data.frames.length - 1, value: 0, id: "replay-slider" });
    const speed = h("select", { id: "replay-speed" }, [0.25, 0.5, 1, 2, 4].map((s) => h("option", { value: s, selected: s === 1 }, `${s}×`)));
    const clock = h("span", { class: "muted", id: "replay-clock" }, "0.00 s");
    const legend = h("div", { class: "muted" },
      "springs:", h("span", { class: "legend-swatch", style: "background:#9bc59d" }), "soft",
      h("span", { class: "legend-swatch", style: "background:#4a4f55" }), "hard",
      h("span", { class: "legend-swatch", style: "background:#d1495b" }), "actuated (sine)",
      h("span", { class: "legend-swatch", style: "background:#2f6fb5" }), "actuated (anti-phase)");
    this.panel.replaceChildren(title, holder, h("div", { class: "controls" }, play, slider, speed, clock), legend);

    const state = this.state;
    Object.assign(state, { frame: 0, frames: data.frames.length, time: 0, playing: true, label });
    const fps = (data.frames.length - 1) / Math.max(1e-9, data.times[data.times.length - 1]);
    play.onclick = () => { state.playing = !state.playing; play.textContent = state.playing ? "Pause" : "Play"; };
    slider.oninput = () => { state.time = data.times[Number(slider.value)]; state.playing = false; play.textContent = "Play"; };
    speed.onchange = () => { state.speed = Number(speed.value); };

    let renderer;
    try {
      renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
      state.renderer = "webgl";
    } catch (error) {
      state.renderer = null;
      holder.append(h("p", { class: "error" }, "This browser cannot draw WebGL: ", String(error.message || error)));
    }
    const masses = data.frames[0].length;
    const springs = data.springs;
    const scene = new THREE.Scene();
    scene.background = new THREE.Color("#f4f6f8");
    const camera = new THREE.PerspectiveCamera(40, 16 / 9, 0.05, 500);
    camera.up.set(0, 0, 1);
    const grid = new THREE.GridHelper(60, 60, 0x8d98a3, 0xbfc7cf);
    grid.rotation.x = Math.PI / 2;
    const ground = new THREE.Mesh(new THREE.PlaneGeometry(60, 60), new THREE.MeshBasicMaterial({ color: "#e3e8ed" }));
    ground.position.z = -0.002;  // the ground (z = 0) under the grid lines
    scene.background = new THREE.Color("#fbfcfd");
    scene.add(ground, grid, new THREE.AmbientLight(0xffffff, 1.2));
    const geometry = new THREE.BufferGeometry();
    const positions = new Float32Array(springs.length * 6);
    const colours = new Float32Array(springs.length * 6);
    const stiffness = data.stiffness, low = Math.min(...stiffness), high = Math.max(...stiffness);
    springs.forEach((_, s) => {
      const phase = data.phase ? data.phase[s] : null;
      let colour;
      if (phase !== null && phase !== undefined) colour = Math.cos(phase) >= 0 ? IN_PHASE : ANTI_PHASE;
      else colour = PASSIVE_SOFT.clone().lerp(PASSIVE_HARD, high > low ? (stiffness[s] - low) / (high - low) : 1);
      colours.set([colour.r, colour.g, colour.b, colour.r, colour.g, colour.b], s * 6);
    });
    geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
    geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
    scene.add(new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true })));
    const dots = new THREE.InstancedMesh(new THREE.SphereGeometry(0.06, 8, 6), new THREE.MeshBasicMaterial({ color: "#1d232a" }), masses);
    scene.add(dots);
    const matrix = new THREE.Matrix4();
    let controls = null;
    if (renderer) {
      holder.append(renderer.domElement);
      controls = new OrbitControls(camera, renderer.domElement);
    }
    const first = data.frames[0];
    const centre = (frame) => frame.reduce((acc, p) => [acc[0] + p[0] / masses, acc[1] + p[1] / masses, acc[2] + p[2] / masses], [0, 0, 0]);
    const c0 = centre(first);
    // stand back in proportion to the robot's size, so a big box fits the view too
    const extent = Math.max(...[0, 1, 2].map((k) => Math.max(...first.map((p) => p[k])) - Math.min(...first.map((p) => p[k]))));
    const away = 1.2 * Math.max(1, extent / 2.5);
    camera.position.set(c0[0] - 3 * away, c0[1] - 6 * away, c0[2] + 3.5 * away);
    controls?.target.set(...c0);

    const draw = (frame) => {
      const points = data.frames[frame];
      springs.forEach(([a, b], s) => positions.set([...points[a], ...points[b]], s * 6));
      geometry.attributes.position.needsUpdate = true;
      points.forEach((p, m) => { matrix.makeTranslation(p[0], p[1], p[2]); dots.setMatrixAt(m, matrix); });
      dots.instanceMatrix.needsUpdate = true;
      const c = centre(points);  // follow the robot: move camera and target with its centre
      if (controls) {
        const shift = new THREE.Vector3(c[0], c[1], 0).sub(new THREE.Vector3(controls.target.x, controls.target.y, 0));
        controls.target.add(shift);
        camera.position.add(shift);
        controls.update();
      }
      if (renderer) {
        const width = holder.clientWidth || 600;
        if (renderer.domElement.width !== Math.floor(width * devicePixelRatio)) {
          renderer.setPixelRatio(devicePixelRatio);
          renderer.setSize(width, 380, false);
          camera.aspect = width / 380;
          camera.updateProjectionMatrix();
        }
        renderer.render(scene, camera);
      }
    };
    let last = performance.now();
    const loop = (now) => {
      const elapsed = Math.max(0, (now - last) / 1000);  // rAF's clock may start before `last`
      last = now;
      const end = data.times[data.times.length - 1];
      if (state.playing) state.time = (state.time + elapsed * state.speed) % Math.max(end, 1e-9);
      const frame = Math.max(0, Math.min(data.frames.length - 1, Math.round(state.time * fps)));
      if (frame !== state.frame || !state.drawn) {
        state.frame = frame;
        state.drawn = true;
        draw(frame);
        slider.value = frame;
        clock.textContent = `${data.times[frame].toFixed(2)} s`;
      }
      this.raf = requestAnimationFrame(loop);
    };
    this.raf = requestAnimationFrame(loop);
    this.disposers = [() => cancelAnimationFrame(this.raf), () => controls?.dispose(), () => renderer?.dispose()];
  }

  dispose() {
    for (const fn of this.disposers || []) fn();
    this.disposers = [];
  }
}

// -- a sweep ---------------------------------------------------------------------------------------

async function sweepView(sweepId) {
  softevo.view = "sweep";
  const sweep = await api(`/sweeps/${sweepId}`);
  const boxes = sweep.boxes;
  const table = h("table", {},
    h("tr", {}, ["box", "runs", "completed", "best mean (m/s)", "spread (std)", "min", "max"].map((t) => h("th", {}, t))),
    boxes.map((b) => h("tr", {}, h("td", {}, box(b.shape)),
      h("td", {}, b.run_ids.map((id) => h("a", { href: `#/runs/${id}`, style: "margin-right:.4rem" }, `#${id}`))),
      h("td", { class: "num" }, `${b.completed}/${b.run_ids.length}`),
      h("td", { class: "num" }, fmt(b.best_mean)), h("td", { class: "num" }, fmt(b.best_std)),
      h("td", { class: "num" }, fmt(b.best_min)), h("td", { class: "num" }, fmt(b.best_max)))));
  const charts = h("div", { class: "grid" });
  view.replaceChildren(h("h2", {}, `Sweep ${sweepId} `, status(sweep.status)),
    h("div", { class: "panel" }, table), charts);

  // Figure 4(a): best speed per box, the mean as a bar, the best and worst seed as dots
  const x = boxes.map((_, i) => i);
  const bars = uPlot.paths.bars({ size: [0.6, 60] });
  chart("boxes", "Best speed per bounding box (bars: mean over seeds; dots: best and worst seed)", {
    scales: { x: { time: false, range: [-0.6, boxes.length - 0.4] }, y: { range: (u, min, max) => [0, Math.max(max * 1.1, 0.01)] } },
    axes: [{ label: "bounding box", values: (u, ticks) => ticks.map((t) => (Number.isInteger(t) && boxes[t] ? box(boxes[t].shape) : "")), splits: () => x },
      { label: "speed (m/s)", size: 60 }],
    series: [{ label: "box" },
      { label: "mean", fill: "rgba(47,111,181,0.55)", stroke: "#2f6fb5", paths: bars, points: { show: false } },
      { label: "max", stroke: "#1d232a", paths: () => null, points: { show: true, size: 6 } },
      { label: "min", stroke: "#66707a", paths: () => null, points: { show: true, size: 6 } }],
  }, [x, boxes.map((b) => b.best_mean), boxes.map((b) => b.best_max), boxes.map((b) => b.best_min)], charts);

  // the boxes' learning curves side by side: best so far of every seed
  for (const b of boxes) {
    const curves = await Promise.all(b.run_ids.map((id) => api(`/runs/${id}/curve`)));
    const length = Math.max(1, ...curves.map((c) => c.generations.length));
    const gens = Array.from({ length }, (_, i) => i);
    chart(`box-${box(b.shape)}`, `${box(b.shape)}: best so far per seed`, {
      height: 200,
      scales: { x: { time: false } },
      axes: [GENERATION_AXIS, { label: "m/s", size: 55 }],
      series: [{ label: "generation" }, ...curves.map((c, i) => ({ label: `run #${b.run_ids[i]}`, stroke: ["#2f6fb5", "#e67e22", "#2e8b57", "#8e44ad", "#c0392b"][i % 5], width: 1.5 }))],
    }, [gens, ...curves.map((c) => gens.map((g) => c.generations[g]?.best_so_far ?? null))], charts);
  }
}

route();
