// softevo dashboard: what every view shares. The API client (with the token field), the DOM
// helpers and formatters, the charts (uPlot), `window.softevo` (the chart data and the replay's
// state, so tests and curious users can read what is drawn) and what a view undoes on leaving.
export const softevo = (window.softevo = { charts: {}, dots: 0, replay: null, view: null });
export const view = document.getElementById("view");
const tokenInput = document.getElementById("token");
tokenInput.value = localStorage.getItem("softevo-token") || "";
tokenInput.addEventListener("change", () => {
  localStorage.setItem("softevo-token", tokenInput.value);
  tokenInput.classList.remove("wanted");
});

export const cleanup = [];
export function onLeave(fn) { cleanup.push(fn); }

export async function api(path, options = {}) {
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


export const h = (tag, attrs = {}, ...children) => {
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
export const fmt = (value, digits = 4) => (value === null || value === undefined ? "–" : Number(value).toFixed(digits));
export const box = (shape) => (shape ? shape.join("×") : "–");
export const status = (s) => h("span", { class: `status ${s}` }, s);
export const progressBar = (done, total) =>
  h("span", {}, h("span", { class: "bar" }, h("i", { style: `width:${(100 * done) / Math.max(1, total)}%` })),
    `${done}/${total}`);


// -- charts ----------------------------------------------------------------------------------------

// generations are whole numbers: ticks at 1, 2, 5, 10, ... apart, never at 0.5
export const GENERATION_AXIS = { label: "generation", incrs: [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000] };

export const CURVE_SERIES = [
  { key: "best_so_far", label: "best so far", stroke: "#1d232a", width: 2 },
  { key: "best", label: "best", stroke: "#2f6fb5" },
  { key: "mean", label: "mean", stroke: "#e67e22", dash: [6, 4] },
  { key: "median", label: "median", stroke: "#2e8b57", dash: [2, 3] },
];

export function chart(id, title, options, data, parent) {
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

// What a run's fitness is (its config's objective; speed when absent), with its unit.
const OBJECTIVES = {
  speed: ["speed", "m/s"], forward: ["forward speed", "m/s"], climb: ["climb rate", "m/s"], efficiency: ["efficiency", "m/J"],
};
export function objective(config) {
  const [name, unit] = OBJECTIVES[(config && config.objective) || "speed"] || OBJECTIVES.speed;
  return { name, unit, label: `${name} (${unit})` };
}

// "flat", or "steps (height 0.2, depth 4.5)": a run's terrain in a few words.
export function terrainText(config) {
  const terrain = (config && config.sim && config.sim.terrain) || { kind: "flat" };
  const { kind, ...rest } = terrain;
  delete rest.mesh;
  const parts = Object.entries(rest).map(([key, value]) => `${key} ${value}`);
  return parts.length ? `${kind} (${parts.join(", ")})` : kind;
}
