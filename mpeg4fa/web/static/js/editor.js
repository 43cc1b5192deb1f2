// The face model editor page: wires the panels to the API, the view and the pointer.
import { api, setStatus, upload } from "./api.js";
import { View, partColor } from "./view.js";
import { installPointer, holeLoop } from "./select.js";

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

const state = {
  model: null, selected: new Set(), armed: null, featurePoints: [], posed: false,
  version: 0, poseVersion: 0, fapu: null, problems: null, boxMode: false, lastSave: null,
};
const view = new View($("viewport"), $("labels"));

function show(model, { frame = false, keepSelection = false } = {}) {
  state.model = model;
  if (!keepSelection) state.selected = new Set();
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
  $("sel-count").textContent = `${state.selected.size} faces selected`;
  $("sel-count").dataset.count = String(state.selected.size);
  view.setColors(state.selected);
}

function select(faces, add) {
  if (!add) state.selected = new Set();
  for (const f of faces) state.selected.add(f);
  showSelection();
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
  if (add && state.selected.has(hit.face)) { state.selected.delete(hit.face); showSelection(); return; }
  select([hit.face], add);
}

function selectedList() { return [...state.selected].sort((a, b) => a - b); }

function wire() {
  $("btn-load-head").addEventListener("click", async () => {
    try { show(await api("/api/load", { source: "head" }), { frame: true }); setStatus("loaded the head", "ok"); } catch { /* shown */ }
  });
  $("upload-file").addEventListener("change", async (e) => {
    const file = e.target.files[0];
    if (!file) return;
    try { show(await upload(file), { frame: true }); setStatus(`loaded ${file.name}`, "ok"); } catch { /* shown */ }
    e.target.value = "";
  });
  $("btn-frame").addEventListener("click", () => view.frame());
  $("btn-box-mode").addEventListener("click", () => {
    state.boxMode = !state.boxMode;
    $("btn-box-mode").classList.toggle("on", state.boxMode);
    $("btn-box-mode").setAttribute("aria-pressed", String(state.boxMode));
  });
  $("btn-clear-sel").addEventListener("click", () => select([], false));
  $("btn-grow").addEventListener("click", async () => {
    if (!state.selected.size) { setStatus("select a face to grow from", "error"); return; }
    try {
      const all = new Set();
      for (const f of [...state.selected]) {
        if (all.has(f)) continue;  // already inside a region grown from another selected face
        const { faces } = await api("/api/region", { face: f, same_part: $("grow-same-part").checked });
        for (const g of faces) all.add(g);
      }
      select(all, false);
      setStatus(`grew the selection to ${state.selected.size} connected faces`, "ok");
    } catch { /* shown */ }
  });
  $("btn-delete-faces").addEventListener("click", () => {
    if (!state.selected.size) { setStatus("select faces to delete", "error"); return; }
    edit("delete_faces", { faces: selectedList() });
  });
  $("btn-split").addEventListener("click", () => {
    if (!state.selected.size) { setStatus("select faces to split off", "error"); return; }
    edit("split_part", { faces: selectedList(), name: $("part-name").value.trim() });
  });
  $("btn-delete-part").addEventListener("click", () => edit("delete_part", { name: $("part-select").value }));
  $("btn-fill-hole").addEventListener("click", () => {
    const { loop, why } = holeLoop(state.model.indices, state.selected);
    if (!loop) { setStatus(`fill hole: ${why}`, "error"); return; }
    edit("fill_hole", { loop });
  });
  $("btn-undo").addEventListener("click", async () => { try { show(await api("/api/undo", {})); setStatus("undone", "ok"); } catch { /* shown */ } });
  $("btn-redo").addEventListener("click", async () => { try { show(await api("/api/redo", {})); setStatus("redone", "ok"); } catch { /* shown */ } });
  $("btn-validate").addEventListener("click", validate);
  $("btn-save").addEventListener("click", save);
  $("btn-fp-clear").addEventListener("click", () => {
    if (!state.armed) { setStatus("pick a label to clear", "error"); return; }
    edit("clear_point", { label: state.armed }, { keepSelection: true });
  });
  $("btn-mirror").addEventListener("click", () => edit("mirror_points", { overwrite: $("mirror-overwrite").checked },
                                                       { keepSelection: true }));
  $("show-labels").addEventListener("change", (e) => { view.showLabels = e.target.checked; view.requestRender(); });
  installPointer(view, $("box"), { onClick, onBox: (faces, add) => {
    select(faces, add); setStatus(`box selected ${faces.length} faces`, "ok");
  }, boxMode: () => state.boxMode });
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
  selectFaces: (faces, add = false) => select(faces, add),
  screenOfVertex: (i) => view.screenOf(view.vertex(i)),
  screenOfFace: (f) => view.screenOf(view.faceCentre(f)),
  facesCamera: (f) => view.faceFacesCamera(f),
  pickAt: (x, y) => view.pick(x, y),
};
start();
