// A sweep: best fitness per bounding box or task (the paper's Figure 4a) and their learning curves.
import { GENERATION_AXIS, api, box, chart, fmt, h, objective, softevo, status, view } from "./api.js";

export async function sweepView(sweepId) {
  softevo.view = "sweep";
  const sweep = await api(`/sweeps/${sweepId}`);
  const boxes = sweep.boxes;
  const byTask = boxes.some((b) => b.task);
  const name = (b) => (b.task ? `${b.task} ${box(b.shape)}` : box(b.shape));
  const unit = byTask ? "m/s, each task's objective" : objective(sweep.request).unit;
  const table = h("table", {},
    h("tr", {}, [byTask ? "task" : "box", "runs", "completed", `best mean (${unit})`, "spread (std)", "min", "max"].map((t) => h("th", {}, t))),
    boxes.map((b) => h("tr", {}, h("td", {}, name(b)),
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
  chart("boxes", `Best fitness per ${byTask ? "task" : "bounding box"} (bars: mean over seeds; dots: best and worst seed)`, {
    scales: { x: { time: false, range: [-0.6, boxes.length - 0.4] }, y: { range: (u, min, max) => [Math.min(0, min * 1.1), Math.max(max * 1.1, 0.01)] } },
    axes: [{ label: byTask ? "task" : "bounding box", values: (u, ticks) => ticks.map((t) => (Number.isInteger(t) && boxes[t] ? name(boxes[t]) : "")), splits: () => x },
      { label: unit, size: 60 }],
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
    chart(`box-${b.task || ""}${box(b.shape)}`, `${name(b)}: best so far per seed`, {
      height: 200,
      scales: { x: { time: false } },
      axes: [GENERATION_AXIS, { label: unit, size: 55 }],
      series: [{ label: "generation" }, ...curves.map((c, i) => ({ label: `run #${b.run_ids[i]}`, stroke: ["#2f6fb5", "#e67e22", "#2e8b57", "#8e44ad", "#c0392b"][i % 5], width: 1.5 }))],
    }, [gens, ...curves.map((c) => gens.map((g) => c.generations[g]?.best_so_far ?? null))], charts);
  }
}
