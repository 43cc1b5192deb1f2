// The face model editor page: wires the panels to the API, the view and the pointer.
import { api, setStatus, upload } from "./api.js";
import { View, partColor } from "./view.js";
import { installPointer, holeLoop, cornersOf, facesWithin } from "./select.js";

const $ = (id) => document.getElementById(id);
const FAPS = [
  [3, "open_jaw", 0, 1080], [12, "raise_l_cornerlip", -600, 600], [13, "raise_r_cornerlip", -600, 600],
  [19, "close_t_l_eyelid", -300, 1080], [20, "close_t_r_eyelid", -300, 1080],
  [31, "raise_l_i_eyebrow", -900, 900], [32, "raise_r_i_eyebrow", -900, 900],
];
const VISEMES = ["none", "PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR", "AA", "E", "ih", "oh", "ou"];
const EXPRESSIONS = ["neutral", "joy", "sadness", "anger", "fear", "disgust", "surprise"];
const FAPU_ROWS = [["IRISD0", "iris diameter"], ["ES0", "eye separation"], ["ENS0", "eye-nose separation"],
                   ["MNS0", "mouth-nose separation"], ["MW0", "mouth width"]];

// selected: faces (Faces mode); vertices: vertices (Vertices mode); moveMode: the gizmo is shown
const state = {
  model: null, mode: "faces", selected: new Set(), vertices: new Set(), armed: null, featurePoints: [],
  posed: false, version: 0, poseVersion: 0, fapu: null, problems: null, boxMode: false, moveMode: false,
  lastSave: null, drag: null,
};
const view = new View($("viewport"), $("labels"));

// keepSelection: keep it when the edit kept the vertex and face numbering (same counts)
function show(model, { frame = false, keepSelection = false } = {}) {
  const old = state.model;
  const same = old && old.counts.vertices === model.counts.vertices && old.counts.triangles === model.counts.triangles;
  state.model = model;
  if (!keepSelection || !same) { state.selected = new Set(); state.vertices = new Set(); }
  resetPose();
  view.setModel(model, model.positions, { frame });
  view.setColors(state.selected);
  $("counts").textContent = `${model.counts.vertices} vertices, ${model.counts.triangles} faces, `
    + `${Object.keys(model.points).length}/84 points`;
  $("btn-undo").disabled = !model.can_undo;
  $("btn-redo").disabled = !model.can_redo;
  showParts();
  showSelection();
  showPoints();
  state.version += 1;
  document.body.dataset.version = String(state.version);
  refreshFapu();
}

function showParts() {
  const list = $("parts"), pick = $("part-select");
  list.replaceChildren(); pick.replaceChildren();
  const counts = new Array(state.model.parts.length).fill(0);
  for (const p of state.model.triangle_parts) counts[p] += 1;
  state.model.parts.forEach((name, i) => {
    const li = document.createElement("li");
    li.dataset.part = name;
    const sw = document.createElement("span");
    sw.className = "swatch";
    sw.style.background = `#${partColor(name).toString(16).padStart(6, "0")}`;
    li.append(sw, `${name} (${counts[i]})`);
    list.append(li);
    const o = document.createElement("option");
    o.value = o.textContent = name;
    pick.append(o);
  });
}

function showSelection() {
  const faces = state.mode === "faces", n = faces ? state.selected.size : state.vertices.size;
  $("sel-count").textContent = `${n} ${faces ? "faces" : "vertices"} selected`;
  $("sel-count").dataset.count = String(n);
  $("sel-count").dataset.mode = state.mode;
  view.setColors(faces ? state.selected : new Set(facesWithin(state.model.indices, state.vertices)));
  view.markVertices(faces ? [] : [...state.vertices]);
  showMove();
}

// faces or vertices, by the mode
function select(items, add) {
  const set = state.mode === "faces" ? "selected" : "vertices";
  if (!add) state[set] = new Set();
  for (const i of items) state[set].add(i);
  showSelection();
}

function toggle(item) {
  const set = state.mode === "faces" ? state.selected : state.vertices;
  if (set.has(item)) set.delete(item); else set.add(item);
  showSelection();
}

