// facerig.js: the face engine's feature-point deformer, run in the page (no dependencies; Node too).
//
// A port of mpeg4fa/face/deformers/feature_points.py (deform): 68 shown FAP values in, every vertex of
// the head out, in millimetres, float64. The rig comes as data (mpeg4fa/serve/fap_head.py rig_data):
// the linear map FAPs -> feature point motion (FAPU x direction already applied), the inner/outer lip
// corner rule, the sparse map feature point motion -> skin, the lid sheets, the tongue roll, the jaw,
// the eyes and the head turn with its fade down the neck, in that order (lips move in the jaw's frame,
// the jaw and eyes in the head's). Same steps, same order, same numbers: the page's head is the
// Python face's to rounding, not an approximation of it.

const RIG_VERSION = 1;

/** Right-handed rotation by ``angle`` about axis 0, 1 or 2, as a row-major 3x3 (motion.rotation_matrix). */
export function rotation(axis, angle) {
  const c = Math.cos(angle), s = Math.sin(angle);
  const [i, j] = [[1, 2], [2, 0], [0, 1]][axis];
  const r = [1, 0, 0, 0, 1, 0, 0, 0, 1];
  r[3 * i + i] = c; r[3 * i + j] = -s; r[3 * j + i] = s; r[3 * j + j] = c;
  return r;
}

function mul(a, b) {
  const r = new Array(9).fill(0);
  for (let i = 0; i < 3; i++) for (let j = 0; j < 3; j++) for (let k = 0; k < 3; k++) r[3 * i + j] += a[3 * i + k] * b[3 * k + j];
  return r;
}

/** Angle about +x that lowers a point at (y, z) from the pivot by ``drop`` (motion.arc_angle): the root nearest 0. */
export function arcAngle(y, z, drop) {
  const radius = Math.hypot(y, z);
  if (radius === 0 || drop === 0) return 0;
  const phase = Math.atan2(z, y);
  const base = Math.acos(Math.min(1, Math.max(-1, (y - drop) / radius)));
  const wrap = (x) => { const t = 2 * Math.PI; return (((x + Math.PI) % t) + t) % t - Math.PI; };
  const a = wrap(base - phase), b = wrap(-base - phase);
  return Math.abs(b) < Math.abs(a) ? b : a;
}

/** share -> the rotation ``r`` turned by that share of its angle about its own axis (Rodrigues), row-major. */
export function partialRotation(r) {
  const angle = Math.acos(Math.min(1, Math.max(-1, 0.5 * (r[0] + r[4] + r[8] - 1))));
  if (angle < 1e-12) return () => [1, 0, 0, 0, 1, 0, 0, 0, 1];
  let axis = [r[7] - r[5], r[2] - r[6], r[3] - r[1]];
  let norm = Math.hypot(...axis);
  if (norm <= 1e-9) {  // a half turn: the column of R + I with the most in it
    const m = [r[0] + 1, r[1], r[2], r[3], r[4] + 1, r[5], r[6], r[7], r[8] + 1];
    const cols = [0, 1, 2].map((j) => [m[j], m[3 + j], m[6 + j]]);
    axis = cols.reduce((best, col) => (Math.hypot(...col) > Math.hypot(...best) ? col : best));
    norm = Math.hypot(...axis);
  }
  const [x, y, z] = axis.map((a) => a / norm);
  const k = [0, -z, y, z, 0, -x, -y, x, 0], k2 = mul(k, k);
  return (share) => {
    const a = share * angle, s = Math.sin(a), c1 = 1 - Math.cos(a);
    return k.map((kv, i) => (i % 4 === 0 ? 1 : 0) + s * kv + c1 * k2[i]);
  };
}

const i32 = (a) => Int32Array.from(a);
const f64 = (a) => Float64Array.from(a);

