// head.js: the head both pages show (the FBA player and the live `serve` page), posed from FAP values.
//
// The GLB is the face at rest (mpeg4fa/serve/fap_head.py); its key carries the face engine's rig, which
// facerig.js runs to put every vertex where the Python face puts it. Each frame the posed vertices go
// into the GLB's primitives (each GL vertex is a mesh vertex, listed per part in the key), normals are
// recomputed over the whole mesh (so seams between parts stay smooth), the lashes are grown from the posed
// lid margins (lashes.js; none on a photo-textured head, whose photo has its own), and the picture is drawn.
// One view set-up (renderer, light, camera framing the face, resizing with its element) for both pages.
import * as THREE from "three";
import { OrbitControls } from "three/addons/controls/OrbitControls.js";
import { GLTFLoader } from "three/addons/loaders/GLTFLoader.js";
import { FaceRig } from "./facerig.js";
import { Lashes } from "./lashes.js";

const MM = 0.001;  // the rig's millimetres -> the GLB's metres

/** The three.js view inside ``element`` (a positioned block): renderer, scene, camera and controls. */
export function createView(element) {
  const renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
  renderer.setPixelRatio(window.devicePixelRatio || 1);
  renderer.outputColorSpace = THREE.SRGBColorSpace;
  element.prepend(renderer.domElement);
  const scene = new THREE.Scene();
  scene.background = new THREE.Color(0x2b2f36);
  const camera = new THREE.PerspectiveCamera(30, 1, 0.01, 10);
  scene.add(new THREE.HemisphereLight(0xffffff, 0x444444, 2.0));
  const sun = new THREE.DirectionalLight(0xffffff, 1.5);
  sun.position.set(0.5, 1.5, 2);
  scene.add(sun);
  const controls = new OrbitControls(camera, renderer.domElement);
  const view = {
    renderer, scene, camera, controls, element,
    /** Fit the drawing buffer and the camera to the element (called on every size change). */
    resize() {
      const w = Math.max(element.clientWidth, 1), h = Math.max(element.clientHeight, 1);
      renderer.setSize(w, h, false);
      camera.aspect = w / h;
      camera.updateProjectionMatrix();
    },
    render() { controls.update(); renderer.render(scene, camera); },
  };
  new ResizeObserver(() => view.resize()).observe(element);
  view.resize();
  return view;
}

/** Load the head into ``view``: ``source`` is ``{glb, key}`` (URLs, or the key itself and a data: URL). */
export async function loadHead(view, source) {
  const key = typeof source.key === "string" ? await (await fetch(source.key)).json() : source.key;
  const gltf = await new GLTFLoader().loadAsync(source.glb);
  return new Head(view, gltf.scene, key);
}

export class Head {
  constructor(view, root, key) {
    this.view = view;
    this.root = root;
    this.key = key;
    this.rig = new FaceRig(key.rig);
    this.parts = [];  // {mesh, source: mesh vertex of each GL vertex}
    let lashMesh = null;
    root.traverse((o) => {
      const part = o.isMesh && o.geometry.userData.part;
      if (part === "lashes") lashMesh = o;
      if (!part || !key.parts[part]) return;
      const source = Int32Array.from(key.parts[part]);
      if (source.length !== o.geometry.attributes.position.count) throw new Error(`head part ${part}: vertex count differs from its key`);
      const { position, normal } = o.geometry.attributes;
      if (position.isInterleavedBufferAttribute || (normal && normal.isInterleavedBufferAttribute)) {
        throw new Error(`head part ${part}: interleaved vertex data (the pose writes plain arrays)`);
      }
      o.frustumCulled = false;  // the vertices move; the rest pose's bounds do not
      this.parts.push({ mesh: o, source });
    });
    if (!this.parts.length) throw new Error("the head has no parts its key names");
    // triangles over mesh vertices (all parts), for normals that do not break where GL vertices split
    const tris = [];
    for (const { mesh, source } of this.parts) {
      const index = mesh.geometry.index.array;
      for (let i = 0; i < index.length; i++) tris.push(source[index[i]]);
    }
    this.triangles = Int32Array.from(tris);
    this.normals = new Float32Array(this.rig.rest.length);
    // each feature point's vertex: the first GL vertex made from it (none for a part the GLB leaves out)
    this.fpAt = Array.from(this.rig.fpVertex, (vertex) => {
      for (const part of this.parts) {
        const i = part.source.indexOf(vertex);
        if (i >= 0) return [part.mesh, i];
      }
      return null;
    });
    this.lashes = key.lashes && lashMesh ? new Lashes(key.lashes, lashMesh) : null;
    if (lashMesh && !this.lashes) lashMesh.visible = false;  // no layout to grow them by: not left at rest
    view.scene.add(root);
    this.frame();
    this.values = new Float64Array(68);
    this.pose(this.values);
  }