function setMode(mode) {
  if (mode === state.mode) return;
  // the selection carries over: faces give their corners, vertices the faces they wholly span
  if (state.model && mode === "vertices") state.vertices = new Set(cornersOf(state.model.indices, state.selected));
  else if (state.model) state.selected = new Set(facesWithin(state.model.indices, state.vertices));
  state.mode = mode;
  for (const m of ["faces", "vertices"]) {
    $(`btn-mode-${m}`).classList.toggle("on", m === mode);
    $(`btn-mode-${m}`).setAttribute("aria-pressed", String(m === mode));
  }
  view.showVertexDots(mode === "vertices");
  $("labels").classList.toggle("dim", mode === "vertices");
  if (state.model) showSelection();
}

// ---- moving vertices ------------------------------------------------------------------------------

// what a move moves: the selected vertices, or the corners of the selected faces
function moveSet() {
  if (!state.model) return [];
  return state.mode === "vertices" ? [...state.vertices].sort((a, b) => a - b)
                                   : cornersOf(state.model.indices, state.selected);
}

function centroid(vertices) {
  const p = state.model.positions, c = [0, 0, 0];
  for (const v of vertices) for (let k = 0; k < 3; k++) c[k] += p[v * 3 + k];
  return c.map((x) => x / vertices.length);
}

function showMove(centre = null) {
  const vs = moveSet();
  const c = centre || (vs.length ? centroid(vs) : null);
  for (const [k, axis] of ["x", "y", "z"].entries()) {
    const input = $(`move-${axis}`);
    input.disabled = !c;
    input.value = input.dataset.shown = c ? c[k].toFixed(3) : "";
  }
  $("btn-move-to").disabled = !c;
  if (!state.drag) view.placeGizmo(state.moveMode && c ? c : null);
}

function moveBy(vertices, delta, how) {
  if (!vertices.length) { setStatus("select vertices (or faces) to move", "error"); return Promise.resolve(null); }
  if (delta.every((d) => d === 0)) { setStatus("nothing to move: the centre is already there", "info"); return Promise.resolve(null); }
  return edit("move_vertices", { vertices, delta }, { keepSelection: true }).then((m) => {
    if (m) setStatus(`${how}: moved ${vertices.length} vertices by `
      + `(${delta.map((d) => d.toFixed(3)).join(", ")})`, "ok");
    return m;
  });
}

function moveTo() {
  const vs = moveSet();
  if (!vs.length) { moveBy(vs, [0, 0, 0], ""); return; }
  const fields = ["x", "y", "z"].map((a) => $(`move-${a}`));
  const target = fields.map((f) => Number(f.value));
  if (!fields.every((f, k) => f.value.trim() !== "" && Number.isFinite(target[k]))) {
    setStatus("move: x, y and z must be numbers", "error"); return;
  }
  const c = centroid(vs);
  // a field left as shown (rounded to 3 decimals) moves nothing along its axis
  moveBy(vs, fields.map((f, k) => (f.value === f.dataset.shown ? 0 : target[k] - c[k])), "numeric move");
}

// the gizmo's drag previews the move on the shown mesh; its release applies it through the API (undoable)
function wireGizmo() {
  const g = view.gizmo;
  g.addEventListener("mouseDown", () => {
    const vertices = moveSet();
    state.drag = { vertices, from: view.pivot.position.toArray(), base: Float64Array.from(state.model.positions) };
  });
  g.addEventListener("objectChange", () => {
    const d = state.drag;
    if (!d) return;
    const at = view.pivot.position.toArray(), delta = at.map((x, k) => x - d.from[k]);
    const p = Float64Array.from(d.base);
    for (const v of d.vertices) for (let k = 0; k < 3; k++) p[v * 3 + k] += delta[k];
    view.setPositions(p);
    for (const [k, axis] of ["x", "y", "z"].entries()) $(`move-${axis}`).value = at[k].toFixed(3);
  });
  g.addEventListener("mouseUp", () => {
    const d = state.drag;
    if (!d) return;
    const delta = view.pivot.position.toArray().map((x, k) => x - d.from[k]);
    state.drag = null;
    if (delta.every((x) => Math.abs(x) < 1e-9)) { showMove(); return; }
    moveBy(d.vertices, delta, "dragged").then((m) => { if (!m) show(state.model, { keepSelection: true }); });
  });
}