export class FaceRig {
  /** ``data``: the ``rig`` of fap-head.json. */
  constructor(data) {
    if (data.version !== RIG_VERSION) throw new Error(`face rig version ${data.version}, this page reads ${RIG_VERSION}`);
    this.n = data.n_vertices;
    this.rest = f64(data.rest);
    this.p = new Float64Array(this.rest.length);
    this.fpVertex = i32(data.fp_vertex);
    this.m = new Float64Array(this.fpVertex.length * 3);
    this.angleUnit = data.angle_unit;
    this.t = { rows: i32(data.translate.rows), faps: i32(data.translate.faps), values: f64(data.translate.values) };
    this.corners = data.corners;
    this.cornerMargin = data.corner_margin;
    this.moving = i32(data.moving);
    this.w = { indptr: i32(data.weights.indptr), indices: i32(data.weights.indices), data: f64(data.weights.data) };
    this.irisd = data.irisd;
    this.lids = data.lids.map((l) => ({ ...l, rows: i32(l.rows), ratios: f64(l.ratios) }));
    this.roll = { ...data.roll, parts: data.roll.parts.map((r) => ({ side: r.side, rows: i32(r.rows), weights: f64(r.weights) })) };
    this.jaw = { ...data.jaw, rows: i32(data.jaw.rows), weights: f64(data.jaw.weights) };
    this.eyes = data.eyes;
    this.es = data.es;
    this.head = { ...data.head, fadeRows: i32(data.head.fade_rows), fadeWeights: f64(data.head.fade_weights) };
    this.before = new Float64Array(this.head.fadeRows.length * 3);
  }

  restOf(vertex, c) { return this.rest[3 * vertex + c]; }

  /** Feature point motion (point_motion): the linear map, then the lip corners kept around the opening. */
  pointMotion(v) {
    const m = this.m, t = this.t;
    m.fill(0);
    for (let k = 0; k < t.rows.length; k++) m[t.rows[k]] += v[t.faps[k] - 1] * t.values[k];
    for (const [inner, outer] of this.corners) {
      const ri = this.restOf(this.fpVertex[inner], 0), ro = this.restOf(this.fpVertex[outer], 0);
      const side = Math.sign(ro - ri) || 1;
      const past = side * ((ri + m[3 * inner]) - (ro + m[3 * outer])) + this.cornerMargin;
      if (past > 0) {
        const a = Math.abs(m[3 * inner]), b = Math.abs(m[3 * outer]);
        const share = a + b > 0 ? a / (a + b) : 0.5;
        m[3 * outer] += side * past * share;
        m[3 * inner] -= side * past * (1 - share);
      }
    }
    return m;
  }

  /** Blend rows toward their rotated (and shifted) position by their weights (_rotate_rows), in place. */
  rotateRows(rows, weights, centre, r, shift) {
    const p = this.p;
    for (let k = 0; k < rows.length; k++) {
      const o = 3 * rows[k];
      const x = p[o] - centre[0], y = p[o + 1] - centre[1], z = p[o + 2] - centre[2];
      for (let i = 0; i < 3; i++) {
        let step = (r[3 * i] - (i === 0)) * x + (r[3 * i + 1] - (i === 1)) * y + (r[3 * i + 2] - (i === 2)) * z;
        if (shift) step += shift[i];
        p[o + i] += weights[k] * step;
      }
    }
  }

