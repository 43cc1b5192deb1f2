// The Photos panel: calibrate the head on a front and a side photo (issue 17 item 4).
// Each photo is drawn in an SVG in its own pixels, with the head's box and feature points over it;
// dragging a box edge refits the guessed points (POST /api/photos/box; the dragged ones stay put),
// dragging a point moves it (x-y on the front, z-y on the side). "Find the face" places the front photo's
// points with the landmark model (POST /api/photos/find). Calibrate sends every point
// (POST /api/calibrate); the calibrated head is drawn beside the photos in a small three.js view
// wearing the blended texture (GET /api/texture-preview on the skin's texture coordinates).
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { ApiError, api, setStatus } from "./api.js";

const $ = (id) => document.getElementById(id);
const SVG = "http://www.w3.org/2000/svg";
const VIEWS = ["front", "side"];
const EDGES = ["left", "top", "right", "bottom"];
const POINT_RADIUS_PX = 3.5;   // on screen, whatever the photo's size
const MIN_BOX_PX = 8;          // in photo pixels
const DEBOUNCE_MS = 300;       // after a drag ends, before recalibrating
const panel = $("panel-photos");

const state = {
  loaded: false, sizes: {}, sideView: "left", guess: null, dragged: { front: {}, side: {} }, urls: {},
  calibrations: 0, textures: 0, calibrated: false, method: "dffd", report: null, exported: null,
  pending: 0, timer: null, again: false, running: false, editorVersion: document.body.dataset.version || "0",
};

function busy(delta) {
  state.pending += delta;
  panel.dataset.busy = state.pending > 0 ? "1" : "0";
}

function fail(e) {
  setStatus(e instanceof ApiError ? `error in ${e.where}: ${e.error}` : `error: ${e.message}`, "error");
}

async function postForm(path, form) {
  busy(+1);
  try {
    const r = await fetch(path, { method: "POST", body: form });
    let body = null;
    try { body = await r.json(); } catch { body = null; }
    if (!r.ok) {
      throw new ApiError(body && body.error ? body.error : `HTTP ${r.status}`, body && body.where ? body.where : path,
                         r.status);
    }
    return body;
  } finally { busy(-1); }
}

async function call(path, body) {
  busy(+1);
  try { return await api(path, body); } finally { busy(-1); }
}

// ---- the photos with their box and points --------------------------------------------------------

function el(name, attrs = {}, parent = null) {
  const e = document.createElementNS(SVG, name);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
  if (parent) parent.append(e);
  return e;
}

function svgOf(view) { return $(`svg-${view}`); }

// photo pixels per screen pixel of a view's SVG (it is scaled to fit its box)
function scaleOf(view) {
  const svg = svgOf(view), r = svg.getBoundingClientRect();
  return r.width > 0 && svg.viewBox.baseVal ? svg.viewBox.baseVal.width / r.width : 1;
}

function toPhoto(view, clientX, clientY) {
  const svg = svgOf(view);
  const p = svg.createSVGPoint();
  p.x = clientX; p.y = clientY;
  const q = p.matrixTransform(svg.getScreenCTM().inverse());
  return [q.x, q.y];
}

function toScreen(view, x, y) {
  const svg = svgOf(view);
  const p = svg.createSVGPoint();
  p.x = x; p.y = y;
  const q = p.matrixTransform(svg.getScreenCTM());
  return { x: q.x, y: q.y };
}

function drawPhoto(view) {
  const svg = svgOf(view);
  const [w, h] = state.sizes[view];
  svg.replaceChildren();
  svg.setAttribute("preserveAspectRatio", "xMidYMid meet");
  fitViewBox(view);
  el("image", { href: state.urls[view], x: 0, y: 0, width: w, height: h, "data-testid": `photo-${view}-image` }, svg);
  el("rect", { class: "box", "data-testid": `box-${view}` }, svg);
  for (const edge of EDGES) el("line", { class: "edge", "data-edge": edge, "data-testid": `box-${view}-${edge}` }, svg);
  const points = el("g", { class: "points" }, svg);
  for (const label of Object.keys(state.guess[view])) {
    const c = el("circle", { class: "fp", "data-label": label, "data-testid": `fp-${view}-${label}` }, points);
    const t = el("title", {}, c);
    t.textContent = label;
  }
  el("text", { class: "drag-label" }, svg);
  placeOverlay(view);
}

