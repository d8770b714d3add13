// The list of runs: status, progress, best speed; start one from a preset, cancel one.
import { api, box, fmt, h, objective, onLeave, progressBar, softevo, status, terrainText, view } from "./api.js";
import { measureLabel, objectiveShort } from "./units.js";
import { sweepsPanel } from "./sweeps.js";

export async function runsView() {
  softevo.view = "runs";
  const presets = await api("/presets");
  const message = h("span", { class: "muted", id: "start-message" });
  const form = h("form", { class: "start", id: "start-form" },
    h("label", {}, "preset", h("select", { name: "preset" },
      // a first try should take a minute, not the paper's 1000 generations
      presets.map((p) => h("option", { value: p.name, title: p.description, selected: p.name === "quick" }, p.name)))),
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
    if (shape) request.shape = shape;  // "5x5x3": the server reads (and refuses) it as the CLI does
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
  const sweeps = sweepsPanel(presets);
  view.replaceChildren(
    h("div", { class: "panel" }, h("h3", {}, "Start a run"), form),
    h("div", { class: "panel" }, h("h3", {}, "Runs"), table), sweeps.panel);

  async function refresh() {
    const page = await api("/runs?limit=100");
    table.replaceChildren(
      h("tr", {}, COLUMNS.map((t) => h("th", {}, t))),
      ...page.items.map((run) => h("tr", { "data-run": run.id },
        h("td", {}, h("a", { href: `#/runs/${run.id}` }, `#${run.id}`)),
        h("td", { class: "thumb" }, thumbnail(run)),
        h("td", {}, status(run.status)),
        h("td", {}, progressBar(run.progress.generation, run.progress.generations)),
        ...searchCells(run.config),
        h("td", { class: "num" }, `${fmt(run.progress.best_fitness)} ${objective(run.config).unit}`),
        h("td", {}, run.preset || "–"),
        h("td", {}, box(run.config.shape)),
        h("td", { class: "num" }, run.seed),
        h("td", {}, run.sweep_id ? h("a", { href: `#/sweeps/${run.sweep_id}` }, `sweep ${run.sweep_id}`) : "–"),
        h("td", {}, ["queued", "running"].includes(run.status) ? cancelButton(run.id, refresh) : ""))));
    if (!page.items.length) table.append(h("tr", {}, h("td", { colspan: COLUMNS.length, class: "muted" }, "No runs yet: start one above.")));
  }
  await Promise.all([refresh(), sweeps.refresh()]);
  const timer = setInterval(() => Promise.all([refresh(), sweeps.refresh()]).catch(() => {}), 2000);
  onLeave(() => clearInterval(timer));
}

const COLUMNS = ["run", "", "status", "progress", "algorithm", "encoding", "objectives", "task",
  "best fitness", "preset", "box", "seed", "sweep", ""];

// What a run searches with and for: its algorithm (a quality-diversity run's descriptors with
// it), encoding, objectives (↑ maximised, ↓ minimised; the fitness alone for a run without) and
// task (terrain / the fitness's objective), so an nsga2 run and a map-elites one tell apart.
function searchCells(config) {
  const descriptors = config.descriptors || [], objectives = config.objectives || [];
  const fitness = objective(config);
  const goals = objectives.map((o) => `${measureLabel(o.measure)}, ${o.goal === "max" ? "maximised" : "minimised"}`);
  return [
    h("td", { class: "algorithm" }, config.algorithm || "ga",
      descriptors.length ? h("span", { class: "muted" }, ` (${descriptors.join(" × ")})`) : ""),
    h("td", { class: "encoding" }, config.encoding || "voxel"),
    h("td", { class: "objectives", title: objectives.length ? goals.join("; ") : fitness.label },
      objectives.length ? objectives.map(objectiveShort).join(", ") : fitness.name),
    h("td", { class: "task" }, `${terrainText(config)} / ${fitness.name}`),
  ];
}

// A small picture of the run's best robot at rest; the URL names the best's generation, so a new
// best is fetched and an unchanged one comes from the browser's cache on each refresh.
function thumbnail(run) {
  const generation = run.progress.best_generation;
  if (generation === null || generation === undefined) return "";
  return h("img", {
    class: "thumbnail", src: `/runs/${run.id}/best/thumbnail.png?generation=${generation}`,
    loading: "lazy", width: 60, height: 45, alt: `best robot of run ${run.id}`,
  });
}

export function cancelButton(runId, after) {
  return h("button", {
    onclick: async (event) => {
      event.target.disabled = true;
      try { await api(`/runs/${runId}/cancel`, { method: "POST" }); }
      catch (error) { alert(error.message); }
      await after();
    },
  }, "Cancel");
}