  /** Every vertex (Float64Array, x y z per vertex, mm) posed by one row of 68 shown values. */
  pose(v) {
    const p = this.p, rest = this.rest;
    p.set(rest);
    const m = this.pointMotion(v);
    if (m.some((x) => x !== 0)) {
      const { indptr, indices, data } = this.w;
      for (let j = 0; j < this.moving.length; j++) {
        let dx = 0, dy = 0, dz = 0;
        for (let k = indptr[j]; k < indptr[j + 1]; k++) {
          const c = 3 * indices[k], w = data[k];
          dx += w * m[c]; dy += w * m[c + 1]; dz += w * m[c + 2];
        }
        const o = 3 * this.moving[j];
        p[o] += dx; p[o + 1] += dy; p[o + 2] += dz;
      }
    }
    for (const lid of this.lids) {  // lids.turn_lid: the sheet turns about the eye centre's x axis
      const value = v[lid.fap - 1];
      if (!value) continue;
      const c = 3 * lid.joint, q = 3 * lid.point;
      const angle = arcAngle(rest[q + 1] - rest[c + 1], rest[q + 2] - rest[c + 2], lid.down * value * this.irisd);
      if (angle === 0) continue;
      for (let k = 0; k < lid.rows.length; k++) {
        const a = lid.ratios[k] * angle, co = Math.cos(a), si = Math.sin(a), o = 3 * lid.rows[k];
        const dy = p[o + 1] - rest[c + 1], dz = p[o + 2] - rest[c + 2];
        p[o + 1] = rest[c + 1] + co * dy - si * dz;
        p[o + 2] = rest[c + 2] + si * dy + co * dz;
      }
    }
    const roll = v[this.roll.fap - 1];
    if (roll && this.roll.axis_fp !== null) {
      const axisY = rest[3 * this.fpVertex[this.roll.axis_fp] + 1];
      for (const part of this.roll.parts) {
        this.rotateRows(part.rows, part.weights, [0, axisY, 0], rotation(2, part.side * roll * this.angleUnit), null);
      }
    }
    const jaw = this.jaw;
    const open = v[jaw.open - 1], thrust = v[jaw.thrust - 1], shift = v[jaw.shift - 1];
    if (open || thrust || shift) {
      const pivot = [rest[3 * jaw.pivot], rest[3 * jaw.pivot + 1], rest[3 * jaw.pivot + 2]];
      const chin = 3 * this.fpVertex[jaw.chin_fp];
      const angle = arcAngle(rest[chin + 1] - pivot[1], rest[chin + 2] - pivot[2], open * jaw.mns);
      const offset = [0, 1, 2].map((i) => thrust * jaw.mns * jaw.thrust_dir[i] + shift * jaw.mw * jaw.shift_dir[i]);
      this.rotateRows(jaw.rows, jaw.weights, pivot, rotation(0, angle), offset);
    }
    for (const eye of this.eyes) {
      const yaw = v[eye.yaw - 1] * this.angleUnit, pitch = v[eye.pitch - 1] * this.angleUnit;
      const push = v[eye.thrust - 1] * this.es;
      if (!(yaw || pitch || push)) continue;
      const c = [0, 1, 2].map((i) => rest[3 * eye.joint + i]);
      const turn = mul(rotation(1, yaw), rotation(0, pitch));
      const d = eye.thrust_dir.map((x) => push * x);
      for (let u = eye.part[0]; u < eye.part[1]; u++) {
        const o = 3 * u, x = p[o] - c[0], y = p[o + 1] - c[1], z = p[o + 2] - c[2];
        for (let i = 0; i < 3; i++) p[o + i] = c[i] + turn[3 * i] * x + turn[3 * i + 1] * y + turn[3 * i + 2] * z + d[i];
      }
      for (let i = 0; i < 3; i++) p[3 * eye.joint + i] = c[i] + d[i];
    }
    const h = this.head;
    const pitch = v[h.pitch - 1] * this.angleUnit, yaw = v[h.yaw - 1] * this.angleUnit, rollH = v[h.roll - 1] * this.angleUnit;
    if (pitch || yaw || rollH) {  // apply_head_rotation: turn everything, then blend the neck back by its share
      const r = mul(mul(rotation(1, yaw), rotation(0, pitch)), rotation(2, rollH));
      const c = [0, 1, 2].map((i) => rest[3 * this.fpVertex[h.fp] + i]);
      const rows = h.fadeRows, before = this.before;
      for (let k = 0; k < rows.length; k++) for (let i = 0; i < 3; i++) before[3 * k + i] = p[3 * rows[k] + i];
      for (let o = 0; o < p.length; o += 3) {
        const x = p[o] - c[0], y = p[o + 1] - c[1], z = p[o + 2] - c[2];
        for (let i = 0; i < 3; i++) p[o + i] = c[i] + r[3 * i] * x + r[3 * i + 1] * y + r[3 * i + 2] * z;
      }
      if (h.neck === "turn") {  // each neck vertex turned by its share of the angle (partial_rotations)
        const part = partialRotation(r);
        for (let k = 0; k < rows.length; k++) {
          const m = part(h.fadeWeights[k]);
          const x = before[3 * k] - c[0], y = before[3 * k + 1] - c[1], z = before[3 * k + 2] - c[2];
          for (let i = 0; i < 3; i++) p[3 * rows[k] + i] = c[i] + m[3 * i] * x + m[3 * i + 1] * y + m[3 * i + 2] * z;
        }
      } else {  // "blend": each neck vertex blended back toward where it was by its share
        for (let k = 0; k < rows.length; k++) {
          for (let i = 0; i < 3; i++) {
            const o = 3 * rows[k] + i, b = before[3 * k + i];
            p[o] = b + h.fadeWeights[k] * (p[o] - b);
          }
        }
      }
    }
    return p;
  }

  /** Feature point ``i``'s posed position (mm) after :meth:`pose`. */
  featurePoint(i) {
    const o = 3 * this.fpVertex[i];
    return [this.p[o], this.p[o + 1], this.p[o + 2]];
  }
}
