// lashes.js: the browser head's eyelashes, cards grown from the posed lid margins every frame.
//
// The same cards as the Python renderer's (mpeg4fa/render/lashes.py, lash_vertices): each lash leaves the
// lid's front edge along the eyeball's outward direction, turned about the margin's tangent by its lift on
// the first half and by lift + curl on the second, so the lashes turn with the lids whatever they do. The
// layout comes in the head's key (mpeg4fa/serve/fap_head.py, lash_data); nothing is retyped here but the
// strand look, which the GL shader draws per fragment and a three.js material takes as a texture: strands
// across the card, each a little off its place, of its own reach, thinning to the tip.
import * as THREE from "three";

const MM = 0.001;  // millimetres -> the GLB's metres
const STRANDS = 64;  // strands in one repeat of the strand texture along the margin

/** A repeatable 0..1 hash of a strand's number (the same pattern every load). */
function hash(n) {
  const x = Math.sin(n * 127.1 + 311.7) * 43758.5453;
  return x - Math.floor(x);
}

/** The strands' alpha: STRANDS strands across (u: along the margin), root at v = 0 to tip at v = 1. */
function strandTexture(spacing, width) {
  const w = 2048, h = 128, perMm = w / (STRANDS * spacing);
  const canvas = document.createElement("canvas");
  canvas.width = w;
  canvas.height = h;
  const g = canvas.getContext("2d");
  g.fillStyle = "#000";
  g.fillRect(0, 0, w, h);
  g.fillStyle = "#fff";
  for (let i = 0; i < STRANDS; i++) {
    const centre = (i + 0.5 + 0.4 * (hash(i) - 0.5)) * spacing;
    const reach = 0.7 + 0.3 * hash(i + 11);
    const lean = 0.25 * (hash(i + 3) - 0.5) * reach;
    const root = width, tip = width * 0.15;
    for (const shift of [-STRANDS * spacing, 0, STRANDS * spacing]) {  // strands across the seam wrap round
      const x0 = (centre + shift) * perMm, x1 = (centre + lean + shift) * perMm;
      g.beginPath();
      g.moveTo(x0 - root * perMm, h);
      g.lineTo(x0 + root * perMm, h);
      g.lineTo(x1 + tip * perMm, h * (1 - reach));
      g.lineTo(x1 - tip * perMm, h * (1 - reach));
      g.closePath();
      g.fill();
    }
  }
  const texture = new THREE.CanvasTexture(canvas);
  texture.wrapS = THREE.RepeatWrapping;
  texture.anisotropy = 4;
  return texture;
}

export class Lashes {
  /** The cards of ``data`` (the key's ``lashes``), posed by :meth:`update` from the rig's posed vertices. */
  constructor(data) {
    this.data = data;
    const k = data.rows.length;
    this.k = k;
    this.positions = new Float32Array(9 * k);  // roots, middles, tips (mm, what tests read back)
    const geometry = new THREE.BufferGeometry();
    this.position = new THREE.BufferAttribute(new Float32Array(9 * k), 3);
    this.normal = new THREE.BufferAttribute(new Float32Array(9 * k), 3);
    const uv = new Float32Array(6 * k);
    for (let row = 0; row < 3; row++) {
      for (let i = 0; i < k; i++) {
        uv[2 * (row * k + i)] = data.along[i] / (STRANDS * data.spacing);
        uv[2 * (row * k + i) + 1] = row / 2;
      }
    }
    geometry.setAttribute("position", this.position);
    geometry.setAttribute("normal", this.normal);
    geometry.setAttribute("uv", new THREE.BufferAttribute(uv, 2));
    geometry.setIndex(data.indices);
    const colour = new THREE.Color().setRGB(...data.colour, THREE.LinearSRGBColorSpace);
    const material = new THREE.MeshLambertMaterial({
      color: colour, alphaMap: strandTexture(data.spacing, data.width), alphaToCoverage: true, alphaTest: 0.05,
      side: THREE.DoubleSide,
    });
    this.mesh = new THREE.Mesh(geometry, material);
    this.mesh.name = "lashes";
    this.mesh.frustumCulled = false;  // they move with the lids
  }

  /** Grow the cards from the posed vertices ``p`` (mm, x y z of every mesh vertex). */
  update(p) {
    const d = this.data, k = this.k, out = this.positions, nor = this.normal.array;
    for (let i = 0; i < k; i++) {
      const r = 3 * d.roots[i], j = 3 * d.joint[i], a = 3 * d.after[i], b = 3 * d.before[i];
      // the outward direction at the root and the margin's tangent, made square to it
      let rx = p[r] - p[j], ry = p[r + 1] - p[j + 1], rz = p[r + 2] - p[j + 2];
      let len = Math.hypot(rx, ry, rz) || 1;
      rx /= len; ry /= len; rz /= len;
      let tx = (p[a] - p[b]) * d.sign[i], ty = (p[a + 1] - p[b + 1]) * d.sign[i], tz = (p[a + 2] - p[b + 2]) * d.sign[i];
      len = Math.hypot(tx, ty, tz) || 1;
      tx /= len; ty /= len; tz /= len;
      const along = tx * rx + ty * ry + tz * rz;
      tx -= along * rx; ty -= along * ry; tz -= along * rz;
      len = Math.hypot(tx, ty, tz) || 1;
      tx /= len; ty /= len; tz /= len;
      // the radial turned about the tangent (square to it: Rodrigues without its axis term)
      const cx = ty * rz - tz * ry, cy = tz * rx - tx * rz, cz = tx * ry - ty * rx;
      const turn = (angle) => {
        const c = Math.cos(angle), s = Math.sin(angle);
        return [rx * c + cx * s, ry * c + cy * s, rz * c + cz * s];
      };
      const first = turn(d.lift[i]), second = turn(d.bend[i]);
      const half = 0.5 * d.length[i];
      const base = [p[r] + d.root_offset * rx, p[r + 1] + d.root_offset * ry, p[r + 2] + d.root_offset * rz];
      const middle = [base[0] + half * first[0], base[1] + half * first[1], base[2] + half * first[2]];
      const tip = [middle[0] + half * second[0], middle[1] + half * second[1], middle[2] + half * second[2]];
      [base, middle, tip].forEach((v, row) => out.set(v, 3 * (row * k + i)));
      // each card row's normal: across the strand, square to the tangent
      [first, first, second].forEach((v, row) => {
        let nx = ty * v[2] - tz * v[1], ny = tz * v[0] - tx * v[2], nz = tx * v[1] - ty * v[0];
        const n = Math.hypot(nx, ny, nz) || 1;
        nor.set([nx / n, ny / n, nz / n], 3 * (row * k + i));
      });
    }
    const pos = this.position.array;
    for (let q = 0; q < out.length; q++) pos[q] = out[q] * MM;
    this.position.needsUpdate = true;
    this.normal.needsUpdate = true;
  }
}
