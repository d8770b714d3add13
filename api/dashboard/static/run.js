// One run, live: its curve, population dot plot, diversity and the 3D replay of the best robot.
import { CURVE_SERIES, GENERATION_AXIS, api, box, chart, duration, fmt, h, objective, onLeave, progressBar, softevo, status, terrainText, view } from "./api.js";
import { ArchiveMap } from "./archive.js";
import { frontPanel, hypervolumeChart } from "./front.js";
import { Replay } from "./replay.js";
import { cancelButton } from "./runs.js";
import { measureLabel } from "./units.js";

const FINISHED = ["completed", "failed", "cancelled"];

// The run's page: `page` holds what its parts share (the run as last read, its curve and
// individuals so far, the panels and plots), each part built by one function below.
export async function runView(runId) {
  softevo.view = "run";
  softevo.replay = softevo.dots = softevo.failedDots = null;  // nothing of the last view's
  const run = await api(`/runs/${runId}`);
  const page = { runId, run, population: run.config.population, fitness: objective(run.config), individuals: [] };
  layout(page);
  page.showSummary = summaryPanel(page);
  page.showSummary();

  // the data the charts draw, grown generation by generation
  page.curve = (await api(`/runs/${runId}/curve`)).generations;
  await loadGenerations(page);
  curveChart(page);
  dotChart(page);
  diversityChart(page);
  page.replay = new Replay(page.replayPanel);
  onLeave(() => page.replay.dispose());
  qualityDiversity(page);
  if (page.archive) await page.archive.update();
  page.front = frontPanel(page.run, page.charts, page.replay, () => page.individuals);
  if (page.front) await page.front.update();
  page.hypervolume = hypervolumeChart(page.run, page.curve, page.charts);
  if (page.run.progress.best_fitness !== null) {
    await showBest(page);
  } else {
    page.replayPanel.append(h("p", { class: "muted" }, "The replay appears once a generation is done."));
  }
  if (!FINISHED.includes(page.run.status)) followLive(page);
}

// The page's frame: title, task, the summary and chart panels, the replay and the settings.
function layout(page) {
  const { run, runId } = page;
  page.summary = h("div", { id: "summary" });
  page.charts = h("div", { class: "grid" });
  page.replayPanel = h("div", { class: "panel", id: "replay" });
  const settings = h("pre", { class: "settings" }, JSON.stringify(run.config, null, 2));
  view.replaceChildren(
    h("h2", {}, `Run #${runId}`, " ", h("span", { class: "muted" },
      `${run.preset || "custom"}, ${run.config.algorithm || "ga"}, ${run.config.encoding || "voxel"}, ${box(run.config.shape)}, seed ${run.seed}`)),
    h("p", { class: "muted", id: "task" }, taskLine(run.config, page.fitness)),
    page.summary, page.charts,
    h("div", { class: "grid" }, page.replayPanel,
      h("div", { class: "panel" }, h("h3", {}, "Settings"), settings)));
}

// What the run is after: its terrain and either its objectives (the curve and the dot plot show
// the fitness beside them) or its fitness, with a quality-diversity run's descriptors.
function taskLine(config, fitness) {
  const terrain = `task: ${terrainText(config)} terrain`;
  const objectives = config.objectives || [];
  const goal = (o) => `${measureLabel(o.measure)}, ${o.goal === "max" ? "higher" : "lower"} is better`;
  if (objectives.length) return `${terrain}, objectives: ${objectives.map(goal).join("; ")} (curve and dots: ${fitness.label})`;
  const descriptors = config.descriptors || [];
  return `${terrain}, fitness = ${fitness.label}` + (descriptors.length ? `, descriptors: ${descriptors.join(", ")}` : "");
}

// The summary line, its error and links; returns the function that shows `page.run` in it.
function summaryPanel(page) {
  const { runId } = page;
  // built once: only the text changes, so the Cancel button stays put (and clickable) while
  // the run reports a generation every fraction of a second
  const summaryText = h("span", {});
  const summaryError = h("div", { class: "error" });
  const cancel = cancelButton(runId, async () => { page.run = await api(`/runs/${runId}`); page.showSummary(); });
  page.summary.replaceChildren(h("div", { class: "panel" }, cancel, " ", summaryText, summaryError,
    h("div", { class: "links" },
      h("a", { href: `/runs/${runId}/curve?format=csv` }, "curve (CSV)"),
      h("a", { href: `/runs/${runId}/best` }, "best robot file"),
      h("a", { href: `/runs/${runId}/figures/curve.png` }, "curve (PNG)"),
      h("a", { href: `/runs/${runId}/figures/population.png` }, "population (PNG)"),
      h("a", { href: `/runs/${runId}/figures/diversity.png` }, "diversity (PNG)"),
      page.run.sweep_id ? h("a", { href: `#/sweeps/${page.run.sweep_id}` }, `sweep ${page.run.sweep_id}`) : "")));
  return () => {
    const run = page.run;
    softevo.run = run;  // what the summary shows, for tests and curious users
    const finished = !["queued", "running"].includes(run.status);
    const wall = duration(run.started_at, finished ? run.finished_at : new Date().toISOString());
    summaryText.replaceChildren(
      status(run.status), " ", progressBar(run.progress.generation, run.progress.generations),
      ` best ${fmt(run.progress.best_fitness)} ${page.fitness.unit}`,
      run.progress.best_generation !== null ? ` (generation ${run.progress.best_generation})` : "",
      `, ${run.progress.evaluations} simulations, ${run.progress.saved} from the cache`,
      run.progress.eta_seconds ? `, about ${Math.round(run.progress.eta_seconds)} s left` : "",
      wall ? h("span", { id: "wall-time" }, `, ${finished ? "wall time" : "running for"} ${wall}`) : "");
    summaryError.textContent = run.error || "";
    summaryError.hidden = !run.error;
    cancel.hidden = !["queued", "running"].includes(run.status);
  };
}