// the photo and its box with a margin (a photo often cuts the neck: the box's bottom edge lies below it)
function fitViewBox(view) {
  const [w, h] = state.sizes[view];
  const [x0, y0, x1, y1] = state.guess.box[view];
  const m = 0.03 * Math.max(w, h);
  const a = Math.min(0, x0 - m), b = Math.min(0, y0 - m), c = Math.max(w, x1 + m), d = Math.max(h, y1 + m);
  const svg = svgOf(view);
  svg.setAttribute("viewBox", `${a} ${b} ${c - a} ${d - b}`);
  svg.style.aspectRatio = `${c - a} / ${d - b}`;
}

// move the box, its edges and the points to where the state has them
function placeOverlay(view) {
  const svg = svgOf(view);
  const [x0, y0, x1, y1] = state.guess.box[view];
  const rect = svg.querySelector("rect.box");
  rect.setAttribute("x", x0); rect.setAttribute("y", y0);
  rect.setAttribute("width", x1 - x0); rect.setAttribute("height", y1 - y0);
  const ends = { left: [x0, y0, x0, y1], right: [x1, y0, x1, y1], top: [x0, y0, x1, y0], bottom: [x0, y1, x1, y1] };
  for (const line of svg.querySelectorAll("line.edge")) {
    const [a, b, c, d] = ends[line.dataset.edge];
    line.setAttribute("x1", a); line.setAttribute("y1", b); line.setAttribute("x2", c); line.setAttribute("y2", d);
  }
  const r = POINT_RADIUS_PX * scaleOf(view);
  const dragged = state.dragged[view];
  for (const c of svg.querySelectorAll("circle.fp")) {
    const [x, y] = state.guess[view][c.dataset.label];
    c.setAttribute("cx", x); c.setAttribute("cy", y); c.setAttribute("r", r);
    c.classList.toggle("dragged", c.dataset.label in dragged);
  }
}

function showLabel(view, label, x, y) {
  const t = svgOf(view).querySelector("text.drag-label");
  if (!label) { t.textContent = ""; return; }
  const k = scaleOf(view);
  t.textContent = label;
  t.setAttribute("x", x + 6 * k); t.setAttribute("y", y - 6 * k);
  t.setAttribute("font-size", 12 * k);
}

function installDragging(view) {
  const svg = svgOf(view);
  let drag = null;
  svg.addEventListener("pointerdown", (ev) => {
    if (!state.loaded || ev.button !== 0) return;
    const t = ev.target;
    if (t.matches("circle.fp")) drag = { kind: "point", label: t.dataset.label };
    else if (t.matches("line.edge")) drag = { kind: "edge", edge: t.dataset.edge, box: [...state.guess.box[view]] };
    else return;
    ev.preventDefault();
    svg.setPointerCapture(ev.pointerId);
    svg.classList.add("dragging");
  });
  svg.addEventListener("pointermove", (ev) => {
    if (!drag) return;
    const [x, y] = toPhoto(view, ev.clientX, ev.clientY);
    if (drag.kind === "point") {
      state.guess[view][drag.label] = [x, y];
      state.dragged[view][drag.label] = [x, y];
      showLabel(view, drag.label, x, y);
    } else {
      state.guess.box[view] = movedBox(drag.box, drag.edge, x, y);
    }
    placeOverlay(view);
  });
  const end = async (ev) => {
    if (!drag) return;
    const d = drag;
    drag = null;
    svg.classList.remove("dragging");
    if (svg.hasPointerCapture(ev.pointerId)) svg.releasePointerCapture(ev.pointerId);
    showLabel(view, null);
    if (d.kind === "point") {
      panel.dataset.drags = String(Number(panel.dataset.drags || 0) + 1);
      scheduleCalibration();
    } else {
      await refit(view);
    }
  };
  svg.addEventListener("pointerup", end);
  svg.addEventListener("pointercancel", end);
}

