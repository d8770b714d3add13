// The 3D replay of one robot (three.js): springs coloured by material and actuation phase.
import * as THREE from "three";
import { OrbitControls } from "three/addons/OrbitControls.js";
import { api, fmt, h, softevo, terrainText } from "./api.js";
import { costOfTransportText, energyText } from "./units.js";
import { voxelMesh } from "./voxels.js";

const PASSIVE_SOFT = new THREE.Color("#9bc59d"), PASSIVE_HARD = new THREE.Color("#4a4f55");
const IN_PHASE = new THREE.Color("#d1495b"), ANTI_PHASE = new THREE.Color("#2f6fb5");

// The terrain's surface from the replay's height grid (x, y, z[y][x]): shaded by height, with
// its grid lines, so slopes, steps, bars and bumps read at a glance.
function terrainMesh({ x, y, z }) {
  const geometry = new THREE.BufferGeometry();
  const vertices = new Float32Array(x.length * y.length * 3);
  const colours = new Float32Array(x.length * y.length * 3);
  const flat = z.flat(), low = Math.min(...flat), high = Math.max(...flat);
  const base = new THREE.Color("#d5dce3"), top = new THREE.Color("#8fa3b5");
  y.forEach((yv, j) => x.forEach((xv, i) => {
    const k = j * x.length + i;
    vertices.set([xv, yv, z[j][i] - 0.002], k * 3);
    const c = base.clone().lerp(top, high > low ? (z[j][i] - low) / (high - low) : 0);
    colours.set([c.r, c.g, c.b], k * 3);
  }));
  const index = [];
  for (let j = 0; j + 1 < y.length; j++) {
    for (let i = 0; i + 1 < x.length; i++) {
      const a = j * x.length + i, b = a + 1, c = a + x.length, d = c + 1;
      index.push(a, b, d, a, d, c);
    }
  }
  geometry.setIndex(index);
  geometry.setAttribute("position", new THREE.BufferAttribute(vertices, 3));
  geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  const solid = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({ vertexColors: true, side: THREE.DoubleSide }));
  const lines = new THREE.LineSegments(new THREE.WireframeGeometry(geometry), new THREE.LineBasicMaterial({ color: 0xaab4be, transparent: true, opacity: 0.25 }));
  return [solid, lines];
}

export class Replay {
  constructor(panel) {
    this.panel = panel;
    this.loaded = false;
    this.best = null;  // the generation of the best robot shown, null for a picked individual
    this.asked = 0;  // replays asked for: only the last one asked is shown
    this.picked = false;  // a robot the user picked: the run view stops following the best
    this.state = { frame: 0, frames: 0, time: 0, playing: false, speed: 1, renderer: null, label: "" };
    this.disposers = [];
    softevo.replay = this.state;
  }

  async load(url, label) {
    const data = await this.fetch(url);
    this.show(data, label(data));
    return data;
  }

  // a robot the user clicked, kept on screen while the run goes on; an error is said in the
  // panel, and the page follows the best robot again
  pick(url, label) {
    this.best = null;
    this.picked = true;
    this.load(url, label).catch((error) => {
      this.picked = false;
      this.panel.append(h("p", { class: "error" }, error.message));
    });
  }

  // fetch and show apart: the run view draws a new best with the summary that names it
  async fetch(url) {
    const asked = ++this.asked;
    return { ...(await api(`${url}?fps=30`)), asked };
  }

  // false, and nothing drawn, for a replay asked before the last one (a robot picked while the
  // best one was being simulated stays on screen when the best one comes)
  show(data, label) {
    if (data.asked !== this.asked) {
      softevo.replaysDropped = (softevo.replaysDropped || 0) + 1;  // for tests
      return false;
    }
    this.data = data;
    this.loaded = true;
    this.build(label);
    return true;
  }

