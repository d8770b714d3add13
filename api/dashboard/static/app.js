// softevo dashboard: runs, one run live (curve, population, diversity, 3D replay), sweeps.
// ES modules: api.js (what every view shares), runs.js, sweeps.js, run.js, replay.js, sweep.js; uPlot
// (global) draws the charts, three.js the replay. Everything it shows
// comes from the REST API of the server that serves it. `window.softevo` exposes the chart data
// and the replay's state, so tests (and curious users) can read what is drawn.
import { cleanup, h, softevo, view } from "./api.js";
import { runView } from "./run.js";
import { runsView } from "./runs.js";
import { sweepView } from "./sweep.js";

// -- routing ---------------------------------------------------------------------------------------

async function route() {
  for (const fn of cleanup.splice(0)) fn();
  softevo.charts = {};
  softevo.dots = 0;
  const hash = location.hash.replace(/^#/, "") || "/";
  let match;
  try {
    if ((match = hash.match(/^\/runs\/(\d+)$/))) await runView(Number(match[1]));
    else if ((match = hash.match(/^\/sweeps\/(\d+)$/))) await sweepView(Number(match[1]));
    else await runsView();
  } catch (error) {
    view.replaceChildren(h("p", { class: "error" }, String(error.message || error)));
  }
}
window.addEventListener("hashchange", route);

// -- the runs --------------------------------------------------------------------------------------

route();