function toggleMoveMode() {
  state.moveMode = !state.moveMode;
  $("btn-move-mode").classList.toggle("on", state.moveMode);
  $("btn-move-mode").setAttribute("aria-pressed", String(state.moveMode));
  showMove();
  if (state.moveMode && !moveSet().length) setStatus("move: select vertices or faces to show the gizmo", "info");
}

async function edit(op, args, { keepSelection = false } = {}) {
  try {
    const model = await api("/api/edit", { edit: { op, ...args } });
    show(model, { keepSelection });
    setStatus(`${op.replace(/_/g, " ")}: done`, "ok");
    return model;
  } catch { return null; }
}

// ---- feature points -------------------------------------------------------------------------------

function showPoints() {
  const placed = state.model ? state.model.points : {};
  for (const b of document.querySelectorAll("#fp-list button[data-label]")) {
    const label = b.dataset.label;
    b.classList.toggle("placed", label in placed);
    b.classList.toggle("armed", label === state.armed);
    b.dataset.placed = label in placed ? "1" : "0";
  }
  $("fp-count").textContent = `${Object.keys(placed).length}/84 placed`;
  const fp = state.featurePoints.find((p) => p.label === state.armed);
  $("fp-current").textContent = fp
    ? `${fp.label}: ${fp.description}${fp.label in placed ? ` (vertex ${placed[fp.label]})` : " (not placed)"}`
      + " — click the mesh to place it"
    : "pick a label, then click the mesh";
}

function arm(label) {
  state.armed = state.armed === label ? null : label;
  view.setPicked(state.armed);
  showPoints();
}

async function loadFeaturePoints() {
  const { points } = await api("/api/feature-points");
  state.featurePoints = points;
  const groups = new Map();
  for (const p of points) {
    if (!groups.has(p.group)) groups.set(p.group, []);
    groups.get(p.group).push(p);
  }
  const list = $("fp-list");
  list.replaceChildren();
  for (const [group, ps] of groups) {
    const d = document.createElement("details");
    d.dataset.group = String(group);
    d.open = true;
    const s = document.createElement("summary");
    s.textContent = `group ${group}`;
    d.append(s);
    for (const p of ps) {
      const b = document.createElement("button");
      b.type = "button";
      b.textContent = p.label;
      b.title = `${p.description}${p.side ? ` (${p.side}; mirror ${p.mirror})` : ""}`;
      b.dataset.label = p.label;
      b.dataset.testid = `fp-${p.label}`;
      b.id = `fp-${p.label.replace(".", "-")}`;
      b.addEventListener("click", () => arm(p.label));
      d.append(b);
    }
    list.append(d);
  }
}

async function refreshFapu() {
  const table = $("fapu-table");
  try {
    const { fapu } = await api("/api/fapu", undefined, { quiet: true });
    state.fapu = fapu;
    $("fapu-note").textContent = "";
    for (const [key] of FAPU_ROWS) {
      const v = fapu[key];
      $(`fapu-${key}`).textContent = v == null ? "—" : v.toFixed(3);
      $(`fapu-${key}-unit`).textContent = v == null ? "—" : (v / 1024).toFixed(5);
    }
  } catch (e) {
    state.fapu = null;
    $("fapu-note").textContent = e.error || e.message;
    for (const [key] of FAPU_ROWS) { $(`fapu-${key}`).textContent = "—"; $(`fapu-${key}-unit`).textContent = "—"; }
  }
  table.dataset.version = String(state.version);
}

// ---- the try panel --------------------------------------------------------------------------------

let poseTimer = null, poseSeq = 0;

function poseRequest() {
  const faps = {};
  for (const [n] of FAPS) {
    const v = Number($(`fap-${n}`).value);
    $(`fap-${n}-value`).textContent = String(v);
    if (v !== 0) faps[n] = v;
  }
  const body = { faps };
  if ($("viseme").value) body.viseme = $("viseme").value;
  if ($("expression").value) body.expression = $("expression").value;
  return body;
}