  // One robot on screen: its panel, its scene drawn by the replay's one renderer, played.
  build(label) {
    const data = this.data;
    this.clear();
    const ui = this.panelFor(data, label);
    const renderer = this.glRenderer(ui.holder);
    const world = robotScene(data, ui.byHue);
    const showSprings = (on) => { this.state.springs = world.showSprings(on); };
    ui.springsBox.checked = !world.body;
    showSprings(!world.body);
    ui.springsBox.onchange = () => { showSprings(ui.springsBox.checked); this.state.drawn = false; };
    Object.assign(this.state, { voxels: world.body ? world.body.faces : 0, terrain: world.terrain });
    const controls = renderer ? new OrbitControls(world.camera, renderer.domElement) : null;
    if (controls) controls.target.set(...world.centre);
    const draw = drawer(data, world, renderer, controls, ui.holder);
    this.play(data, ui, draw);
    this.disposers.push(() => controls?.dispose(), () => world.dispose());
  }

  // The replay's WebGL renderer (so its one GL context), made once and moved into each new
  // panel: a live run shows a new best every few generations, and a context made for each cost
  // the page's main thread seconds in a software renderer (a click waited behind it) and piled
  // contexts up until the browser dropped the oldest. Null where WebGL cannot draw.
  glRenderer(holder) {
    if (this.renderer === undefined) {
      try {
        this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
      } catch (error) {
        this.renderer = null;
        this.rendererError = String(error.message || error);
      }
    }
    this.state.renderer = this.renderer ? "webgl" : null;
    if (this.renderer) holder.append(this.renderer.domElement);
    else holder.append(h("p", { class: "error" }, "This browser cannot draw WebGL: ", this.rendererError));
    return this.renderer;
  }

  // The panel's title, measures, canvas holder, controls and legend, for `data`.
  panelFor(data, label) {
    const title = h("h3", {}, "Replay: ", label, data.speed !== null ? ` · ${fmt(data.speed)} m/s` : " · unstable",
      data.blew_up_at !== null && data.blew_up_at !== undefined ? ` (blew up at ${fmt(data.blew_up_at, 3)} s: its sim.dt is too large)` : "");
    const measures = data.measures || {};
    const terrain = terrainText({ sim: { terrain: data.terrain } });
    const facts = h("p", { class: "muted", id: "replay-measures" }, `terrain: ${terrain} · forward ${fmt(measures.forward_speed)} m/s · climb ${fmt(measures.climb_rate)} m/s`
      + (measures.energy !== null && measures.energy !== undefined ? ` · actuator work ${energyText(measures.energy)} · cost of transport ${costOfTransportText(measures.cost_of_transport)}` : ""));
    const holder = h("div", { id: "replay-canvas" });
    const play = h("button", { id: "replay-play" }, "Pause");
    const slider = h("input", { type: "range", min: 0, max: data.frames.length - 1, value: 0, id: "replay-slider" });
    const speed = h("select", { id: "replay-speed" }, [0.25, 0.5, 1, 2, 4].map((s) => h("option", { value: s, selected: s === 1 }, `${s}×`)));
    const clock = h("span", { class: "muted", id: "replay-clock" }, "0.00 s");
    // a co-designed robot (voxel-phase) has more than the paper's two phases: colour by hue
    const phases = new Set((data.phase || []).filter((p) => p !== null).map((p) => p.toFixed(4)));
    const byHue = phases.size > 2;
    this.state.phaseColours = byHue ? "hue" : "two";
    const legend = h("div", { class: "muted" },
      "materials:", h("span", { class: "legend-swatch", style: "background:#9bc59d" }), "soft",
      h("span", { class: "legend-swatch", style: "background:#4a4f55" }), "hard",
      ...(byHue
        ? [h("span", { class: "legend-swatch", style: "background:linear-gradient(90deg,#e33,#ee3,#3e3,#3ee,#33e,#e3e,#e33)" }),
          `actuated, coloured by phase (hue: 0 → 2π; ${phases.size} phases)`]
        : [h("span", { class: "legend-swatch", style: "background:#d1495b" }), "actuated (sine)",
          h("span", { class: "legend-swatch", style: "background:#2f6fb5" }), "actuated (anti-phase)"]));
    const springsBox = h("input", { type: "checkbox", id: "replay-springs" });
    const springsLabel = h("label", { class: "muted" }, springsBox, " springs");
    this.panel.replaceChildren(title, facts, holder, h("div", { class: "controls" }, play, slider, speed, clock, springsLabel), legend);
    return { label, holder, play, slider, speed, clock, springsBox, byHue };
  }