function movedBox(box, edge, x, y) {
  const [x0, y0, x1, y1] = box;
  const out = [x0, y0, x1, y1];
  if (edge === "left") out[0] = Math.min(x, x1 - MIN_BOX_PX);
  if (edge === "right") out[2] = Math.max(x, x0 + MIN_BOX_PX);
  if (edge === "top") out[1] = Math.min(y, y1 - MIN_BOX_PX);
  if (edge === "bottom") out[3] = Math.max(y, y0 + MIN_BOX_PX);
  return out;
}

async function refit(view) {
  try {
    const { guess } = await call("/api/photos/box", { view, box: state.guess.box[view], dragged: state.dragged });
    state.guess = guess;
    panel.dataset.refits = String(Number(panel.dataset.refits || 0) + 1);
    fitViewBox(view);
    VIEWS.forEach(placeOverlay);
    const held = guess.dragged[view].length;
    setStatus(`${view} box refitted: the guessed points follow it${held ? `; the ${held} dragged by hand stay put` : ""}`, "ok");
    scheduleCalibration();
  } catch (e) {
    const { guess } = await call("/api/photos").catch(() => ({ guess: null }));  // back to what the server has
    if (guess) { state.guess = guess; VIEWS.forEach(placeOverlay); }
  }
}

async function loadPhotos() {
  const files = { front: $("photo-front").files[0], side: $("photo-side").files[0] };
  if (!files.front || !files.side) {
    setStatus("choose a front and a side photo first", "error");
    return;
  }
  const form = new FormData();
  form.append("front", files.front, files.front.name);
  form.append("side", files.side, files.side.name);
  form.append("side_view", $("photo-side-view").value);
  try {
    const answer = await postForm("/api/photos", form);
    for (const v of VIEWS) {
      if (state.urls[v]) URL.revokeObjectURL(state.urls[v]);
      state.urls[v] = URL.createObjectURL(files[v]);
      state.sizes[v] = answer[v].size;
    }
    Object.assign(state, { loaded: true, sideView: answer.side_view, guess: answer.guess, dragged: { front: {}, side: {} },
                           calibrations: 0 });  // new photos: nothing is recalibrated before Calibrate is pressed
    setCalibrated(false, null);
    VIEWS.forEach(drawPhoto);
    $("btn-calibrate").disabled = false;
    $("btn-photos-find").disabled = false;
    panel.dataset.loaded = "1";
    setStatus(`photos loaded: ${Object.keys(answer.guess.front).length} points on the front, `
      + `${Object.keys(answer.guess.side).length} on the side; drag the box edges and the points`, "ok");
  } catch (e) { fail(e); }
}

async function findFace() {
  // the landmark model places the front photo's points (POST /api/photos/find); they count as dragged, so a
  // later box drag leaves them; the box is fitted to them and the points not found (ears, hairline) follow
  try {
    const { guess, found } = await call("/api/photos/find", { view: "front" });
    state.guess = guess;
    state.dragged.front = Object.fromEntries(guess.dragged.front.map((label) => [label, guess.front[label]]));
    panel.dataset.finds = String(Number(panel.dataset.finds || 0) + 1);
    fitViewBox("front");
    VIEWS.forEach(placeOverlay);
    setStatus(`face found: ${found.length} points placed on the front photo; the others follow the box. `
      + "Drag any point that is off", "ok");
    scheduleCalibration();
  } catch (e) { fail(e); }
}

// ---- calibration ---------------------------------------------------------------------------------

function scheduleCalibration() {
  if (!state.calibrations || !$("calib-live").checked) return;
  clearTimeout(state.timer);
  state.timer = setTimeout(calibrate, DEBOUNCE_MS);
}

async function calibrate() {
  clearTimeout(state.timer);
  if (state.running) { state.again = true; return; }
  state.running = true;
  try {
    const method = $("calib-method").value;
    const answer = await call("/api/calibrate", { front: state.guess.front, side: state.guess.side, method });
    state.calibrations += 1;
    state.method = method;
    state.report = answer.report;
    live.show(answer);
    setCalibrated(true, null);
    const r = answer.report;
    $("calib-report").textContent = `${method}: ${r.points} points, largest miss ${r.max_point_error_mm.toFixed(3)} mm`;
    setStatus(`calibrated (${method})`, "ok");
    await loadTexture();
  } catch (e) { /* shown in the status bar by api() */ } finally {
    state.running = false;
    if (state.again) { state.again = false; calibrate(); }
  }
}