function schedulePose() {
  clearTimeout(poseTimer);
  poseTimer = setTimeout(pose, 60);
}

async function pose() {
  if (!state.model) return;
  const body = poseRequest();
  const seq = ++poseSeq;
  try {
    const { positions } = await api("/api/pose", body);
    if (seq !== poseSeq) return;
    state.posed = Object.keys(body.faps).length > 0 || !!body.viseme || !!body.expression;
    view.setPositions(positions);
    state.poseVersion += 1;
    document.body.dataset.poseVersion = String(state.poseVersion);
    setStatus(state.posed ? "posed (edits apply to the neutral mesh)" : "neutral", "ok");
  } catch { /* shown */ }
}

function resetPose() {
  for (const [n] of FAPS) { $(`fap-${n}`).value = "0"; $(`fap-${n}-value`).textContent = "0"; }
  $("viseme").value = ""; $("expression").value = "";
  state.posed = false;
}

function buildTryPanel() {
  const box = $("fap-sliders");
  for (const [n, name, lo, hi] of FAPS) {
    const row = document.createElement("label");
    row.className = "slider";
    row.innerHTML = `<span>FAP ${n} ${name}</span>
      <input type="range" id="fap-${n}" data-testid="fap-${n}" min="${lo}" max="${hi}" step="10" value="0">
      <output id="fap-${n}-value">0</output>`;
    box.append(row);
    row.querySelector("input").addEventListener("input", schedulePose);
  }
  for (const [id, names] of [["viseme", VISEMES], ["expression", EXPRESSIONS]]) {
    const sel = $(id);
    const none = document.createElement("option");
    none.value = ""; none.textContent = `(no ${id})`;
    sel.append(none);
    for (const v of names) { const o = document.createElement("option"); o.value = o.textContent = v; sel.append(o); }
    sel.addEventListener("change", schedulePose);
  }
  $("btn-pose-reset").addEventListener("click", () => { resetPose(); pose(); });
  const rows = $("fapu-rows");
  for (const [key, what] of FAPU_ROWS) {
    const tr = document.createElement("tr");
    tr.innerHTML = `<th title="${what}">${key}</th><td id="fapu-${key}" data-testid="fapu-${key}">—</td>`
      + `<td id="fapu-${key}-unit">—</td>`;
    rows.append(tr);
  }
}

// ---- wiring -----------------------------------------------------------------------------------------

function onClick(hit, add) {
  if (!state.model) return;
  if (!hit) { if (!add && !state.armed) select([], false); return; }
  if (state.armed) {
    const label = state.armed;
    edit("assign_point", { label, vertex: hit.vertex }, { keepSelection: true }).then((m) => {
      if (m) setStatus(`placed ${label} at vertex ${hit.vertex}`, "ok");
    });
    return;
  }
  const item = state.mode === "faces" ? hit.face : hit.vertex;
  if (add) toggle(item); else select([item], false);
}

function selectedList() { return [...state.selected].sort((a, b) => a - b); }