  // Plays `data` with `draw(frame)`: the play button, slider and speed, one frame per animation frame.
  play(data, ui, draw) {
    const state = this.state;
    Object.assign(state, { frame: 0, frames: data.frames.length, time: 0, playing: true, label: ui.label });
    const fps = (data.frames.length - 1) / Math.max(1e-9, data.times[data.times.length - 1]);
    ui.play.onclick = () => { state.playing = !state.playing; ui.play.textContent = state.playing ? "Pause" : "Play"; };
    ui.slider.oninput = () => { state.time = data.times[Number(ui.slider.value)]; state.playing = false; ui.play.textContent = "Play"; };
    ui.speed.onchange = () => { state.speed = Number(ui.speed.value); };
    state.drawn = false;
    let last = performance.now();
    const loop = (now) => {
      const elapsed = Math.max(0, (now - last) / 1000);  // rAF's clock may start before `last`
      last = now;
      const end = data.times[data.times.length - 1];
      if (state.playing) state.time = (state.time + elapsed * state.speed) % Math.max(end, 1e-9);
      const frame = Math.max(0, Math.min(data.frames.length - 1, Math.round(state.time * fps)));
      if (frame !== state.frame || !state.drawn) {
        state.frame = frame;
        state.drawn = true;
        draw(frame);
        ui.slider.value = frame;
        ui.clock.textContent = `${data.times[frame].toFixed(2)} s`;
      }
      this.raf = requestAnimationFrame(loop);
    };
    this.raf = requestAnimationFrame(loop);
    this.disposers.push(() => cancelAnimationFrame(this.raf));
  }

  // What the robot on screen holds (its loop, controls and scene) let go, the renderer kept.
  clear() {
    for (const fn of this.disposers.splice(0)) fn();
  }

  // Leaving the view: the robot and the renderer's GL context let go.
  dispose() {
    this.clear();
    if (this.renderer) {
      this.renderer.dispose();
      this.renderer.forceContextLoss();
    }
    this.renderer = undefined;
  }
}

// The scene of a replay: ground or terrain, springs, masses and (where the replay has faces)
// the shaded voxels, lit; a camera standing back in proportion to the robot's size.
function robotScene(data, byHue) {
  const masses = data.frames[0].length, springs = data.springs;
  const scene = new THREE.Scene();
  scene.background = new THREE.Color("#fbfcfd");
  const grid = new THREE.GridHelper(60, 60, 0x8d98a3, 0xbfc7cf);
  grid.rotation.x = Math.PI / 2;
  const ground = new THREE.Mesh(new THREE.PlaneGeometry(60, 60), new THREE.MeshBasicMaterial({ color: "#e3e8ed" }));
  ground.position.z = -0.002;  // the ground (z = 0) under the grid lines
  const surface = data.terrain && data.terrain.mesh ? terrainMesh(data.terrain.mesh) : null;
  scene.add(...(surface ? surface : [ground, grid]), new THREE.AmbientLight(0xffffff, 1.2));
  const geometry = new THREE.BufferGeometry();
  const positions = new Float32Array(springs.length * 6);
  geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
  geometry.setAttribute("color", new THREE.BufferAttribute(springColours(data, byHue), 3));
  const lines = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true }));
  const dots = new THREE.InstancedMesh(new THREE.SphereGeometry(0.06, 8, 6), new THREE.MeshBasicMaterial({ color: "#1d232a" }), masses);
  // shaded voxels by default, the springs (and masses) as an option
  const body = data.faces ? voxelMesh(data, byHue) : null;
  const sun = new THREE.DirectionalLight(0xffffff, 1.6);
  sun.position.set(-3, -5, 8);
  scene.add(lines, dots, sun, ...(body ? [body.mesh] : []));
  const world = { scene, lines, dots, body, positions, terrain: surface ? data.terrain.kind : "flat" };
  world.showSprings = (on) => {  // whether the springs show (they do where there is no body)
    lines.visible = dots.visible = on || !body;
    if (body) body.mesh.visible = !on;
    return on || !body;
  };
  // this robot's GPU buffers; its materials are left to the garbage collector: disposing them
  // would drop the shader programs the next robot's like materials use (compiling one again is
  // seconds in a software renderer)
  world.dispose = () => scene.traverse((node) => node.geometry?.dispose());
  const first = data.frames[0];
  world.centre = centreOf(first);
  const extent = Math.max(...[0, 1, 2].map((k) => Math.max(...first.map((p) => p[k])) - Math.min(...first.map((p) => p[k]))));
  const away = 1.2 * Math.max(1, extent / 2.5), c0 = world.centre;
  world.camera = new THREE.PerspectiveCamera(40, 16 / 9, 0.05, 500);
  world.camera.up.set(0, 0, 1);
  world.camera.position.set(c0[0] - 3 * away, c0[1] - 6 * away, c0[2] + 3.5 * away);
  return world;
}