  /** A note when the face has another deformer than the one facerig.js ports (its pose then differs), else "". */
  get deformerNote() {
    const own = this.key.deformer;
    return own && own !== "fap" ? `posed by the feature-point deformer, not this face's ${own}` : "";
  }

  /** Take the head out of the view (another replaces it) and free its GPU buffers. */
  remove() {
    this.view.scene.remove(this.root);
    this.root.traverse((o) => {
      if (!o.isMesh) return;
      o.geometry.dispose();
      for (const m of [].concat(o.material)) { if (m.map) m.map.dispose(); m.dispose(); }
    });
  }

  /** Point the camera at the face: between the chin and the top of the head, in front of it. */
  frame() {
    const { labels, rest } = this.key.feature_points;
    const fp = (label) => rest[labels.indexOf(label)];
    const chin = fp("2.1"), top = labels.includes("11.1") ? fp("11.1") : fp("4.1");
    const centre = new THREE.Vector3(0, (chin[1] + top[1]) / 2, chin[2]);
    this.view.camera.position.set(centre.x, centre.y, centre.z + 0.75);
    this.view.controls.target.copy(centre);
    this.view.controls.update();
  }

  /** Pose the head with one row of 68 shown values (shown.js): every vertex as the Python face has it. */
  pose(values) {
    this.values = values;
    const p = this.rig.pose(values);
    const n = this.normals, t = this.triangles;
    n.fill(0);
    for (let k = 0; k < t.length; k += 3) {
      const a = 3 * t[k], b = 3 * t[k + 1], c = 3 * t[k + 2];
      const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
      const vx = p[c] - p[a], vy = p[c + 1] - p[a + 1], vz = p[c + 2] - p[a + 2];
      const nx = uy * vz - uz * vy, ny = uz * vx - ux * vz, nz = ux * vy - uy * vx;
      n[a] += nx; n[a + 1] += ny; n[a + 2] += nz;
      n[b] += nx; n[b + 1] += ny; n[b + 2] += nz;
      n[c] += nx; n[c + 1] += ny; n[c + 2] += nz;
    }
    for (const { mesh, source } of this.parts) {
      const pos = mesh.geometry.attributes.position, nor = mesh.geometry.attributes.normal;
      const pa = pos.array, na = nor ? nor.array : null;
      for (let i = 0; i < source.length; i++) {
        const o = 3 * source[i], q = 3 * i;
        pa[q] = p[o] * MM; pa[q + 1] = p[o + 1] * MM; pa[q + 2] = p[o + 2] * MM;
        if (na) {
          const len = Math.hypot(n[o], n[o + 1], n[o + 2]) || 1;
          na[q] = n[o] / len; na[q + 1] = n[o + 1] / len; na[q + 2] = n[o + 2] / len;
        }
      }
      pos.needsUpdate = true;
      if (nor) nor.needsUpdate = true;
    }
    if (this.lashes) this.lashes.update(p);
  }

  /** The lash cards' vertices in millimetres (roots, middles, tips; null without lashes): what tests compare. */
  lashVertices() {
    return this.lashes ? Array.from(this.lashes.positions) : null;
  }

  /** Feature points of the drawn head in millimetres (world), read back from the GL vertices: what tests compare. */
  featurePoints() {
    const v = new THREE.Vector3();
    this.root.updateMatrixWorld(true);
    return { labels: this.key.feature_points.labels, positions: this.fpAt.map((at) => {
      if (at === null) return null;
      const [mesh, i] = at;
      mesh.getVertexPosition(i, v);
      mesh.localToWorld(v);
      return [v.x / MM, v.y / MM, v.z / MM];
    }) };
  }
}
