// The three.js view: the mesh (flat shaded, coloured per part, selected faces highlighted), the vertices
// as dots (all of them in vertex mode, the selected ones always), the feature points as small spheres
// with labels, orbit/zoom/pan, a translate gizmo on the selection's centre, picking and projection.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { TransformControls } from "three/addons/controls/TransformControls.js";

const PALETTE = [0x93c47d, 0x8e7cc3, 0xffd966, 0xb4a7d6, 0xa2c4c9, 0xea9999, 0xf9cb9c, 0x6aa84f, 0x45818e];
const SELECTED = new THREE.Color(0xff6a00);
const POINT = 0x1f4fff, POINT_PICKED = 0xff1f6a;
const DOT = 0x3b3530, DOT_SELECTED = 0xffe000;
const BIN_PX = 16;  // the screen cells triangles are binned in for the box selection's visibility test
const GIZMO_SIZE = 0.8;  // TransformControls' handle size (1 is its default)
export const BACKGROUND = 0x2b2f36;

const KNOWN = { skin: 0xd9b49c, eye_l: 0x6fa8dc, eye_r: 0x76a5af, teeth_upper: 0xf6f0d8, teeth_lower: 0xe3d9b8,
                teeth: 0xf2e6b0, tongue: 0xc27ba0 };

// a part keeps its colour through edits: known names have theirs, names that say what they are (a
// renamed "upper_teeth", "eye_left") that of the kind, others one picked by their name
const KINDS = [[/teeth|tooth/, KNOWN.teeth], [/tongue/, KNOWN.tongue], [/(^|_)eyes?(_|$)/, KNOWN.eye_l],
               [/skin/, KNOWN.skin]];

export function partColor(name) {
  if (name in KNOWN) return KNOWN[name];
  const kind = KINDS.find(([word]) => word.test(name));
  if (kind) return kind[1];
  let h = 0;
  for (const ch of name) h = (h * 31 + ch.charCodeAt(0)) >>> 0;
  return PALETTE[h % PALETTE.length];
}

// a white disc on transparent, so that big point sprites draw round rather than square
let disc = null;
function roundDot() {
  if (disc) return disc;
  const c = document.createElement("canvas");
  c.width = c.height = 32;
  const g = c.getContext("2d");
  g.fillStyle = "#fff";
  g.beginPath(); g.arc(16, 16, 15, 0, 2 * Math.PI); g.fill();
  disc = new THREE.CanvasTexture(c);
  return disc;
}

