// A sweep: best fitness per bounding box or task (the paper's Figure 4a) and their learning curves,
// one line per seed; followed live (every 2 s) until its runs are done.
import { GENERATION_AXIS, api, box, chart, fmt, h, objective, onLeave, softevo, status, view } from "./api.js";

const COLOURS = ["#2f6fb5", "#e67e22", "#2e8b57", "#8e44ad", "#c0392b"];
const ACTIVE = ["queued", "running"];

export async function sweepView(sweepId) {
  softevo.view = "sweep";
  let sweep = await api(`/sweeps/${sweepId}`);
  const boxes = sweep.boxes;
  const byTask = boxes.some((b) => b.task);
  const name = (b) => (b.task ? `${b.task} ${box(b.shape)}` : box(b.shape));
  const unit = byTask ? "m/s, each task's objective" : objective(sweep.request).unit;
  // every run's seed: the curves are named by it (the box or task is the chart's title)
  const seeds = {};
  await Promise.all(boxes.flatMap((b) => b.run_ids).map(async (id) => { seeds[id] = (await api(`/runs/${id}`)).seed; }));
  // for tests: the status when opened, updates drawn, whether it is still being followed
  softevo.sweep = { seeds, labels: {}, opened: sweep.status, updates: 0, following: ACTIVE.includes(sweep.status) };

  const title = h("h2", {});
  const table = h("table", { id: "sweep-boxes" });
  const charts = h("div", { class: "grid" });
  view.replaceChildren(title, h("div", { class: "panel" }, table), charts);
  const showTable = () => {
    title.replaceChildren(`Sweep ${sweepId} `, status(sweep.status));
    table.replaceChildren(
      h("tr", {}, [byTask ? "task" : "box", "runs (seed)", "completed", `best mean (${unit})`, "spread (std)", "min", "max"].map((t) => h("th", {}, t))),
      ...sweep.boxes.map((b) => h("tr", {}, h("td", {}, name(b)),
        h("td", {}, b.run_ids.map((id, i) => h("a", { href: `#/runs/${id}`, title: b.statuses[i], style: "margin-right:.4rem" }, `#${id} (${seeds[id]})`))),
        h("td", { class: "num" }, `${b.completed}/${b.run_ids.length}`),
        h("td", { class: "num" }, fmt(b.best_mean)), h("td", { class: "num" }, fmt(b.best_std)),
        h("td", { class: "num" }, fmt(b.best_min)), h("td", { class: "num" }, fmt(b.best_max)))));
  };
  showTable();

  // Figure 4(a): best speed per box, the mean as a bar, the best and worst seed as dots
  const x = boxes.map((_, i) => i);
  const bars = uPlot.paths.bars({ size: [0.6, 60] });
  const barData = () => [x, sweep.boxes.map((b) => b.best_mean), sweep.boxes.map((b) => b.best_max), sweep.boxes.map((b) => b.best_min)];
  const barPlot = chart("boxes", `Best fitness per ${byTask ? "task" : "bounding box"} (bars: mean over seeds; dots: best and worst seed)`, {
    scales: { x: { time: false, range: [-0.6, boxes.length - 0.4] }, y: { range: (u, min, max) => [Math.min(0, (min ?? 0) * 1.1), Math.max((max ?? 0) * 1.1, 0.01)] } },
    axes: [{ label: byTask ? "task" : "bounding box", values: (u, ticks) => ticks.map((t) => (Number.isInteger(t) && boxes[t] ? name(boxes[t]) : "")), splits: () => x },
      { label: unit, size: 60 }],
    series: [{ label: "box" },
      { label: "mean", fill: "rgba(47,111,181,0.55)", stroke: "#2f6fb5", paths: bars, points: { show: false } },
      { label: "max", stroke: "#1d232a", paths: () => null, points: { show: true, size: 6 } },
      { label: "min", stroke: "#66707a", paths: () => null, points: { show: true, size: 6 } }],
  }, barData(), charts);

  // the boxes' learning curves side by side: best so far of every seed
  const curvePlots = [];
  for (const b of boxes) {
    const id = `box-${b.task || ""}${box(b.shape)}`;
    const labels = b.run_ids.map((run) => `seed ${seeds[run]}`);
    softevo.sweep.labels[id] = labels;
    const plot = chart(id, `${name(b)}: best so far per seed`, {
      height: 200,
      scales: { x: { time: false } },
      axes: [GENERATION_AXIS, { label: unit, size: 55 }],
      series: [{ label: "generation" }, ...labels.map((label, i) => ({ label, stroke: COLOURS[i % COLOURS.length], width: 1.5 }))],
    }, await curveData(b), charts);
    curvePlots.push([b.run_ids, plot]);
  }

  // live: the table, the bars and the curves every 2 s while a run is queued or running
  if (!ACTIVE.includes(sweep.status)) return;
  let busy = false;
  const last = Object.fromEntries(sweep.boxes.flatMap((b) => b.run_ids.map((id, i) => [id, b.statuses[i]])));
  const timer = setInterval(async () => {
    if (busy) return;
    busy = true;
    try {
      sweep = await api(`/sweeps/${sweepId}`);
      showTable();
      barPlot.setData(barData());
      // only the curves of runs that were active at the last look can have grown
      const moving = new Set(sweep.boxes.flatMap((b) => b.run_ids.filter((id, i) => ACTIVE.includes(b.statuses[i]) || ACTIVE.includes(last[id]))));
      for (const b of sweep.boxes) b.run_ids.forEach((id, i) => { last[id] = b.statuses[i]; });
      for (const [runIds, plot] of curvePlots) if (runIds.some((id) => moving.has(id))) plot.setData(await curveData({ run_ids: runIds }));
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
