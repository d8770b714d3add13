// A run with objectives: its Pareto front over every robot evaluated (the first two objectives,
// as measured, each named with its unit and goal, with tick labels; an axis one outlier would
// squash is logarithmic or clipped), filling live, and the hypervolume (raw, and normalised 0-1)
// over the simulations run.
// A click on a point of the front replays that robot.
import { api, chart, h, onLeave, softevo } from "./api.js";
import { axisScale, hypervolumeUnit, measureLabel, significant, ticks } from "./units.js";

const MARGIN = { left: 74, bottom: 58, top: 10, right: 14 };
const FRONT = "#c0392b", DOTS = "#9aa3ab", INK = "#4b545c";
// an axis's name in two lines: the measure with its unit, then its goal (and a log scale)
const axisName = (o, scale) => [measureLabel(o.measure),
  `${o.goal === "max" ? "higher" : "lower"} is better${scale.kind === "log" ? ", log scale" : ""}`];
const finite = (v) => v !== null && v !== undefined && Number.isFinite(Number(v));

// 0..1 along an axis (clipped values at its ends), padded so no point sits on the frame
function unit(scale, v) {
  const c = Math.min(scale.hi, Math.max(scale.lo, v));
  const u = scale.kind === "log" ? Math.log10(c / scale.lo) / Math.log10(scale.hi / scale.lo) : (c - scale.lo) / (scale.hi - scale.lo);
  return 0.04 + 0.92 * u;
}
const outside = (scale, v) => v < scale.lo || v > scale.hi;

// the largest font size (`largest` px down to 9 px) at which `text` fits in `room` pixels
function fitFont(ctx, text, room, largest = 13) {
  for (let size = largest; size > 9; size--) {
    ctx.font = `${size}px system-ui, sans-serif`;
    if (ctx.measureText(text).width <= room) return;
  }
  ctx.font = "9px system-ui, sans-serif";
}

export class FrontScatter {
  constructor(parent, runId, onPick, everyone) {
    this.runId = runId;
    this.everyone = everyone;  // the run's individuals loaded so far (the page's)
    this.caption = h("p", { class: "muted" }, "The front fills as generations are committed.");
    this.canvas = h("canvas", { width: 560, height: 420, class: "front" });
    this.panel = h("div", { class: "panel", id: "front" },
      h("h3", {}, "Pareto front over every robot evaluated (click a red point to replay it)"),
      this.canvas, this.caption);
    parent.append(this.panel);
    // drawn at the panel's width, so its labels are read at their size, not scaled down
    const observer = new ResizeObserver(() => { if (this.data && this.fit()) this.draw(); });
    observer.observe(this.panel);
    onLeave(() => observer.disconnect());
    this.data = null;
    this.drawn = [];  // [x, y, point] in canvas pixels, for clicks
    this.canvas.addEventListener("click", (event) => {
      const point = this.pointAt(event);
      if (point) onPick(point);
    });
  }