async function loadTexture() {
  busy(+1);
  try {
    const r = await fetch("/api/texture-preview");
    if (!r.ok) {
      const body = await r.json().catch(() => ({}));
      throw new ApiError(body.error || `HTTP ${r.status}`, body.where || "texture-preview", r.status);
    }
    const url = URL.createObjectURL(await r.blob());
    const img = $("texture-preview");
    await new Promise((ok, bad) => { img.onload = ok; img.onerror = bad; img.src = url; });
    live.setTexture(img);
    state.textures += 1;
    panel.dataset.textures = String(state.textures);
  } catch (e) { fail(e); } finally { busy(-1); }
}

function setCalibrated(on, cleared) {
  state.calibrated = on;
  panel.dataset.calibrated = on ? String(state.calibrations) : "0";
  panel.dataset.cleared = cleared ? "1" : "0";
  $("btn-export").disabled = !on;
  $("photos-state").textContent = on ? `calibrated (${state.method})`
    : cleared ? `calibration cleared: ${cleared}` : state.loaded ? "photos loaded, not calibrated" : "";
  if (!on) { live.clear(); $("texture-preview").removeAttribute("src"); if (!cleared) $("calib-report").textContent = ""; }
}

async function exportFdp() {
  try {
    const { files, folder } = await call("/api/export", { name: $("export-name").value });
    state.exported = files;
    const list = $("exported");
    list.replaceChildren(...files.map((f) => {
      const li = document.createElement("li");
      li.dataset.file = f;
      li.textContent = f;
      return li;
    }));
    list.title = folder;
    setStatus(`exported ${files.join(", ")} into ${folder}`, "ok");
  } catch (e) { /* shown by api() */ }
}

// a mesh edit, load or upload clears the calibration on the server: ask it after the editor shows a new mesh
new MutationObserver(async () => {
  if (document.body.dataset.version === state.editorVersion) return;
  state.editorVersion = document.body.dataset.version;
  if (!state.calibrated) return;
  try {
    const s = await call("/api/photos");
    if (!s.calibrated) {
      setCalibrated(false, s.cleared);
      setStatus(`photo calibration cleared: ${s.cleared}; calibrate again`, "info");
    }
  } catch { /* shown by api() */ }
}).observe(document.body, { attributes: true, attributeFilter: ["data-version"] });

// ---- the calibrated head in its own small view ---------------------------------------------------

