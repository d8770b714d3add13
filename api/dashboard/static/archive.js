// A MAP-Elites run's archive as a heat map that fills live: one square per cell, coloured by its
// elite's fitness (empty cells blank); a click on a cell replays that elite.
import { api, fmt, h, softevo } from "./api.js";

// viridis, sampled: low fitness dark blue, high yellow
const RAMP = ["#440154", "#482878", "#3e4989", "#31688e", "#26828e", "#1f9e89", "#35b779", "#6ece58", "#b5de2b", "#fde725"];
const colour = (t) => RAMP[Math.min(RAMP.length - 1, Math.max(0, Math.floor(t * RAMP.length)))];

export class ArchiveMap {
  constructor(parent, runId, fitness, onPick) {
    this.runId = runId;
    this.fitness = fitness;
    this.caption = h("p", { class: "muted" }, "The archive fills as generations are committed.");
    this.canvas = h("canvas", { width: 520, height: 400, class: "archive" });
    this.panel = h("div", { class: "panel", id: "archive" },
      h("h3", {}, "Archive: the best robot of every kind of body (click a cell to replay it)"),
      this.canvas, this.caption);
    parent.append(this.panel);
    this.data = null;
    this.canvas.addEventListener("click", (event) => {
      const cell = this.cellAt(event);
      if (cell) onPick(cell);
    });
  }

  async update() {
    this.data = await api(`/runs/${this.runId}/archive`);
    softevo.archive = this.data;  // what is drawn, for tests and curious users
    this.draw();
  }

  // the grid's geometry: descriptor 1 across, descriptor 2 (if any) up, margins for the axes
  layout() {
    const [first, second] = this.data.descriptors;
    const cols = first.bins, rows = second ? second.bins : 1;
    const left = 48, bottom = 40, top = 8, right = 8;
    const w = (this.canvas.width - left - right) / cols, hgt = (this.canvas.height - top - bottom) / rows;
    return { first, second, cols, rows, left, bottom, top, w, hgt };
  }

  cellAt(event) {
    if (!this.data) return null;
    const { cols, rows, left, top, w, hgt } = this.layout();
    const rect = this.canvas.getBoundingClientRect();
    const x = ((event.clientX - rect.left) * this.canvas.width) / rect.width;
    const y = ((event.clientY - rect.top) * this.canvas.height) / rect.height;
    const i = Math.floor((x - left) / w), j = rows - 1 - Math.floor((y - top) / hgt);
    if (i < 0 || i >= cols || j < 0 || j >= rows) return null;
    return this.data.cells.find((c) => c.cell[0] === i && (c.cell[1] ?? 0) === j) || null;
  }

  draw() {
    const ctx = this.canvas.getContext("2d");
    const { first, second, cols, rows, left, bottom, top, w, hgt } = this.layout();
    ctx.clearRect(0, 0, this.canvas.width, this.canvas.height);
    ctx.strokeStyle = "#d9dee3";
    ctx.strokeRect(left, top, cols * w, rows * hgt);
    const values = this.data.cells.map((c) => c.fitness);
    const low = Math.min(...values), high = Math.max(...values);
    for (const cell of this.data.cells) {
      const [i, j = 0] = cell.cell;
      ctx.fillStyle = colour(high > low ? (cell.fitness - low) / (high - low) : 1);
      ctx.fillRect(left + i * w + 0.5, top + (rows - 1 - j) * hgt + 0.5, w - 1, hgt - 1);
    }
    ctx.fillStyle = "#66707a";
    ctx.font = "15px system-ui, sans-serif";
    ctx.fillText(`${first.name} ${first.low} → ${first.high}`, left, this.canvas.height - bottom + 26);
    if (second) {
      ctx.save();
      ctx.translate(16, top + rows * hgt);
      ctx.rotate(-Math.PI / 2);
      ctx.fillText(`${second.name} ${second.low} → ${second.high}`, 0, 0);
      ctx.restore();
    }
    const { coverage, qd_score: qd, cells } = this.data;
    // what each axis measures, in its unit (the catalogue's words: heading is in degrees)
    const axes = [first, second].filter(Boolean).map((axis, k) => `${k ? "up" : "across"}: ${axis.name}, ${axis.help}`);
    this.caption.textContent = `${cells.length} of ${cols * rows} cells filled (coverage ${fmt(coverage, 3)}), ` +
      `QD-score ${fmt(qd)}; colour: elite's ${this.fitness.label} from ${fmt(low)} (dark) to ${fmt(high)} (yellow); ` +
      `${axes.join("; ")}`;
  }
}