  // the canvas as wide as the panel holds (a resize clears it: true when it changed)
  fit() {
    const width = Math.max(320, Math.min(720, this.panel.clientWidth - 26));
    if (width === this.canvas.width) return false;
    this.canvas.width = width;
    this.canvas.height = Math.round(width * 0.72);
    return true;
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

  // [x, y] of each robot in the objectives' units: the front's points and every other robot
  // evaluated with both measures (a survivor is a robot already drawn)
  values(objectives, points) {
    const [a, b] = objectives;
    const at = (p) => [p.measures[a.measure], b ? p.measures[b.measure] : 0];
    const dots = this.everyone().filter((p) => p.fitness !== null && p.measures && p.operator !== "survivor")
      .map(at).filter(([x, y]) => finite(x) && finite(y));
    return { dots, front: points.map(at) };
  }

  // the axes' scales and a function from values to canvas pixels
  place(objectives, points) {
    const { dots, front } = this.values(objectives, points);
    const all = [...dots, ...front];
    const sx = axisScale(all.map((p) => p[0]), front.map((p) => p[0]));
    const sy = objectives[1] ? axisScale(all.map((p) => p[1]), front.map((p) => p[1])) : { kind: "linear", lo: -1, hi: 1 };
    const { left, bottom, top, right } = MARGIN;
    const w = this.canvas.width - left - right, hgt = this.canvas.height - top - bottom;
    const px = ([x, y]) => [left + unit(sx, x) * w, top + hgt - unit(sy, y) * hgt];
    this.drawn = points.map((p, i) => [...px(front[i]), p]);
    softevo.frontDrawn = Object.fromEntries(this.drawn.map(([x, y, p]) => [p.id, [x, y]]));  // for tests
    return { sx, sy, px, dots, w, hgt };
  }

  draw() {
    const ctx = this.canvas.getContext("2d");
    const { objectives, points } = this.data;
    this.fit();
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    if (!points.length) return;
    const placed = this.place(objectives, points);
    this.axes(ctx, objectives, placed);
    const off = placed.dots.filter(([x, y]) => outside(placed.sx, x) || outside(placed.sy, y));
    for (const dot of placed.dots) {
      const [x, y] = placed.px(dot);
      ctx.beginPath();
      if (off.includes(dot)) { ctx.strokeStyle = "#2f6fb5"; ctx.rect(x - 3.5, y - 3.5, 7, 7); ctx.stroke(); }
      else { ctx.fillStyle = DOTS; ctx.arc(x, y, 2.6, 0, 2 * Math.PI); ctx.fill(); }
    }
    const line = [...this.drawn].sort((p, q) => p[0] - q[0]);
    ctx.strokeStyle = FRONT;
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    line.forEach(([x, y], i) => (i ? ctx.lineTo(x, y) : ctx.moveTo(x, y)));
    ctx.stroke();
    ctx.fillStyle = FRONT;
    for (const [x, y] of this.drawn) { ctx.beginPath(); ctx.arc(x, y, 4.5, 0, 2 * Math.PI); ctx.fill(); }
    softevo.frontDots = placed.dots.length;  // for tests
    softevo.frontScales = [placed.sx.kind, placed.sy.kind];
    this.caption.textContent = `${points.length} robots on the front (red) of the ${placed.dots.length} evaluated ` +
      `(grey) after ${this.data.generations} generations` + (off.length ? `; ${off.length} beyond an axis, drawn on its edge (blue squares)` : "");
  }

  // frame, grid, tick labels and the axes' names
  axes(ctx, objectives, { sx, sy, px, w, hgt }) {
    const { left, top } = MARGIN;
    ctx.lineWidth = 1;
    ctx.strokeStyle = "#e3e7eb";
    ctx.fillStyle = INK;
    ctx.font = "11px system-ui, sans-serif";
    ctx.textAlign = "center";
    ctx.textBaseline = "top";
    for (const v of ticks(sx)) {
      const [x] = px([v, sy.lo]);
      ctx.beginPath(); ctx.moveTo(x, top); ctx.lineTo(x, top + hgt); ctx.stroke();
      ctx.fillText(significant(v, 3), x, top + hgt + 4);
    }
    ctx.textAlign = "right";
    ctx.textBaseline = "middle";
    for (const v of objectives[1] ? ticks(sy) : []) {
      const [, y] = px([sx.lo, v]);
      ctx.beginPath(); ctx.moveTo(left, y); ctx.lineTo(left + w, y); ctx.stroke();
      ctx.fillText(significant(v, 3), left - 4, y);
    }
    ctx.strokeStyle = "#8a939b";
    ctx.strokeRect(left, top, w, hgt);
    ctx.textAlign = "center";
    ctx.textBaseline = "alphabetic";
    this.axisTitle(ctx, axisName(objectives[0], sx), left + w / 2, this.canvas.height - 24, w, 0);
    if (objectives[1]) this.axisTitle(ctx, axisName(objectives[1], sy), 16, top + hgt / 2, hgt, -Math.PI / 2);
  }

  // two lines centred at (x, y), turned by `angle`, each in the largest font that fits `room`
  axisTitle(ctx, [name, goal], x, y, room, angle) {
    ctx.save();
    ctx.translate(x, y);
    ctx.rotate(angle);
    ctx.fillStyle = "#1d232a";
    fitFont(ctx, name, room);
    ctx.fillText(name, 0, 0);
    ctx.fillStyle = INK;
    fitFont(ctx, goal, room, 12);
    ctx.fillText(goal, 0, 15);
    ctx.restore();
  }
}

// the run page's front panel (null for a run without objectives): a picked point replays its robot
export function frontPanel(run, parent, replay, everyone) {
  if (!run.config.objectives || !run.config.objectives.length) return null;
  return new FrontScatter(parent, run.id, (point) => {
    replay.pick(`/runs/${run.id}/individuals/${point.id}/replay`,
      () => `front robot of generation ${point.generation}, index ${point.index}`);
  }, everyone);
}

// x: the simulations run until each generation was committed (the curve's evaluations summed),
// y: the hypervolume of the front so far, and its normalised hypervolume (0-1; null for a
// generation committed before the column existed)
export function hypervolumeData(curve) {
  let spent = 0;
  return [curve.map((r) => (spent += r.evaluations || 0)), curve.map((r) => r.hypervolume ?? null),
    curve.map((r) => r.normalised_hypervolume ?? null)];
}

// "speed 0 to 0.5, cost of transport 100000 to 0": each objective's reference (0) and ideal (1)
const bounds = (objectives) =>
  objectives.map((o) => `${o.measure.replace(/_/g, " ")} ${o.reference} to ${o.ideal ?? "?"}`).join(", ");

// the hypervolume chart of a run with objectives (null for one without); `show(curve)` redraws it.
// Raw (left axis, the objectives' units) and normalised (right axis, 0-1: each objective scaled
// from its reference to its ideal, so both ends of a front count alike)
export function hypervolumeChart(run, curve, parent) {
  const objectives = run.config.objectives || [];
  if (!objectives.length) return null;
  const reference = objectives.map((o) => `${o.measure.replace(/_/g, " ")} ${o.reference}`).join(", ");
  const unitText = hypervolumeUnit(objectives);
  let generations = [];
  const atGeneration = (u, v, s, i) => (v === null || i === null || i === undefined ? "–" : `${v} (generation ${generations[i]})`);
  const stepped = uPlot.paths.stepped({ align: 1 });
  const title = `Hypervolume of the front so far (${unitText}; reference point: ${reference}) and normalised `
    + `(0-1, each objective scaled from reference to ideal: ${bounds(objectives)})`;
  const plot = chart("hypervolume", title, {
    scales: { x: { time: false, range: (u, min, max) => [0, Math.max(max, 1)] },
      y: { range: (u, min, max) => [0, Math.max(max * 1.05, 1e-9)] }, normalised: { range: [0, 1] } },
    axes: [{ label: "simulations run (cumulative)" }, { label: `hypervolume (${unitText})`, size: 70 },
      { scale: "normalised", side: 1, label: "normalised (0-1)", size: 70, grid: { show: false } }],
    series: [{ label: "simulations", value: atGeneration },
      { label: "hypervolume", stroke: "#2f6fb5", width: 1.5, paths: stepped, value: (u, v) => significant(v) },
      { label: "normalised (0-1)", scale: "normalised", stroke: "#c0392b", width: 1.5, dash: [6, 3],
        paths: stepped, value: (u, v) => (v === null || v === undefined ? "–" : v.toFixed(3)) }],
  }, [[], [], []], parent);
  const show = (rows) => { generations = rows.map((r) => r.generation); plot.setData(hypervolumeData(rows)); };
  show(curve);
  return { plot, show };
}