// Committed generations only, in pages of 5000 in (generation, index) order: a long run opens
// in a few requests, not one per generation.
async function loadGenerations(page) {
  const { curve, individuals } = page;
  const committed = curve.length ? curve[curve.length - 1].generation : -1;
  while (individuals.length < (committed + 1) * page.population) {
    const found = await api(`/runs/${page.runId}/individuals?offset=${individuals.length}&limit=5000`);
    const items = found.items.filter((item) => item.generation <= committed);
    individuals.push(...items);
    if (items.length < found.items.length || found.items.length === 0) break;
  }
}

const curveData = (page) => [page.curve.map((r) => r.generation), ...CURVE_SERIES.map((s) => page.curve.map((r) => r[s.key]))];
const diversityData = (page) => [page.curve.map((r) => r.generation), page.curve.map((r) => r.diversity)];
const qdData = (page, key) => [page.curve.map((r) => r.generation), page.curve.map((r) => r[key] ?? null)];

function curveChart(page) {
  const label = page.fitness.label;
  page.curvePlot = chart("curve", `Learning curve: ${label}`, {
    scales: { x: { time: false } },
    axes: [GENERATION_AXIS, { label, size: 60 }],
    series: [{ label: "generation" }, ...CURVE_SERIES.map((s) => ({ label: s.label, stroke: s.stroke, width: s.width || 1.5, dash: s.dash }))],
  }, curveData(page), page.charts);
}

// The population dot plot's data: x = generation, spread a little by index; failed ones in red at 0.
function dotData(page) {
  const x = [], ok = [], failed = [];
  for (const item of page.individuals) {
    x.push(item.generation + (item.index / page.population - 0.5) * 0.7);
    ok.push(item.fitness === null ? null : item.fitness);
    // failed: no speed, whether simulated in this generation or reused from the cache
    failed.push(item.fitness === null ? 0 : null);
  }
  softevo.dots = page.individuals.length;
  softevo.failedDots = page.individuals.filter((i) => i.fitness === null).length;
  return [x, ok, failed];
}

function dotChart(page) {
  const { fitness } = page;
  const dotPlot = chart("population", "Population: every individual (click one to replay it)", {
    scales: { x: { time: false, range: (u, min, max) => [Math.round(min) - 0.6, Math.round(max) + 0.6] } },
    cursor: { drag: { x: false, y: false } },
    axes: [GENERATION_AXIS, { label: fitness.label, size: 60 }],
    series: [{ label: "generation", value: (u, v) => (v === null ? "–" : Math.round(v)) },
      { label: fitness.name, stroke: "#2f6fb5", paths: () => null, points: { show: true, size: 4, fill: "#2f6fb5" },
        value: (u, v) => (v === null || v === undefined ? "–" : v.toFixed(3)) },
      // not the hovered robot's 0 or nothing: how many failed of all drawn, always readable
      { label: "failed", stroke: "#c0392b", paths: () => null, points: { show: true, size: 6, fill: "#c0392b" },
        value: () => `${softevo.failedDots ?? 0} of ${softevo.dots ?? 0}` }],
  }, dotData(page), page.charts);
  // capture phase on the root: uPlot stops the click's propagation on its plotting area
  dotPlot.root.addEventListener("click", (event) => replayClicked(page, event), true);
  page.dotPlot = dotPlot;
}