function wire() {
  $("btn-load-head").addEventListener("click", async () => {
    try { show(await api("/api/load", { source: "head" }), { frame: true }); setStatus("loaded the head", "ok"); } catch { /* shown */ }
  });
  $("upload-file").addEventListener("change", async (e) => {
    const files = [...e.target.files];
    if (!files.length) return;
    try {
      const model = await upload(files);
      show(model, { frame: true });
      const others = files.length - 1;
      setStatus(`loaded ${model.source}${others ? ` with ${others} more file${others > 1 ? "s" : ""}` : ""}`, "ok");
    } catch { /* shown */ }
    e.target.value = "";
  });
  $("btn-frame").addEventListener("click", () => view.frame());
  $("btn-box-mode").addEventListener("click", () => {
    state.boxMode = !state.boxMode;
    $("btn-box-mode").classList.toggle("on", state.boxMode);
    $("btn-box-mode").setAttribute("aria-pressed", String(state.boxMode));
  });
  $("btn-clear-sel").addEventListener("click", () => select([], false));
  $("btn-mode-faces").addEventListener("click", () => setMode("faces"));
  $("btn-mode-vertices").addEventListener("click", () => setMode("vertices"));
  $("btn-grow").addEventListener("click", grow);
  $("btn-delete-faces").addEventListener("click", deleteFaces);
  $("btn-delete-vertices").addEventListener("click", deleteVertices);
  $("btn-split").addEventListener("click", () => {
    const faces = selectedFaces();
    if (!faces.length) { setStatus("select faces (or the vertices around them) to split off", "error"); return; }
    edit("split_part", { faces, name: $("part-name").value.trim() });
  });
  $("btn-delete-part").addEventListener("click", () => edit("delete_part", { name: $("part-select").value }));
  $("btn-rename-part").addEventListener("click", () => {
    const name = $("part-select").value, to = $("rename-to").value.trim();
    if (!to) { setStatus("rename: type the part's new name", "error"); return; }
    edit("rename_part", { name, to }, { keepSelection: true }).then((m) => {
      if (m) { $("part-select").value = to; setStatus(`renamed part ${name} to ${to}`, "ok"); }
    });
  });
  $("btn-fill-hole").addEventListener("click", () => {
    const faces = state.mode === "faces";
    const { loop, why } = holeLoop(state.model.indices, faces ? state.selected : state.vertices, { faces });
    if (!loop) { setStatus(`fill hole: ${why}`, "error"); return; }
    edit("fill_hole", { loop });
  });
  $("btn-undo").addEventListener("click", undo);
  $("btn-redo").addEventListener("click", redo);
  $("btn-move-mode").addEventListener("click", toggleMoveMode);
  $("btn-move-to").addEventListener("click", moveTo);
  for (const a of ["x", "y", "z"]) {
    $(`move-${a}`).addEventListener("keydown", (e) => { if (e.key === "Enter") moveTo(); });
  }
  document.addEventListener("keydown", shortcut);
  wireGizmo();
  $("btn-validate").addEventListener("click", validate);
  $("btn-save").addEventListener("click", save);
  $("btn-fp-clear").addEventListener("click", () => {
    if (!state.armed) { setStatus("pick a label to clear", "error"); return; }
    edit("clear_point", { label: state.armed }, { keepSelection: true });
  });
  $("btn-mirror").addEventListener("click", () => edit("mirror_points", { overwrite: $("mirror-overwrite").checked },
                                                       { keepSelection: true }));
  $("show-labels").addEventListener("change", (e) => { view.showLabels = e.target.checked; view.requestRender(); });
  installPointer(view, $("box"), { onClick, onBox: (rect, add) => {
    if (!state.model) return;
    const faces = state.mode === "faces";
    const items = faces ? view.facesInRect(...rect) : view.verticesInRect(...rect);
    select(items, add);
    setStatus(`box selected ${items.length} ${faces ? "faces" : "vertices"}`, "ok");
  }, boxMode: () => state.boxMode });
}

// the faces an edit on faces takes: the selected ones, or those the selected vertices wholly span
function selectedFaces() {
  return state.mode === "faces" ? selectedList() : facesWithin(state.model.indices, state.vertices);
}

async function grow() {
  const faces = state.mode === "faces";
  const seeds = faces ? [...state.selected] : firstFaces([...state.vertices]);
  if (!seeds.length) { setStatus(`select a ${faces ? "face" : "vertex"} to grow from`, "error"); return; }
  try {
    const all = new Set();
    for (const f of seeds) {
      if (all.has(f)) continue;  // already inside a region grown from another seed
      const { faces: region } = await api("/api/region", { face: f, same_part: $("grow-same-part").checked });
      for (const g of region) all.add(g);
    }
    select(faces ? all : cornersOf(state.model.indices, all), false);
    setStatus(`grew the selection to ${faces ? state.selected.size : state.vertices.size} connected `
      + `${faces ? "faces" : "vertices"}`, "ok");
  } catch { /* shown */ }
}