class LiveHead {
  constructor(container) {
    this.container = container;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setClearColor(0x2b2f36);
    this.renderer.domElement.dataset.testid = "calib-canvas";
    this.renderer.domElement.id = "calib-canvas";
    container.prepend(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(30, 1, 0.1, 1e5);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x555555, 2.0));
    const light = new THREE.DirectionalLight(0xffffff, 1.2);
    light.position.set(0.3, 0.4, 1);
    this.camera.add(light);
    this.scene.add(this.camera);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener("change", () => this.render());
    this.skin = null; this.other = null; this.texture = null; this.framed = false;
    this.updates = 0;
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth), h = Math.max(1, this.container.clientHeight - 18);
    this.renderer.setSize(w, h);
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.render();
  }

  render() { this.renderer.render(this.scene, this.camera); }

  clear() {
    for (const m of [this.skin, this.other]) if (m) { this.scene.remove(m); m.geometry.dispose(); m.material.dispose(); }
    this.skin = this.other = null;
    if (this.texture) { this.texture.dispose(); this.texture = null; }
    this.framed = false;
    this.render();
  }

  // answer: /api/calibrate's {positions, skin: {indices, uvs}, other_indices}
  show(answer) {
    const p = answer.positions, idx = answer.skin.indices;
    const corners = new Float32Array(idx.length * 3);
    for (let k = 0; k < idx.length; k++) corners.set(p.slice(idx[k] * 3, idx[k] * 3 + 3), k * 3);
    if (!this.skin) {
      const g = new THREE.BufferGeometry();
      g.setAttribute("position", new THREE.BufferAttribute(corners, 3));
      g.setAttribute("uv", new THREE.BufferAttribute(new Float32Array(answer.skin.uvs), 2));
      this.skin = new THREE.Mesh(g, new THREE.MeshStandardMaterial({ color: 0xd9b49c, roughness: 0.9, side: THREE.DoubleSide }));
      const o = new THREE.BufferGeometry();
      o.setAttribute("position", new THREE.BufferAttribute(new Float32Array(p), 3));
      o.setIndex(answer.other_indices);
      this.other = new THREE.Mesh(o, new THREE.MeshStandardMaterial({ color: 0x9aa4b0, flatShading: true, roughness: 0.8 }));
      this.scene.add(this.skin, this.other);
      if (this.texture) this.setMap(this.texture);
    } else {
      this.skin.geometry.attributes.position.array.set(corners);
      this.skin.geometry.attributes.position.needsUpdate = true;
      this.other.geometry.attributes.position.array.set(p);
      this.other.geometry.attributes.position.needsUpdate = true;
    }
    this.skin.geometry.computeVertexNormals();
    this.other.geometry.computeVertexNormals();
    this.skin.geometry.computeBoundingBox();
    this.positions = Float32Array.from(p);
    if (!this.framed) this.frame();
    this.updates += 1;
    panel.dataset.liveUpdates = String(this.updates);
    this.render();
  }

  frame() {
    const box = this.skin.geometry.boundingBox;
    const c = box.getCenter(new THREE.Vector3()), size = box.getSize(new THREE.Vector3());
    const d = (Math.max(size.x, size.y) / (2 * Math.tan((this.camera.fov * Math.PI) / 360))) * 1.15;
    this.camera.position.set(c.x + 0.35 * d, c.y, c.z + 0.94 * d);
    this.camera.near = d / 100; this.camera.far = d * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(c);
    this.controls.update();
    this.framed = true;
  }

  setTexture(img) {
    if (this.texture) this.texture.dispose();
    this.texture = new THREE.Texture(img);
    this.texture.colorSpace = THREE.SRGBColorSpace;
    this.texture.needsUpdate = true;  // flipY (the default): v = 0 is the image's bottom row, as the bake has it
    if (this.skin) this.setMap(this.texture);
    this.render();
  }

  setMap(texture) {
    this.skin.material.map = texture;
    this.skin.material.color.set(0xffffff);
    this.skin.material.needsUpdate = true;
  }
}

const live = new LiveHead($("calib-view"));

// ---- wiring --------------------------------------------------------------------------------------

$("btn-photos-toggle").addEventListener("click", () => {
  const open = panel.dataset.open !== "1";
  panel.dataset.open = open ? "1" : "0";
  $("btn-photos-toggle").setAttribute("aria-expanded", String(open));
  $("btn-photos-toggle").textContent = open ? "Photos ▾" : "Photos ▸";
  requestAnimationFrame(() => { if (state.loaded) VIEWS.forEach(placeOverlay); live.resize(); });
});
$("btn-photos-load").addEventListener("click", loadPhotos);
$("btn-photos-find").addEventListener("click", findFace);
$("btn-calibrate").addEventListener("click", calibrate);
$("btn-export").addEventListener("click", exportFdp);
new ResizeObserver(() => { if (state.loaded) VIEWS.forEach(placeOverlay); }).observe(svgOf("front"));
VIEWS.forEach(installDragging);
for (const view of VIEWS) {  // until a photo is loaded
  const svg = svgOf(view);
  svg.setAttribute("viewBox", "0 0 100 100");
  const t = el("text", { x: 50, y: 50, class: "placeholder", "text-anchor": "middle" }, svg);
  t.textContent = `no ${view} photo`;
}
panel.dataset.ready = "1";

// for tests and the console: screen positions of what the page draws over the photos
window.photos = {
  state, live, scale: scaleOf,
  screenOfPoint: (view, label) => toScreen(view, ...state.guess[view][label]),
  // t: how far along the edge (0: its top or left end)
  screenOfEdge: (view, edge, t = 0.5) => {
    const [x0, y0, x1, y1] = state.guess.box[view];
    const ys = y0 + t * (y1 - y0), xs = x0 + t * (x1 - x0);
    const at = { left: [x0, ys], right: [x1, ys], top: [xs, y0], bottom: [xs, y1] };
    return toScreen(view, ...at[edge]);
  },
  photoOfScreen: (view, x, y) => toPhoto(view, x, y),
};