// A click on the dot plot replays the individual nearest to it (within 12 pixels).
function replayClicked(page, event) {
  const { dotPlot, fitness, replay, runId } = page;
  const rect = dotPlot.over.getBoundingClientRect();
  const px = event.clientX - rect.left, py = event.clientY - rect.top;
  let best = null, bestDistance = 12 * 12;
  dotPlot.data[0].forEach((xv, i) => {
    const yv = dotPlot.data[1][i] ?? dotPlot.data[2][i];
    if (yv === null || yv === undefined) return;
    const dx = dotPlot.valToPos(xv, "x") - px, dy = dotPlot.valToPos(yv, "y") - py;
    if (dx * dx + dy * dy < bestDistance) { bestDistance = dx * dx + dy * dy; best = page.individuals[i]; }
  });
  if (!best) return;
  replay.pick(`/runs/${runId}/individuals/${best.id}/replay`,
    () => `individual ${best.id} (generation ${best.generation}, ${best.operator}, ${best.fitness === null ? "failed" : `${fmt(best.fitness)} ${fitness.unit}`})`);
}

function diversityChart(page) {
  page.diversityPlot = chart("diversity", "Diversity", {
    scales: { x: { time: false }, y: { range: (u, min, max) => [0, Math.max(max, 0.01)] } },
    axes: [GENERATION_AXIS, { label: "diversity", size: 60 }],
    series: [{ label: "generation" }, { label: "diversity", stroke: "#8e44ad", width: 1.5 }],
  }, diversityData(page), page.charts);
}

// Quality-diversity: the archive's heat map, and coverage and QD-score beside the curve.
function qualityDiversity(page) {
  const { charts, fitness, runId } = page;
  const qd = page.run.config.descriptors && page.run.config.descriptors.length > 0;
  page.qdCharts = qd ? [["coverage", "Archive coverage (filled fraction of the cells)", "#16a085"],
    ["qd_score", `QD-score (sum of the elites' ${fitness.name})`, "#c0392b"]].map(([key, title, stroke]) => [key, chart(key, title, {
    scales: { x: { time: false } }, axes: [GENERATION_AXIS, { label: key, size: 60 }],
    series: [{ label: "generation" }, { label: key, stroke, width: 1.5 }],
  }, qdData(page, key), charts)]) : [];
  page.archive = qd ? new ArchiveMap(charts, runId, fitness, (cell) => {
    page.replay.pick(`/runs/${runId}/individuals/${cell.id}/replay`,
      () => `elite of cell ${cell.cell.join(", ")} (generation ${cell.generation}, index ${cell.index})`);
  }) : null;
}

// The best robot's replay, shown with the summary in one step: if a better robot was committed
// while the replay was fetched (the run is read again to know), the replay says so and the
// next update fetches the new one.
async function showBest(page) {
  const { replay, runId } = page;
  const data = await replay.fetch(`/runs/${runId}/best/replay`);
  if (data.generation !== page.run.progress.best_generation) page.run = await api(`/runs/${runId}`);
  const label = FINISHED.includes(page.run.status) ? "the fastest robot" : "the fastest robot so far";
  const newer = page.run.progress.best_generation;
  const behind = newer !== null && newer > data.generation ? `; a better one, of generation ${newer}, is loading` : "";
  if (!replay.show(data, `${label} (generation ${data.generation}${behind})`)) return;
  replay.best = data.generation;
  page.showSummary();
}

// Live: one server-sent event per committed generation, then `end`.
function followLive(page) {
  const events = new EventSource(`/runs/${page.runId}/events`);
  onLeave(() => events.close());
  // events come in bursts (a reconnect replays every generation): redraw at most twice a second
  let dirty = false, busy = false;
  const timer = setInterval(async () => {
    if (!dirty || busy) return;
    dirty = false;
    busy = true;
    try { await update(page); } catch (error) { /* the next event retries */ }
    busy = false;
  }, 500);
  onLeave(() => clearInterval(timer));
  const queue = () => { dirty = true; };
  events.addEventListener("generation", queue);
  events.addEventListener("status", queue);
  events.addEventListener("end", () => { events.close(); queue(); });
}

// One redraw: the run, its curve and new generations read again, every plot given them.
async function update(page) {
  const { replay, runId } = page;
  page.run = await api(`/runs/${runId}`);
  page.curve = (await api(`/runs/${runId}/curve`)).generations;
  await loadGenerations(page);
  page.curvePlot.setData(curveData(page));
  page.dotPlot.setData(dotData(page));
  page.diversityPlot.setData(diversityData(page));
  for (const [key, plot] of page.qdCharts) plot.setData(qdData(page, key));
  if (page.hypervolume) page.hypervolume.show(page.curve);
  if (page.archive) await page.archive.update();
  if (page.front) await page.front.update();
  // follow the fastest robot as it changes, unless the user picked an individual; the
  // summary's best changes with the replay's, never before it
  const following = replay.best !== null;
  const relabel = following && !["queued", "running"].includes(page.run.status) && replay.state.label.includes("so far");
  const stale = (!replay.loaded && !replay.picked) || relabel || (following && replay.best !== page.run.progress.best_generation);
  if (stale && page.run.progress.best_fitness !== null) {
    page.replayPanel.querySelector("p.muted")?.remove();
    await showBest(page);
  } else page.showSummary();
}
