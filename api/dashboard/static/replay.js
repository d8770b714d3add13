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
    this.state = { frame: 0, frames: 0, time: 0, playing: false, speed: 1, renderer: null, label: "" };
    softevo.replay = this.state;
  }

  async load(url, label) {
    const data = await this.fetch(url);
    this.show(data, label(data));
    return data;
  }

  // fetch and show apart: the run view draws a new best with the summary that names it
  fetch(url) { return api(`${url}?fps=30`); }

  show(data, label) {
    this.data = data;
    this.loaded = true;
    this.build(label);
  }

  build(label) {
    const data = this.data;
    this.dispose();
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

    const state = this.state;
    Object.assign(state, { frame: 0, frames: data.frames.length, time: 0, playing: true, label });
    const fps = (data.frames.length - 1) / Math.max(1e-9, data.times[data.times.length - 1]);
    play.onclick = () => { state.playing = !state.playing; play.textContent = state.playing ? "Pause" : "Play"; };
    slider.oninput = () => { state.time = data.times[Number(slider.value)]; state.playing = false; play.textContent = "Play"; };
    speed.onchange = () => { state.speed = Number(speed.value); };

    let renderer;
    try {
      renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
      state.renderer = "webgl";
    } catch (error) {
      state.renderer = null;
      holder.append(h("p", { class: "error" }, "This browser cannot draw WebGL: ", String(error.message || error)));
    }
    const masses = data.frames[0].length;
    const springs = data.springs;
    const scene = new THREE.Scene();
    scene.background = new THREE.Color("#f4f6f8");
    const camera = new THREE.PerspectiveCamera(40, 16 / 9, 0.05, 500);
    camera.up.set(0, 0, 1);
    const grid = new THREE.GridHelper(60, 60, 0x8d98a3, 0xbfc7cf);
    grid.rotation.x = Math.PI / 2;
    const ground = new THREE.Mesh(new THREE.PlaneGeometry(60, 60), new THREE.MeshBasicMaterial({ color: "#e3e8ed" }));
    ground.position.z = -0.002;  // the ground (z = 0) under the grid lines
    scene.background = new THREE.Color("#fbfcfd");
    const surface = data.terrain && data.terrain.mesh ? terrainMesh(data.terrain.mesh) : null;
    state.terrain = surface ? data.terrain.kind : "flat";  // what the scene's ground is
    scene.add(...(surface ? surface : [ground, grid]), new THREE.AmbientLight(0xffffff, 1.2));
    const geometry = new THREE.BufferGeometry();
    const positions = new Float32Array(springs.length * 6);
    const colours = new Float32Array(springs.length * 6);
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
    geometry.setAttribute("position", new THREE.BufferAttribute(positions, 3));
    geometry.setAttribute("color", new THREE.BufferAttribute(colours, 3));
    const lines = new THREE.LineSegments(geometry, new THREE.LineBasicMaterial({ vertexColors: true }));
    const dots = new THREE.InstancedMesh(new THREE.SphereGeometry(0.06, 8, 6), new THREE.MeshBasicMaterial({ color: "#1d232a" }), masses);
    // shaded voxels by default, the springs (and masses) as an option
    const body = data.faces ? voxelMesh(data, byHue) : null;
    const sun = new THREE.DirectionalLight(0xffffff, 1.6);
    sun.position.set(-3, -5, 8);
    scene.add(lines, dots, sun, ...(body ? [body.mesh] : []));
    const showSprings = (on) => { lines.visible = dots.visible = on || !body; if (body) body.mesh.visible = !on; state.springs = on || !body; };
    showSprings(!body);
    state.voxels = body ? body.faces : 0;
    springsBox.checked = !body;
    springsBox.onchange = () => { showSprings(springsBox.checked); state.drawn = false; };
    const matrix = new THREE.Matrix4();
    let controls = null;
    if (renderer) {
      holder.append(renderer.domElement);
      controls = new OrbitControls(camera, renderer.domElement);
    }
    const first = data.frames[0];
    const centre = (frame) => frame.reduce((acc, p) => [acc[0] + p[0] / masses, acc[1] + p[1] / masses, acc[2] + p[2] / masses], [0, 0, 0]);
    const c0 = centre(first);
    // stand back in proportion to the robot's size, so a big box fits the view too
    const extent = Math.max(...[0, 1, 2].map((k) => Math.max(...first.map((p) => p[k])) - Math.min(...first.map((p) => p[k]))));
    const away = 1.2 * Math.max(1, extent / 2.5);
    camera.position.set(c0[0] - 3 * away, c0[1] - 6 * away, c0[2] + 3.5 * away);
    controls?.target.set(...c0);

    const draw = (frame) => {
      const points = data.frames[frame];
      springs.forEach(([a, b], s) => positions.set([...points[a], ...points[b]], s * 6));
      geometry.attributes.position.needsUpdate = true;
      points.forEach((p, m) => { matrix.makeTranslation(p[0], p[1], p[2]); dots.setMatrixAt(m, matrix); });
      dots.instanceMatrix.needsUpdate = true;
      body?.update(points);
      const c = centre(points);  // follow the robot: move camera and target with its centre
      if (controls) {
        const shift = new THREE.Vector3(c[0], c[1], 0).sub(new THREE.Vector3(controls.target.x, controls.target.y, 0));
        controls.target.add(shift);
        camera.position.add(shift);
        controls.update();
      }
      if (renderer) {
        const width = holder.clientWidth || 600;
        if (renderer.domElement.width !== Math.floor(width * devicePixelRatio)) {
          renderer.setPixelRatio(devicePixelRatio);
          renderer.setSize(width, 380, false);
          camera.aspect = width / 380;
          camera.updateProjectionMatrix();
        }
        renderer.render(scene, camera);
      }
    };
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
        slider.value = frame;
        clock.textContent = `${data.times[frame].toFixed(2)} s`;
      }
      this.raf = requestAnimationFrame(loop);
    };
    this.raf = requestAnimationFrame(loop);
    this.disposers = [() => cancelAnimationFrame(this.raf), () => controls?.dispose(), () => renderer?.dispose()];
  }

  dispose() {
    for (const fn of this.disposers || []) fn();
    this.disposers = [];
  }
}

// -- a sweep ---------------------------------------------------------------------------------------
