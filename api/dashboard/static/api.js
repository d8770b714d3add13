// softevo dashboard: what every view shares. The API client (with the token field), the DOM
// helpers and formatters, the charts (uPlot), `window.softevo` (the chart data and the replay's
// state, so tests and curious users can read what is drawn) and what a view undoes on leaving.
export const softevo = (window.softevo = { charts: {}, dots: 0, replay: null, view: null });
export const view = document.getElementById("view");
const tokenInput = document.getElementById("token");
tokenInput.value = localStorage.getItem("softevo-token") || "";
// The token also as a cookie: a service with SOFTEVO_PROTECT_READS=1 asks it of every read, and
// the browser adds no header to the pictures, links and event stream it fetches itself.
const setCookie = () => {
  document.cookie = `softevo_token=${encodeURIComponent(tokenInput.value)}; path=/; SameSite=Strict`
    + (tokenInput.value ? "" : "; max-age=0");
};
setCookie();
tokenInput.addEventListener("change", () => {
  localStorage.setItem("softevo-token", tokenInput.value);
  setCookie();
  tokenInput.classList.remove("wanted");
});

export const cleanup = [];
export function onLeave(fn) { cleanup.push(fn); }

export async function api(path, options = {}) {
  const headers = { ...(options.headers || {}) };
  if (options.body) headers["Content-Type"] = "application/json";
  if (tokenInput.value) headers.Authorization = `Bearer ${tokenInput.value}`;  // reads may need it too
  let response = await fetch(path, { ...options, headers });
  // a read refused for a moment (this page's other replay is being simulated): ask again
  for (let tries = 0; response.status === 503 && !options.method && tries < 5; tries++) {
    const wait = Number(response.headers.get("Retry-After"));
    if (!wait) break;
    await new Promise((resolve) => setTimeout(resolve, wait * 1000));
    response = await fetch(path, { ...options, headers });
  }
  const body = response.headers.get("content-type")?.includes("json") ? await response.json() : null;
  if (!response.ok) {
    const detail = body?.detail;
    const text = Array.isArray(detail) ? detail.map(problem).join("; ") : detail || response.statusText;
    if (response.status === 401 || response.status === 403) {
      tokenInput.classList.add("wanted");  // the server wants a token: point at the field
      tokenInput.focus();
    }
    throw new Error(`${response.status}: ${text}`);
  }
  return body;
}

// One refused field in the CLI's words: "shape: expected three sides [nx, ny, nz], got [4, 4]",
// not pydantic's "Value error, ..." nor the field twice when the server's message names it.
function problem(d) {
  const field = (d.loc || []).slice(1).join(".");
  const msg = String(d.msg || "").replace(/^Value error, /, "");
  return !field || msg.startsWith(`${field}: `) ? msg : `${field}: ${msg}`;
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
// seconds between two of the API's timestamps, as "2 min 05 s" or "3.4 s" (null when either is missing)
export function duration(from, to) {
  if (!from || !to) return null;
  const utc = (t) => new Date(/(Z|[+-]\d\d:?\d\d)$/i.test(t) ? t : `${t}Z`);  // SQLite's have no zone
  const exact = Math.max(0, (utc(to) - utc(from)) / 1000);
  if (exact < 9.95) return `${exact.toFixed(1)} s`;
  const s = Math.round(exact);
  const [hours, minutes, seconds] = [Math.floor(s / 3600), Math.floor((s % 3600) / 60), s % 60];
  const pad = (n) => String(n).padStart(2, "0");
  if (hours) return `${hours} h ${pad(minutes)} min`;
  return minutes ? `${minutes} min ${pad(seconds)} s` : `${seconds} s`;
}
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
  // the legend shows the latest values while the cursor is off the chart, not "--"
  const hooks = { ...(options.hooks || {}), setCursor: [...(options.hooks?.setCursor || []), showLast] };
  const plot = new uPlot({ width: width(), height: 260, ...options, hooks }, data, holder);
  const setData = plot.setData.bind(plot);
  plot.setData = (...args) => { setData(...args); showLast(plot); };
  showLast(plot);
  // the grid reflows as panels are added and the window resizes: follow the panel's width
  const observer = new ResizeObserver(() => {
    if (Math.abs(plot.width - width()) > 1) plot.setSize({ width: width(), height: plot.height });
  });
  observer.observe(holder);
  onLeave(() => observer.disconnect());
  softevo.charts[id] = plot;
  return plot;
}

// the legend at the last point, unless the cursor is on the chart
function showLast(plot) {
  const last = plot.data[0].length - 1;
  if (plot.cursor.idx === null || plot.cursor.idx === undefined || plot.cursor.left < 0) {
    if (last >= 0 && plot.legend.idx !== last) plot.setLegend({ idx: last });
  }
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
