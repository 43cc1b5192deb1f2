// Pointer handling over the view: a click (onClick with the pick under it; shift held: add), a drag with
// Alt held or with box mode on (onBox with the client rectangle). A press on the move gizmo's handles is
// left to the gizmo: neither a click nor a box, and the orbit stays still while it drags.
const CLICK_SLOP = 5;

export function installPointer(view, box, { onClick, onBox, boxMode }) {
  const el = view.container;
  let start = null;

  el.addEventListener("pointerdown", (e) => {
    if (e.button !== 0) { start = null; return; }
    if (view.overGizmo(e.clientX, e.clientY)) {
      view.controls.enabled = false;  // before OrbitControls' listener on the canvas (capture phase here)
      start = { gizmo: true };
      return;
    }
    const boxing = e.altKey || boxMode();
    start = { x: e.clientX, y: e.clientY, shift: e.shiftKey, boxing };
    if (boxing) {
      view.controls.enabled = false;  // runs before OrbitControls' own listener (capture phase here)
      el.setPointerCapture(e.pointerId);
      Object.assign(box.style, { display: "block", left: "0px", top: "0px", width: "0px", height: "0px" });
    }
  }, { capture: true });

  el.addEventListener("pointermove", (e) => {
    if (!start || !start.boxing) return;
    const r = el.getBoundingClientRect();
    Object.assign(box.style, {
      left: `${Math.min(start.x, e.clientX) - r.left}px`, top: `${Math.min(start.y, e.clientY) - r.top}px`,
      width: `${Math.abs(e.clientX - start.x)}px`, height: `${Math.abs(e.clientY - start.y)}px`,
    });
  }, { capture: true });

  el.addEventListener("pointerup", (e) => {
    if (!start) return;
    const s = start;
    start = null;
    if (s.gizmo) { view.controls.enabled = true; return; }
    const moved = Math.hypot(e.clientX - s.x, e.clientY - s.y);
    if (s.boxing) {
      box.style.display = "none";
      view.controls.enabled = true;
      if (moved >= CLICK_SLOP) { onBox([s.x, s.y, e.clientX, e.clientY], s.shift || e.shiftKey); return; }
    }
    if (moved < CLICK_SLOP) onClick(view.pick(e.clientX, e.clientY), s.shift || e.shiftKey);
  }, { capture: true });
}

// The corners of the given faces, sorted.
export function cornersOf(indices, faces) {
  const corners = new Set();
  for (const f of faces) for (let k = 0; k < 3; k++) corners.add(indices[f * 3 + k]);
  return [...corners].sort((a, b) => a - b);
}

// The faces whose three corners are all among the given vertices, sorted.
export function facesWithin(indices, vertices) {
  const inside = new Set(vertices), out = [];
  for (let f = 0; f < indices.length / 3; f++) {
    if (inside.has(indices[f * 3]) && inside.has(indices[f * 3 + 1]) && inside.has(indices[f * 3 + 2])) out.push(f);
  }
  return out;
}

// The boundary loop of the selection: the mesh's boundary edges (in one face only) whose two ends are
// selected vertices (or corners of selected faces, with faces), as one closed chain of vertices; null
// with a reason when there is not one.
export function holeLoop(indices, selected, { faces = true } = {}) {
  const count = new Map();
  const key = (a, b) => (a < b ? `${a},${b}` : `${b},${a}`);
  for (let f = 0; f < indices.length / 3; f++) {
    for (let k = 0; k < 3; k++) {
      const a = indices[f * 3 + k], b = indices[f * 3 + ((k + 1) % 3)];
      const id = key(a, b);
      count.set(id, (count.get(id) || 0) + 1);
    }
  }
  const corners = new Set(faces ? cornersOf(indices, selected) : selected);
  const adj = new Map();
  for (const [id, n] of count) {
    if (n !== 1) continue;
    const [a, b] = id.split(",").map(Number);
    if (!corners.has(a) || !corners.has(b)) continue;
    if (!adj.has(a)) adj.set(a, []);
    if (!adj.has(b)) adj.set(b, []);
    adj.get(a).push(b); adj.get(b).push(a);
  }
  if (!adj.size) return { loop: null, why: `no hole: the selected ${faces ? "faces touch" : "vertices span"} no open boundary` };
  // connected chains of boundary edges; keep the closed ones (every vertex on two edges)
  const seen = new Set(), loops = [];
  for (const v0 of adj.keys()) {
    if (seen.has(v0)) continue;
    const comp = [], stack = [v0];
    seen.add(v0);
    while (stack.length) {
      const v = stack.pop();
      comp.push(v);
      for (const w of adj.get(v)) if (!seen.has(w)) { seen.add(w); stack.push(w); }
    }
    if (comp.every((v) => adj.get(v).length === 2)) loops.push(comp);
  }
  if (loops.length !== 1) {
    return { loop: null, why: loops.length ? `${loops.length} holes around the selection: select faces around one`
                                          : "the selection's boundary edges do not close around a hole" };
  }
  return { loop: loops[0], why: "" };
}