// one face using each vertex (vertices no face uses give none)
function firstFaces(vertices) {
  const want = new Set(vertices), out = new Set(), idx = state.model.indices;
  for (let k = 0; k < idx.length && want.size; k++) {
    if (want.has(idx[k])) { want.delete(idx[k]); out.add(Math.floor(k / 3)); }
  }
  return [...out];
}

function deleteFaces() {
  const faces = selectedFaces();
  if (!faces.length) { setStatus("select faces to delete", "error"); return; }
  edit("delete_faces", { faces });
}

function deleteVertices() {
  const vertices = moveSet();
  if (!vertices.length) { setStatus("select vertices (or faces) to delete", "error"); return; }
  edit("delete_vertices", { vertices });
}

async function undo() {
  try { show(await api("/api/undo", {}), { keepSelection: true }); setStatus("undone", "ok"); } catch { /* shown */ }
}

async function redo() {
  try { show(await api("/api/redo", {}), { keepSelection: true }); setStatus("redone", "ok"); } catch { /* shown */ }
}

// keys over the page (not while typing in a field): Delete, Ctrl+Z, Ctrl+Y / Ctrl+Shift+Z, G, Escape
function shortcut(e) {
  const t = e.target;
  if (t instanceof HTMLInputElement || t instanceof HTMLSelectElement || t instanceof HTMLTextAreaElement) return;
  const key = e.key.toLowerCase(), ctrl = e.ctrlKey || e.metaKey;
  if (ctrl && key === "z" && !e.shiftKey) undo();
  else if (ctrl && (key === "y" || (key === "z" && e.shiftKey))) redo();
  else if (ctrl || e.altKey) return;
  else if (key === "delete" || key === "backspace") { if (state.mode === "faces") deleteFaces(); else deleteVertices(); }
  else if (key === "g") toggleMoveMode();
  else if (key === "escape") select([], false);
  else return;
  e.preventDefault();
}

function showProblems(problems) {
  state.problems = problems;
  const ul = $("problems");
  ul.replaceChildren();
  for (const p of problems) { const li = document.createElement("li"); li.textContent = p; ul.append(li); }
  ul.dataset.count = String(problems.length);
}

async function validate() {
  try {
    const { ok, problems } = await api("/api/validate", {});
    showProblems(problems);
    setStatus(ok ? "valid: ready to save" : `${problems.length} problems`, ok ? "ok" : "error");
  } catch { /* shown */ }
}

async function save() {
  const name = $("save-name").value.trim() || "model";
  try {
    const { ok, problems } = await api("/api/validate", {});
    showProblems(problems);
    if (!ok) { setStatus(`not saved: ${problems.length} problems (listed under Save)`, "error"); return; }
    const { files, folder } = await api("/api/save", { name });
    state.lastSave = { files, folder };
    $("saved").textContent = `saved ${files.join(", ")} in ${folder}`;
    setStatus(`saved ${files.join(", ")}`, "ok");
  } catch { /* shown */ }
}

async function start() {
  buildTryPanel();
  wire();
  document.body.dataset.busy = "0";
  try { await loadFeaturePoints(); } catch { /* shown */ }
  try {
    show(await api("/api/model", undefined, { quiet: true }), { frame: true });
    setStatus("ready", "ok");
  } catch (e) {
    setStatus(`${e.error || e.message}: press "Load head" or upload a mesh`, "info");
  }
  document.body.dataset.ready = "1";
}

// test hooks: state, the view's projection (for real clicks at computed places), and selecting
// faces that no click reaches (inside the mouth)
window.editor = {
  state, view,
  selectFaces: (faces, add = false) => { setMode("faces"); select(faces, add); },
  moveSet, centroid: () => centroid(moveSet()),
  screenOfGizmoHandle: (axis, t) => view.gizmoHandle(axis, t),
  screenOfVertex: (i) => view.screenOf(view.vertex(i)),
  screenOfFace: (f) => view.screenOf(view.faceCentre(f)),
  facesCamera: (f) => view.faceFacesCamera(f),
  pickAt: (x, y) => view.pick(x, y),
};
start();
