// A sweep: best fitness per bounding box or task (the paper's Figure 4a) and their learning curves,
// one line per seed; followed live (every 2 s) until its runs are done.
import { GENERATION_AXIS, api, box, chart, fmt, h, objective, onLeave, softevo, status, view } from "./api.js";

const COLOURS = ["#2f6fb5", "#e67e22", "#2e8b57", "#8e44ad", "#c0392b"];
const ACTIVE = ["queued", "running"];

// The sweep's page: `page` holds what its parts share (the sweep as last read, the runs' seeds,
// the panels and plots), each part built by one function below.
export async function sweepView(sweepId) {
  softevo.view = "sweep";
  const sweep = await api(`/sweeps/${sweepId}`);
  const byTask = sweep.boxes.some((b) => b.task);
  const page = { sweepId, sweep, boxes: sweep.boxes, byTask, seeds: {},
    unit: byTask ? "m/s, each task's objective" : objective(sweep.request).unit };
  // every run's seed: the curves are named by it (the box or task is the chart's title)
  await Promise.all(page.boxes.flatMap((b) => b.run_ids).map(async (id) => { page.seeds[id] = (await api(`/runs/${id}`)).seed; }));
  // for tests: the status when opened, updates drawn, whether it is still being followed
  softevo.sweep = { seeds: page.seeds, labels: {}, opened: sweep.status, updates: 0, following: ACTIVE.includes(sweep.status) };

  page.title = h("h2", {});
  page.table = h("table", { id: "sweep-boxes" });
  page.charts = h("div", { class: "grid" });
  view.replaceChildren(page.title, h("div", { class: "panel" }, page.table), page.charts);
  showTable(page);
  barChart(page);
  await curveCharts(page);
  if (ACTIVE.includes(sweep.status)) followSweep(page);
}

const boxName = (b) => (b.task ? `${b.task} ${box(b.shape)}` : box(b.shape));

// The table: one row per box or task, its runs (seed), completed, and the best's statistics.
function showTable(page) {
  const { sweep, seeds } = page;
  page.title.replaceChildren(`Sweep ${page.sweepId} `, status(sweep.status));
  page.table.replaceChildren(
    h("tr", {}, [page.byTask ? "task" : "box", "runs (seed)", "completed", `best mean (${page.unit})`, "spread (std)", "min", "max"].map((t) => h("th", {}, t))),
    ...sweep.boxes.map((b) => h("tr", {}, h("td", {}, boxName(b)),
      h("td", {}, b.run_ids.map((id, i) => h("a", { href: `#/runs/${id}`, title: b.statuses[i], style: "margin-right:.4rem" }, `#${id} (${seeds[id]})`))),
      h("td", { class: "num" }, `${b.completed}/${b.run_ids.length}`),
      h("td", { class: "num" }, fmt(b.best_mean)), h("td", { class: "num" }, fmt(b.best_std)),
      h("td", { class: "num" }, fmt(b.best_min)), h("td", { class: "num" }, fmt(b.best_max)))));
}

const barData = (page) => [page.boxes.map((_, i) => i), page.sweep.boxes.map((b) => b.best_mean),
  page.sweep.boxes.map((b) => b.best_max), page.sweep.boxes.map((b) => b.best_min)];

// Figure 4(a): best speed per box, the mean as a bar, the best and worst seed as dots.
function barChart(page) {
  const { boxes, byTask } = page;
  const x = boxes.map((_, i) => i);
  const bars = uPlot.paths.bars({ size: [0.6, 60] });
  page.barPlot = chart("boxes", `Best fitness per ${byTask ? "task" : "bounding box"} (bars: mean over seeds; dots: best and worst seed)`, {
    scales: { x: { time: false, range: [-0.6, boxes.length - 0.4] }, y: { range: (u, min, max) => [Math.min(0, (min ?? 0) * 1.1), Math.max((max ?? 0) * 1.1, 0.01)] } },
    axes: [{ label: byTask ? "task" : "bounding box", values: (u, ticks) => ticks.map((t) => (Number.isInteger(t) && boxes[t] ? boxName(boxes[t]) : "")), splits: () => x },
      { label: page.unit, size: 60 }],
    series: [{ label: "box" },
      { label: "mean", fill: "rgba(47,111,181,0.55)", stroke: "#2f6fb5", paths: bars, points: { show: false } },
      { label: "max", stroke: "#1d232a", paths: () => null, points: { show: true, size: 6 } },
      { label: "min", stroke: "#66707a", paths: () => null, points: { show: true, size: 6 } }],
  }, barData(page), page.charts);
}

// The boxes' learning curves side by side: best so far of every seed.
async function curveCharts(page) {
  page.curvePlots = [];
  for (const b of page.boxes) {
    const id = `box-${b.task || ""}${box(b.shape)}`;
    const labels = b.run_ids.map((run) => `seed ${page.seeds[run]}`);
    softevo.sweep.labels[id] = labels;
    const plot = chart(id, `${boxName(b)}: best so far per seed`, {
      height: 200,
      scales: { x: { time: false } },
      axes: [GENERATION_AXIS, { label: page.unit, size: 55 }],
      series: [{ label: "generation" }, ...labels.map((label, i) => ({ label, stroke: COLOURS[i % COLOURS.length], width: 1.5 }))],
    }, await curveData(b), page.charts);
    page.curvePlots.push([b.run_ids, plot]);
  }
}

// Live: the table, the bars and the curves every 2 s while a run is queued or running.
function followSweep(page) {
  let busy = false;
  const last = Object.fromEntries(page.sweep.boxes.flatMap((b) => b.run_ids.map((id, i) => [id, b.statuses[i]])));
  const timer = setInterval(async () => {
    if (busy) return;
    busy = true;
    try {
      const sweep = page.sweep = await api(`/sweeps/${page.sweepId}`);
      showTable(page);
      page.barPlot.setData(barData(page));
      // only the curves of runs that were active at the last look can have grown
      const moving = new Set(sweep.boxes.flatMap((b) => b.run_ids.filter((id, i) => ACTIVE.includes(b.statuses[i]) || ACTIVE.includes(last[id]))));
      for (const b of sweep.boxes) b.run_ids.forEach((id, i) => { last[id] = b.statuses[i]; });
      for (const [runIds, plot] of page.curvePlots) if (runIds.some((id) => moving.has(id))) plot.setData(await curveData({ run_ids: runIds }));
      softevo.sweep.updates += 1;
      if (!ACTIVE.includes(sweep.status)) {
        clearInterval(timer);
        softevo.sweep.following = false;
      }
    } catch (error) { /* the next tick retries */ }
    busy = false;
  }, 2000);
  onLeave(() => clearInterval(timer));
}

// [generations, best so far of each run]: as long as the longest run's curve
async function curveData(b) {
  const curves = await Promise.all(b.run_ids.map((id) => api(`/runs/${id}/curve`)));
  const length = Math.max(1, ...curves.map((c) => c.generations.length));
  const gens = Array.from({ length }, (_, i) => i);
  return [gens, ...curves.map((c) => gens.map((g) => c.generations[g]?.best_so_far ?? null))];
}