export class View {
  constructor(container, overlay) {
    this.container = container;
    this.overlay = overlay;
    this.renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
    this.renderer.setPixelRatio(window.devicePixelRatio || 1);
    this.renderer.setClearColor(BACKGROUND);
    this.renderer.domElement.id = "canvas";
    this.renderer.domElement.dataset.testid = "canvas";
    container.prepend(this.renderer.domElement);
    this.scene = new THREE.Scene();
    this.camera = new THREE.PerspectiveCamera(35, 1, 0.1, 1e5);
    this.scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 1.6));
    this.light = new THREE.DirectionalLight(0xffffff, 1.6);
    this.camera.add(this.light);
    this.light.position.set(0.3, 0.5, 1);
    this.scene.add(this.camera);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener("change", () => this.requestRender());
    this.raycaster = new THREE.Raycaster();
    this.mesh = null;
    this.points = new THREE.Group();
    this.scene.add(this.points);
    this.dots = this.makeDots(DOT, 2);             // every vertex, in vertex mode
    this.selectedDots = this.makeDots(DOT_SELECTED, 7);
    this.selectedVertices = [];
    this.pivot = new THREE.Object3D();             // what the gizmo moves: placed on the selection's centre
    this.scene.add(this.pivot);
    this.gizmo = new TransformControls(this.camera, this.renderer.domElement);
    this.gizmo.setMode("translate");
    this.gizmo.setSize(GIZMO_SIZE);
    this.gizmo.addEventListener("change", () => this.requestRender());
    this.gizmo.addEventListener("dragging-changed", (e) => { this.controls.enabled = !e.value; });
    this.scene.add(this.gizmo.getHelper());
    this.labels = new Map();
    this.showLabels = true;
    this.pickedLabel = null;
    this.pending = false;
    this.frames = 0;
    new ResizeObserver(() => this.resize()).observe(container);
    this.resize();
  }

  resize() {
    const w = Math.max(1, this.container.clientWidth), h = Math.max(1, this.container.clientHeight);
    this.renderer.setSize(w, h, false);
    this.renderer.domElement.style.width = `${w}px`;
    this.renderer.domElement.style.height = `${h}px`;
    this.camera.aspect = w / h;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  makeDots(color, px) {
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(0), 3));
    const dots = new THREE.Points(geometry, new THREE.PointsMaterial({
      color, size: px, sizeAttenuation: false, map: px > 3 ? roundDot() : null, alphaTest: 0.5 }));
    dots.visible = false;
    dots.renderOrder = 1;
    this.scene.add(dots);
    return dots;
  }

  requestRender() {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => { this.pending = false; this.render(); });
  }

  render() {
    this.renderer.render(this.scene, this.camera);
    this.frames += 1;
    this.placeLabels();
  }

  // model: the API's /api/model answer; positions: the shown positions (neutral or posed), flat V*3
  setModel(model, positions, { frame = false } = {}) {
    this.model = model;
    this.indices = model.indices;
    const t = model.indices.length / 3;
    if (this.mesh) { this.scene.remove(this.mesh); this.mesh.geometry.dispose(); }
    const geometry = new THREE.BufferGeometry();
    geometry.setAttribute("position", new THREE.BufferAttribute(new Float32Array(t * 9), 3));
    geometry.setAttribute("color", new THREE.BufferAttribute(new Float32Array(t * 9), 3));
    // pushed back in depth a little, so the vertex dots on its surface pass the depth test
    const material = new THREE.MeshStandardMaterial({ vertexColors: true, flatShading: true, roughness: 0.8,
                                                       metalness: 0.0, side: THREE.DoubleSide,
                                                       polygonOffset: true, polygonOffsetFactor: 1,
                                                       polygonOffsetUnits: 1 });
    this.mesh = new THREE.Mesh(geometry, material);
    this.scene.add(this.mesh);
    this.selectedVertices = [];  // their numbers may not hold in the new mesh: the caller marks them again
    this.setPositions(positions);
    this.setPoints(model.points);
    this.setColors(new Set());
    if (frame) this.frame();
    this.requestRender();
  }

  setPositions(positions) {
    this.positions = positions;
    const out = this.mesh.geometry.attributes.position;
    const a = out.array, idx = this.indices;
    for (let k = 0; k < idx.length; k++) {
      const v = idx[k] * 3;
      a[k * 3] = positions[v]; a[k * 3 + 1] = positions[v + 1]; a[k * 3 + 2] = positions[v + 2];
    }
    out.needsUpdate = true;
    this.vertexNormals();
    this.mesh.geometry.computeVertexNormals();
    this.mesh.geometry.computeBoundingSphere();
    this.mesh.geometry.computeBoundingBox();
    const all = this.dots.geometry;
    all.setAttribute("position", new THREE.BufferAttribute(Float32Array.from(positions), 3));
    all.computeBoundingSphere();
    this.markVertices(this.selectedVertices);
    this.movePoints();
    this.requestRender();
  }

  // the feature-point spheres follow the shown positions (a pose, a drag) without being made again
  movePoints() {
    for (const m of this.points.children) {
      const v = this.model.points[m.userData.label];
      if (v !== undefined && v < this.positions.length / 3) m.position.copy(this.vertex(v));
    }
  }

  // vertex mode shows every vertex as a dot; the selected vertices are bright dots in either mode
  showVertexDots(on) {
    this.dots.visible = on;
    this.requestRender();
  }

  markVertices(vertices) {
    this.selectedVertices = vertices;
    const a = new Float32Array(vertices.length * 3), p = this.positions;
    vertices.forEach((v, k) => { a[k * 3] = p[v * 3]; a[k * 3 + 1] = p[v * 3 + 1]; a[k * 3 + 2] = p[v * 3 + 2]; });
    const g = this.selectedDots.geometry;
    g.setAttribute("position", new THREE.BufferAttribute(a, 3));
    g.computeBoundingSphere();
    this.selectedDots.visible = vertices.length > 0;
    this.requestRender();
  }

  // the translate gizmo at centre (an [x, y, z]), or hidden with null
  placeGizmo(centre) {
    if (this.gizmo.dragging) return;
    if (!centre) { this.gizmo.detach(); this.requestRender(); return; }
    this.pivot.position.fromArray(centre);
    this.pivot.updateMatrixWorld();
    if (this.gizmo.object !== this.pivot) this.gizmo.attach(this.pivot);
    this.requestRender();
  }

  // whether a press at this client position grabs one of the gizmo's handles (and which)
  overGizmo(clientX, clientY) {
    if (!this.gizmo.object || !this.gizmo.enabled) return null;
    const p = this.ndc(clientX, clientY);
    this.gizmo.pointerHover({ x: p.x, y: p.y, button: 0 });
    return this.gizmo.axis;
  }

  // client position of a point on the gizmo's axis handle ("X", "Y" or "Z"), at t of its arrow's length
  gizmoHandle(axis, t = 0.4) {
    if (!this.gizmo.object) return null;
    const at = this.pivot.position.clone();
    const cam = this.camera.position;
    // TransformControls' own handle scale for a perspective camera, times its size
    const factor = at.distanceTo(cam) * Math.min(1.9 * Math.tan(Math.PI * this.camera.fov / 360) / this.camera.zoom, 7);
    const dir = { X: [1, 0, 0], Y: [0, 1, 0], Z: [0, 0, 1] }[axis];
    at.add(new THREE.Vector3(...dir).multiplyScalar(t * factor * this.gizmo.size / 4));
    return this.screenOf(at);
  }

  // area-weighted vertex normals: a label whose point faces away from the camera is hidden
  vertexNormals() {
    const p = this.positions, idx = this.indices;
    const n = new Float32Array(p.length);
    const a = new THREE.Vector3(), b = new THREE.Vector3(), c = new THREE.Vector3();
    for (let f = 0; f < idx.length; f += 3) {
      const i = idx[f] * 3, j = idx[f + 1] * 3, k = idx[f + 2] * 3;
      a.set(p[j] - p[i], p[j + 1] - p[i + 1], p[j + 2] - p[i + 2]);
      b.set(p[k] - p[i], p[k + 1] - p[i + 1], p[k + 2] - p[i + 2]);
      c.crossVectors(a, b);
      for (const v of [i, j, k]) { n[v] += c.x; n[v + 1] += c.y; n[v + 2] += c.z; }
    }
    this.normals = n;
  }

  facesCamera(v) {
    const n = this.normals, p = this.vertex(v);
    const toCamera = this.camera.position.clone().sub(p);
    return n[v * 3] * toCamera.x + n[v * 3 + 1] * toCamera.y + n[v * 3 + 2] * toCamera.z >= 0;
  }

  setColors(selected) {
    const c = this.mesh.geometry.attributes.color, a = c.array;
    const parts = this.model.parts.map((name, i) => new THREE.Color(partColor(name)));
    const tp = this.model.triangle_parts;
    for (let f = 0; f < tp.length; f++) {
      const col = selected.has(f) ? SELECTED : parts[tp[f]];
      for (let k = 0; k < 3; k++) { a[f * 9 + k * 3] = col.r; a[f * 9 + k * 3 + 1] = col.g; a[f * 9 + k * 3 + 2] = col.b; }
    }
    c.needsUpdate = true;
    this.requestRender();
  }

  size() {
    const box = this.mesh.geometry.boundingBox;
    return box.getSize(new THREE.Vector3()).length();
  }

  frame() {
    const box = this.mesh.geometry.boundingBox;
    const centre = box.getCenter(new THREE.Vector3());
    const d = this.size() / (2 * Math.tan((this.camera.fov * Math.PI) / 360)) * 1.05;
    this.camera.position.set(centre.x, centre.y, centre.z + d);
    this.camera.near = d / 100; this.camera.far = d * 100;
    this.camera.updateProjectionMatrix();
    this.controls.target.copy(centre);
    this.controls.update();
    this.requestRender();
  }

  vertex(i) {
    const p = this.positions;
    return new THREE.Vector3(p[i * 3], p[i * 3 + 1], p[i * 3 + 2]);
  }

  setPoints(points) {
    for (const m of this.points.children) m.material.dispose();
    if (this.points.children.length) this.points.children[0].geometry.dispose();
    this.points.clear();
    const r = this.size() * 0.004;
    const geometry = new THREE.SphereGeometry(r, 10, 8);
    const seen = new Set();
    for (const [label, v] of Object.entries(points)) {
      const m = new THREE.Mesh(geometry, new THREE.MeshBasicMaterial({
        color: label === this.pickedLabel ? POINT_PICKED : POINT, depthTest: true,
        depthWrite: false }));  // hidden by the mesh, but not hiding the selected-vertex dots drawn after them
      m.position.copy(this.vertex(v));
      m.userData.label = label;
      this.points.add(m);
      seen.add(label);
      if (!this.labels.has(label)) {
        const div = document.createElement("div");
        div.className = "fp-label";
        div.textContent = label;
        div.dataset.label = label;
        this.overlay.appendChild(div);
        this.labels.set(label, div);
      }
    }
    for (const [label, div] of this.labels) if (!seen.has(label)) { div.remove(); this.labels.delete(label); }
    this.requestRender();
  }

  setPicked(label) {
    this.pickedLabel = label;
    if (this.model) this.setPoints(this.model.points);
  }

  placeLabels() {
    if (!this.model) return;
    const w = this.container.clientWidth, h = this.container.clientHeight;
    for (const [label, div] of this.labels) {
      const v = this.model.points[label];
      if (v === undefined || !this.showLabels) { div.style.display = "none"; continue; }
      const p = this.vertex(v).project(this.camera);
      div.style.display = p.z < 1 && this.facesCamera(v) ? "" : "none";
      div.style.left = `${((p.x + 1) / 2) * w + 4}px`;
      div.style.top = `${((1 - p.y) / 2) * h - 6}px`;
      div.classList.toggle("picked", label === this.pickedLabel);
    }
  }

  // NDC of a client (page) position over the canvas
  ndc(clientX, clientY) {
    const r = this.renderer.domElement.getBoundingClientRect();
    return new THREE.Vector2(((clientX - r.left) / r.width) * 2 - 1, -((clientY - r.top) / r.height) * 2 + 1);
  }

  // {face, point, vertex}: the face under the pointer and its corner nearest the hit, or null
  pick(clientX, clientY) {
    if (!this.mesh) return null;
    this.raycaster.setFromCamera(this.ndc(clientX, clientY), this.camera);
    const hit = this.raycaster.intersectObject(this.mesh, false)[0];
    if (!hit) return null;
    const face = hit.faceIndex;
    let best = -1, bestD = Infinity;
    for (let k = 0; k < 3; k++) {
      const v = this.indices[face * 3 + k];
      const d = this.vertex(v).distanceToSquared(hit.point);
      if (d < bestD) { bestD = d; best = v; }
    }
    return { face, point: hit.point.toArray(), vertex: best };
  }

  // page (client) coordinates of a model-space point
  screenOf(vec) {
    const r = this.renderer.domElement.getBoundingClientRect();
    const p = vec.clone().project(this.camera);
    return { x: r.left + ((p.x + 1) / 2) * r.width, y: r.top + ((1 - p.y) / 2) * r.height, z: p.z };
  }

  faceCentre(f) {
    const i = this.indices;
    return this.vertex(i[f * 3]).add(this.vertex(i[f * 3 + 1])).add(this.vertex(i[f * 3 + 2])).divideScalar(3);
  }

  faceFacesCamera(f) {
    const i = this.indices;
    const a = this.vertex(i[f * 3]), b = this.vertex(i[f * 3 + 1]), c = this.vertex(i[f * 3 + 2]);
    const n = b.clone().sub(a).cross(c.clone().sub(a));
    const centre = a.add(b).add(c).divideScalar(3);
    return n.dot(this.camera.position.clone().sub(centre)) > 0;
  }

  // A test of whether a model-space point is seen from the camera, not hidden behind another part of
  // the mesh: the triangles are binned by their screen rectangles, so each test casts its ray only
  // against the few triangles under the point.
  visibilityTest() {
    const r = this.renderer.domElement.getBoundingClientRect();
    const n = this.positions.length / 3, sx = new Float32Array(n), sy = new Float32Array(n), ok = new Uint8Array(n);
    for (let v = 0; v < n; v++) {
      const s = this.screenOf(this.vertex(v));
      sx[v] = s.x - r.left; sy[v] = s.y - r.top; ok[v] = s.z > -1 && s.z < 1 ? 1 : 0;
    }
    const cols = Math.ceil(r.width / BIN_PX) + 1, rows = Math.ceil(r.height / BIN_PX) + 1;
    const bins = new Map(), idx = this.indices;
    for (let f = 0; f < idx.length / 3; f++) {
      const a = idx[f * 3], b = idx[f * 3 + 1], c = idx[f * 3 + 2];
      if (!(ok[a] && ok[b] && ok[c])) continue;
      const c0 = Math.max(0, Math.floor(Math.min(sx[a], sx[b], sx[c]) / BIN_PX));
      const c1 = Math.min(cols - 1, Math.floor(Math.max(sx[a], sx[b], sx[c]) / BIN_PX));
      const r0 = Math.max(0, Math.floor(Math.min(sy[a], sy[b], sy[c]) / BIN_PX));
      const r1 = Math.min(rows - 1, Math.floor(Math.max(sy[a], sy[b], sy[c]) / BIN_PX));
      for (let i = r0; i <= r1; i++) {
        for (let j = c0; j <= c1; j++) {
          const key = i * cols + j;
          if (!bins.has(key)) bins.set(key, []);
          bins.get(key).push(f);
        }
      }
    }
    const eye = this.camera.position.clone(), ray = new THREE.Ray(), hit = new THREE.Vector3();
    const slack = this.size() * 1e-4;
    return (point) => {
      const s = this.screenOf(point);
      const list = bins.get(Math.floor((s.y - r.top) / BIN_PX) * cols + Math.floor((s.x - r.left) / BIN_PX)) || [];
      const dir = point.clone().sub(eye), dist = dir.length();
      ray.set(eye, dir.divideScalar(dist));
      for (const f of list) {
        const at = ray.intersectTriangle(this.vertex(idx[f * 3]), this.vertex(idx[f * 3 + 1]),
                                         this.vertex(idx[f * 3 + 2]), false, hit);
        if (at && at.distanceTo(eye) < dist - slack - dist * 1e-5) return false;
      }
      return true;
    };
  }

  // vertices that project into the client rectangle, face the camera and are not hidden behind the mesh
  verticesInRect(x0, y0, x1, y1) {
    const out = [];
    const [ax, bx] = [Math.min(x0, x1), Math.max(x0, x1)], [ay, by] = [Math.min(y0, y1), Math.max(y0, y1)];
    const used = new Uint8Array(this.positions.length / 3);
    for (const v of this.indices) used[v] = 1;
    const seen = this.visibilityTest();
    for (let v = 0; v < used.length; v++) {
      if (!used[v]) continue;
      const p = this.vertex(v), s = this.screenOf(p);
      if (s.z < 1 && s.x >= ax && s.x <= bx && s.y >= ay && s.y <= by && this.facesCamera(v) && seen(p)) out.push(v);
    }
    return out;
  }

  // faces whose projected centre lies in the client rectangle, that face the camera and are not hidden
  facesInRect(x0, y0, x1, y1) {
    const out = [];
    const [ax, bx] = [Math.min(x0, x1), Math.max(x0, x1)], [ay, by] = [Math.min(y0, y1), Math.max(y0, y1)];
    const n = this.indices.length / 3;
    const seen = this.visibilityTest();
    for (let f = 0; f < n; f++) {
      const c = this.faceCentre(f), s = this.screenOf(c);
      if (s.z < 1 && s.x >= ax && s.x <= bx && s.y >= ay && s.y <= by && this.faceFacesCamera(f) && seen(c)) out.push(f);
    }
    return out;
  }
}
