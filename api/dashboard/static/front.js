// A run with objectives: its Pareto front as a scatter that fills live (the first two objectives,
// as measured, each with its goal); a click on a point replays that robot.
import { api, fmt, h, softevo } from "./api.js";

const UNITS = { speed: "m/s", forward_speed: "m/s", climb_rate: "m/s", distance: "m", efficiency: "m/J",
  cost_of_transport: "J/(N·m)", energy: "J", total_mass: "kg", heading: "degrees" };
const axisName = (o) => `${o.measure.replace(/_/g, " ")}${UNITS[o.measure] ? ` (${UNITS[o.measure]})` : ""}, ` +
  `${o.goal === "max" ? "higher" : "lower"} is better`;
const MARGIN = { left: 56, bottom: 40, top: 10, right: 12 };

export class FrontScatter {
  constructor(parent, runId, onPick) {
    this.runId = runId;
    this.caption = h("p", { class: "muted" }, "The front fills as generations are committed.");
    this.canvas = h("canvas", { width: 520, height: 400, class: "front" });
    parent.append(h("div", { class: "panel", id: "front" },
      h("h3", {}, "Pareto front: robots no other beats in every objective (click one to replay it)"),
      this.canvas, this.caption));
    this.data = null;
    this.drawn = [];  // [x, y, point] in canvas pixels, for clicks
    this.canvas.addEventListener("click", (event) => {
      const point = this.pointAt(event);
      if (point) onPick(point);
    });
  }

  async update() {
    this.data = await api(`/runs/${this.runId}/front`);
    softevo.front = this.data;  // what is drawn, for tests and curious users
    this.draw();
  }

  pointAt(event) {
    const rect = this.canvas.getBoundingClientRect();
    const x = ((event.clientX - rect.left) * this.canvas.width) / rect.width;
    const y = ((event.clientY - rect.top) * this.canvas.height) / rect.height;
    let best = null, nearest = 12 * 12;  // within 12 pixels
    for (const [px, py, point] of this.drawn) {
      const d = (px - x) ** 2 + (py - y) ** 2;
      if (d <= nearest) { nearest = d; best = point; }
    }
    return best;
  }

  // canvas pixels of each point: the first objective across, the second (if any) up
  place(objectives, points) {
    const [a, b] = objectives;
    const xs = points.map((p) => p.measures[a.measure]), ys = points.map((p) => (b ? p.measures[b.measure] : 0));
    const span = (v) => { const lo = Math.min(...v), hi = Math.max(...v); return [lo, hi > lo ? hi : lo + 1]; };
    const [x0, x1] = span(xs), [y0, y1] = span(ys);
    const { left, bottom, top, right } = MARGIN;
    const w = this.canvas.width - left - right, hgt = this.canvas.height - top - bottom;
    this.drawn = points.map((p, i) => [left + ((xs[i] - x0) / (x1 - x0)) * w, top + hgt - ((ys[i] - y0) / (y1 - y0)) * hgt, p]);
    softevo.frontDrawn = Object.fromEntries(this.drawn.map(([x, y, p]) => [p.id, [x, y]]));  // for tests
    return { x0, x1, y0, y1 };
  }

  draw() {
    const ctx = this.canvas.getContext("2d");
    const { objectives, points } = this.data;
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    if (!points.length) return;
    const { x0, x1, y0, y1 } = this.place(objectives, points);
    const line = [...this.drawn].sort((p, q) => p[0] - q[0]);
    ctx.strokeStyle = "#c0392b";
    ctx.beginPath();
    line.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
    ctx.stroke();
    ctx.fillStyle = "#c0392b";
    for (const [x, y] of this.drawn) { ctx.beginPath(); ctx.arc(x, y, 4, 0, 2 * Math.PI); ctx.fill(); }
    ctx.fillStyle = "#66707a";
    ctx.font = "13px system-ui, sans-serif";
    ctx.fillText(`${axisName(objectives[0])}: ${fmt(x0)} → ${fmt(x1)}`, MARGIN.left, this.canvas.height - 12);
    if (objectives[1]) {
      ctx.save();
      ctx.translate(16, this.canvas.height - MARGIN.bottom);
      ctx.rotate(-Math.PI / 2);
      ctx.fillText(`${axisName(objectives[1])}: ${fmt(y0)} → ${fmt(y1)}`, 0, 0);
      ctx.restore();
    }
    this.caption.textContent = `${points.length} robots on the front of every one evaluated ` +
      `(generation ${this.data.generations}); objectives: ${objectives.map(axisName).join("; ")}`;
  }
}

// the run page's front panel (null for a run without objectives): a picked point replays its robot
export function frontPanel(run, parent, replay, replayPanel) {
  if (!run.config.objectives || !run.config.objectives.length) return null;
  return new FrontScatter(parent, run.id, (point) => {
    replay.best = null;  // a picked robot stays on screen while the run goes on
    replay.load(`/runs/${run.id}/individuals/${point.id}/replay`,
      () => `front robot of generation ${point.generation}, index ${point.index}`)
      .catch((error) => replayPanel.append(h("p", { class: "error" }, error.message)));
  });
}
