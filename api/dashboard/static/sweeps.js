// The list of sweeps and the form that starts one: a preset over bounding boxes (or task presets)
// and seeds, one run each. A started sweep opens in its own view, which follows it live.
import { api, box, h, status } from "./api.js";

const words = (text) => String(text || "").split(/[\s,;]+/).filter(Boolean);

export function sweepsPanel(presets) {
  const form = sweepForm(presets);
  const table = h("table", { id: "sweeps" });
  const panel = h("div", {}, h("div", { class: "panel" }, h("h3", {}, "Start a sweep"), form),
    h("div", { class: "panel" }, h("h3", {}, "Sweeps"), table));
  return { panel, refresh: () => refreshSweeps(table) };
}

// The form that starts a sweep: over bounding boxes of a preset, or over task presets.
function sweepForm(presets) {
  const tasks = presets.filter((p) => p.name.startsWith("task-"));
  const message = h("span", { class: "muted", id: "sweep-message" });
  const over = h("select", { name: "over" }, h("option", { value: "shapes" }, "bounding boxes"),
    h("option", { value: "tasks" }, "tasks"));
  const preset = h("label", {}, "preset", h("select", { name: "preset" },
    presets.filter((p) => !p.name.startsWith("task-"))
      .map((p) => h("option", { value: p.name, title: p.description, selected: p.name === "quick" }, p.name))));
  const shapes = h("label", {}, "boxes", h("input", { name: "shapes", value: "2x2x2 3x2x2", size: 14, placeholder: "e.g. 4x4x4 5x5x3" }));
  const taskBoxes = h("span", { class: "tasks" }, tasks.map((t) =>
    h("label", { title: t.description }, h("input", { type: "checkbox", name: "tasks", value: t.name, checked: true }), t.name)));
  const form = h("form", { class: "start", id: "sweep-form" },
    h("label", {}, "over", over), preset, shapes, taskBoxes,
    h("label", {}, "seeds", h("input", { name: "seeds", value: "1 2 3", size: 8 })),
    h("label", {}, "population", h("input", { name: "population", type: "number", min: 2, placeholder: "preset" })),
    h("label", {}, "generations", h("input", { name: "generations", type: "number", min: 1, placeholder: "preset" })),
    h("button", { class: "primary", type: "submit" }, "Start sweep"), message);
  // over tasks: each task is a preset with its own box, so neither preset nor boxes are asked
  const showOver = () => {
    const byTask = over.value === "tasks";
    preset.hidden = shapes.hidden = byTask;
    taskBoxes.hidden = !byTask;
  };
  over.addEventListener("change", showOver);
  showOver();
  form.addEventListener("submit", (event) => startSweep(event, form, over, message));
  return form;
}

// The form's sweep, started; its view opens, or the form says why not.
async function startSweep(event, form, over, message) {
  event.preventDefault();
  const data = new FormData(form);
  const request = { seeds: words(data.get("seeds")).map(Number) };
  if (over.value === "tasks") request.tasks = data.getAll("tasks");
  else {
    request.preset = data.get("preset");
    if (words(data.get("shapes")).length) request.shapes = words(data.get("shapes"));
  }
  for (const key of ["population", "generations"]) if (data.get(key)) request[key] = Number(data.get(key));
  try {
    const sweep = await api("/sweeps", { method: "POST", body: JSON.stringify(request) });
    location.hash = `#/sweeps/${sweep.id}`;
  } catch (error) {
    message.className = "error";
    message.textContent = error.message;
  }
}

// The list of the last 50 sweeps, read again.
async function refreshSweeps(table) {
  const page = await api("/sweeps?limit=50");
  table.replaceChildren(
    h("tr", {}, ["sweep", "status", "over", "seeds", "runs completed", "preset"].map((t) => h("th", {}, t))),
    ...page.items.map((sweep) => {
      const runs = sweep.boxes.reduce((n, b) => n + b.run_ids.length, 0);
      const done = sweep.boxes.reduce((n, b) => n + b.completed, 0);
      const byTask = sweep.boxes.some((b) => b.task);
      return h("tr", { "data-sweep": sweep.id },
        h("td", {}, h("a", { href: `#/sweeps/${sweep.id}` }, `sweep ${sweep.id}`)),
        h("td", {}, status(sweep.status)),
        h("td", {}, [...new Set(sweep.boxes.map((b) => (byTask ? b.task : box(b.shape))))].join(", ")),
        h("td", { class: "num" }, (sweep.request.seeds || []).join(", ")),  // stored by the API
        h("td", { class: "num" }, `${done}/${runs}`),
        h("td", {}, sweep.request.preset || (byTask ? "each task's" : "paper-voxel")));
    }));
  if (!page.items.length) table.append(h("tr", {}, h("td", { colspan: 6, class: "muted" }, "No sweeps yet: start one above.")));
}