// Each spring's colour (twice, one per end): by phase, or passive soft to hard by stiffness.
function springColours(data, byHue) {
  const springs = data.springs, colours = new Float32Array(springs.length * 6);
  const stiffness = data.stiffness, low = Math.min(...stiffness), high = Math.max(...stiffness);
  springs.forEach((_, s) => {
    const phase = data.phase ? data.phase[s] : null;
    let colour;
    if (phase !== null && phase !== undefined && byHue) {
      colour = new THREE.Color().setHSL((((phase / (2 * Math.PI)) % 1) + 1) % 1, 0.75, 0.5);
    } else if (phase !== null && phase !== undefined) colour = Math.cos(phase) >= 0 ? IN_PHASE : ANTI_PHASE;
    else colour = PASSIVE_SOFT.clone().lerp(PASSIVE_HARD, high > low ? (stiffness[s] - low) / (high - low) : 1);
    colours.set([colour.r, colour.g, colour.b, colour.r, colour.g, colour.b], s * 6);
  });
  return colours;
}

const centreOf = (frame) => frame.reduce((acc, p) => [acc[0] + p[0] / frame.length, acc[1] + p[1] / frame.length, acc[2] + p[2] / frame.length], [0, 0, 0]);

// `draw(frame)`: the masses, springs and body moved to a frame, the camera following the robot,
// the canvas sized to its holder (on the first frame of each robot, since the camera is new).
function drawer(data, world, renderer, controls, holder) {
  const { camera, positions, dots, body } = world;
  const matrix = new THREE.Matrix4();
  let sized = false;
  return (frame) => {
    const points = data.frames[frame];
    data.springs.forEach(([a, b], s) => positions.set([...points[a], ...points[b]], s * 6));
    world.lines.geometry.attributes.position.needsUpdate = true;
    points.forEach((p, m) => { matrix.makeTranslation(p[0], p[1], p[2]); dots.setMatrixAt(m, matrix); });
    dots.instanceMatrix.needsUpdate = true;
    body?.update(points);
    const c = centreOf(points);  // follow the robot: move camera and target with its centre
    if (controls) {
      const shift = new THREE.Vector3(c[0], c[1], 0).sub(new THREE.Vector3(controls.target.x, controls.target.y, 0));
      controls.target.add(shift);
      camera.position.add(shift);
      controls.update();
    }
    if (!renderer) return;
    const width = holder.clientWidth || 600;
    const resized = renderer.domElement.width !== Math.floor(width * devicePixelRatio);
    if (resized) {
      renderer.setPixelRatio(devicePixelRatio);
      renderer.setSize(width, 380, false);
    }
    if (resized || !sized) {  // this robot's camera is new: give it the canvas's shape
      camera.aspect = width / 380;
      camera.updateProjectionMatrix();
      sized = true;
    }
    renderer.render(world.scene, camera);
  };
}

// -- a sweep ---------------------------------------------------------------------------------------
