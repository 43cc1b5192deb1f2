// facerig.js: the face engine's feature-point deformer, run in the page (no dependencies; Node too).
//
// A port of mpeg4fa/face/deformers/feature_points.py (deform): 68 shown FAP values in, every vertex of
// the head out, in millimetres, float64. The rig comes as data (mpeg4fa/serve/fap_head.py rig_data):
// the linear map FAPs -> feature point motion (FAPU x direction already applied), the inner/outer lip
// corner rule, the sparse map feature point motion -> skin and its fold guard (wide weights where skin
// would turn over), the lid sheets (their FAPs and their follow of the eyes' pitch), the tongue roll,
// the jaw, the eyes and the head turn with its fade down the neck, in that order (lips move in the
// jaw's frame, the jaw and eyes in the head's), after each FAP is eased into the head's reach (face/reach.py:
// identity up to a knee, then knee + span x tanh(excess / span) below the limit). Same steps, same order, same numbers: the page's head is the
// Python face's to rounding, not an approximation of it.

const RIG_VERSION = 6;

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

function transpose(a) {
  return [a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]];
}

/** The part of a head rotation the whole neck takes, its cut included (feature_points.neck_bow): the bow
 * (pitch down, rad) past ``throat`` degrees, about the yawed head's left-right axis; null within it. */
export function neckBow(pitch, yaw, throat) {
  const bow = pitch - throat * (Math.PI / 180);
  if (bow <= 0) return null;
  const yawed = rotation(1, yaw);
  return mul(mul(yawed, rotation(0, bow)), transpose(yawed));
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

/** (share, out) -> the rotation ``r`` turned by that share of its angle about its own axis (Rodrigues),
 * row-major, written into ``out`` (9 numbers; a new array if not given: the neck's rows reuse one). */
export function partialRotation(r) {
  const angle = Math.acos(Math.min(1, Math.max(-1, 0.5 * (r[0] + r[4] + r[8] - 1))));
  if (angle < 1e-12) return (share, out = new Float64Array(9)) => { out.set([1, 0, 0, 0, 1, 0, 0, 0, 1]); return out; };
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
  return (share, out = new Float64Array(9)) => {
    const a = share * angle, s = Math.sin(a), c1 = 1 - Math.cos(a);
    for (let i = 0; i < 9; i++) out[i] = (i % 4 === 0 ? 1 : 0) + s * k[i] + c1 * k2[i];
    return out;
  };
}

/** ``angle`` (rad, + down) up to ``knee`` of its limit, then easing into the limit (lids._ease). */
function ease(angle, up, down, knee) {
  const limit = (angle > 0 ? down : up) * (Math.PI / 180), k = knee * limit, a = Math.abs(angle);
  if (a <= k) return angle;
  return Math.sign(angle) * (k + (limit - k) * Math.tanh((a - k) / (limit - k)));
}

/** 0 at or below 0, 1 at or above 1, a cubic with zero slope at both ends (feature_points._smooth_step). */
function smoothStep(x) {
  const t = Math.min(1, Math.max(0, x));
  return t * t * (3 - 2 * t);
}

/** ``magnitude`` past ``knee`` eased below ``limit`` (reach.ease): C1 at the knee, rising, never at the limit. */
export function easeReach(magnitude, knee, limit) {
  if (magnitude <= knee) return magnitude;
  const span = limit - knee;
  return knee + span * Math.tanh((magnitude - knee) / span);
}

const i32 = (a) => Int32Array.from(a);
const f64 = (a) => Float64Array.from(a);

export class FaceRig {
  /** ``data``: the ``rig`` of fap-head.json. */
  constructor(data) {
    if (data.version !== RIG_VERSION) throw new Error(`face rig version ${data.version}, this page reads ${RIG_VERSION}`);
    this.n = data.n_vertices;
    // the head's reach per FAP: [positive, negative] knee and limit magnitudes, null where not limited
    this.reach = data.reach;
    this.shown = new Float64Array(68);
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
    this.lids = new Map(data.lids.map((l) => [l.fap, { ...l, rows: i32(l.rows), ratios: f64(l.ratios) }]));
    this.gaze = data.gaze;
    const f = data.fold;
    this.fold = {
      onset: f.onset, fullRatio: f.full_ratio, columns: i32(f.columns), triangles: i32(f.triangles),
      normal: f64(f.rest_normal), indptr: i32(f.touches.indptr), indices: i32(f.touches.indices), steep: f64(f.touches.steep),
      shift: { rows: i32(f.shift.rows), indptr: i32(f.shift.indptr), indices: i32(f.shift.indices), data: f64(f.shift.data) },
      scalp: { rows: i32(f.scalp.rows), indptr: i32(f.scalp.indptr), indices: i32(f.scalp.indices), data: f64(f.scalp.data) },
    };
    const k = this.fold.columns.length, t = this.fold.triangles.length / 3;
    this.fold.size = new Float64Array(k); this.fold.share = new Float64Array(k); this.fold.moves = new Float64Array(3 * k);
    // the triangles by their steepness summed over columns, steepest first: a frame sums only those whose
    // sum times the largest column motion could pass the threshold (the rest cannot: skipping them is exact)
    const total = new Float64Array(t);
    for (let i = 0; i < t; i++) for (let e = this.fold.indptr[i]; e < this.fold.indptr[i + 1]; e++) total[i] += this.fold.steep[e];
    this.fold.order = Int32Array.from({ length: t }, (_, i) => i).sort((a, b) => total[b] - total[a]);
    this.fold.bound = Float64Array.from(this.fold.order, (i) => total[i]);
    this.roll = { ...data.roll, parts: data.roll.parts.map((r) => ({ side: r.side, rows: i32(r.rows), weights: f64(r.weights) })) };
    this.jaw = { ...data.jaw, rows: i32(data.jaw.rows), weights: f64(data.jaw.weights) };
    this.eyes = data.eyes;
    this.es = data.es;
    this.head = { ...data.head, fadeRows: i32(data.head.fade_rows), fadeWeights: f64(data.head.fade_weights) };
    this.before = new Float64Array(this.head.fadeRows.length * 3);
    this.neckTurn = new Float64Array(9);
  }

  restOf(vertex, c) { return this.rest[3 * vertex + c]; }

  /** The values this head shows (reach.saturate): each FAP past its knee eased into its limit. */
  saturate(v) {
    const out = this.shown, { knee, limit } = this.reach;
    for (let i = 0; i < 68; i++) {
      const x = v[i], side = x < 0 ? 1 : 0, lim = limit[side][i];
      out[i] = lim === null ? x : Math.sign(x) * easeReach(Math.abs(x), knee[side][i], lim);
    }
    return out;
  }

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

  /** The fold guard (FoldGuard.relieve): where the skin the narrow weights moved by ``m`` nears a fold,
   * move the columns around it toward their wide weights, by a share that grows with the motion past the onset
   * (in place, FoldGuard.shares); the upward share of each column's motion also lets the scalp slide
   * (FoldGuard.scalp). */
  relieve(m) {
    const f = this.fold, p = this.p, { columns, size, share, moves, steep, indptr, indices, triangles, normal, order, bound } = f;
    let largest = 0;
    for (let k = 0; k < columns.length; k++) {
      const o = 3 * columns[k], x = m[o], y = m[o + 1], z = m[o + 2];
      moves[3 * k] = x; moves[3 * k + 1] = y; moves[3 * k + 2] = z;
      size[k] = Math.sqrt(x * x + y * y + z * z);
      if (size[k] > largest) largest = size[k];
    }
    const look = 1 - Math.sqrt(f.onset), rest = this.rest, k = 1 - f.onset, widest = 1 - 1 / f.fullRatio;
    let folding = false;
    share.fill(0);
    for (let j = 0; j < order.length && bound[j] * largest > look; j++) {
      const t = order[j];
      let sum = 0;
      for (let e = indptr[t]; e < indptr[t + 1]; e++) sum += steep[e] * size[indices[e]];
      if (!(sum > look)) continue;
      // facing: the posed triangle's area along its rest normal over its rest area
      const a = 3 * triangles[3 * t], b = 3 * triangles[3 * t + 1], c = 3 * triangles[3 * t + 2];
      const ux = p[b] - p[a], uy = p[b + 1] - p[a + 1], uz = p[b + 2] - p[a + 2];
      const wx = p[c] - p[a], wy = p[c + 1] - p[a + 1], wz = p[c + 2] - p[a + 2];
      const facing = (uy * wz - uz * wy) * normal[3 * t] + (uz * wx - ux * wz) * normal[3 * t + 1]
        + (ux * wy - uy * wx) * normal[3 * t + 2];
      if (!(facing < f.onset)) continue;
      folding = true;
      // the share (FoldGuard.shares): where the facing of the skin's motion scaled by s (a quadratic in s)
      // crosses the onset, s0, and the share by how far the motion has gone past it
      const ex = rest[b] - rest[a], ey = rest[b + 1] - rest[a + 1], ez = rest[b + 2] - rest[a + 2];
      const gx = rest[c] - rest[a], gy = rest[c + 1] - rest[a + 1], gz = rest[c + 2] - rest[a + 2];
      const dx = ux - ex, dy = uy - ey, dz = uz - ez, hx = wx - gx, hy = wy - gy, hz = wz - gz;
      const nx = normal[3 * t], ny = normal[3 * t + 1], nz = normal[3 * t + 2];
      const linear = (ey * hz - ez * hy + dy * gz - dz * gy) * nx + (ez * hx - ex * hz + dz * gx - dx * gz) * ny
        + (ex * hy - ey * hx + dx * gy - dy * gx) * nz;
      const square = (dy * hz - dz * hy) * nx + (dz * hx - dx * hz) * ny + (dx * hy - dy * hx) * nz;
      const disc = linear * linear - 4 * square * k;
      const root = Math.sqrt(Math.max(disc, 0));
      const q = -0.5 * (linear + (linear >= 0 ? root : -root));
      let s0 = linear < 0 ? k / q : q / square;  // the root in (0, 1), chosen by sign (see FoldGuard.shares)
      s0 = disc > 0 ? (Number.isNaN(s0) ? 1 : Math.min(1, Math.max(0, s0))) : 1;
      const s = smoothStep((1 - s0) / widest);
      for (let e = indptr[t]; e < indptr[t + 1]; e++) if (s > share[indices[e]]) share[indices[e]] = s;
    }
    if (!folding) return;
    let sharing = false;
    for (let k = 0; k < columns.length; k++) {
      if (!(size[k] > 0)) share[k] = 0;
      sharing ||= share[k] > 0;
      for (let i = 0; i < 3; i++) moves[3 * k + i] *= share[k];
    }
    if (!sharing) return;
    this.addRows(f.shift, moves);
    let rising = false;
    for (let k = 0; k < columns.length; k++) {
      const up = size[k] > 0 ? Math.max(m[3 * columns[k] + 1], 0) / size[k] : 0;
      rising ||= up * share[k] > 0;
      for (let i = 0; i < 3; i++) moves[3 * k + i] *= up;
    }
    if (rising) this.addRows(f.scalp, moves);
  }

  /** p[rows] += matrix (CSR over its rows, columns of the guard) x moves (K x 3), in place. */
  addRows({ rows, indptr, indices, data }, moves) {
    const p = this.p;
    for (let r = 0; r < rows.length; r++) {
      let dx = 0, dy = 0, dz = 0;
      for (let e = indptr[r]; e < indptr[r + 1]; e++) {
        const k = 3 * indices[e], w = data[e];
        dx += w * moves[k]; dy += w * moves[k + 1]; dz += w * moves[k + 2];
      }
      const o = 3 * rows[r];
      p[o] += dx; p[o + 1] += dy; p[o + 2] += dz;
    }
  }

  /** Turn one lid sheet (lids.turn_lid) so that its point drops ``drop`` mm on its arc about the eye centre's x axis. */
  turnLid(lid, drop) {
    const p = this.p, rest = this.rest, c = 3 * lid.joint, q = 3 * lid.point;
    const angle = arcAngle(rest[q + 1] - rest[c + 1], rest[q + 2] - rest[c + 2], drop);
    if (angle === 0) return;
    for (let k = 0; k < lid.rows.length; k++) {
      const a = lid.ratios[k] * angle, co = Math.cos(a), si = Math.sin(a), o = 3 * lid.rows[k];
      const dy = p[o + 1] - rest[c + 1], dz = p[o + 2] - rest[c + 2];
      p[o + 1] = rest[c + 1] + co * dy - si * dz;
      p[o + 2] = rest[c + 2] + si * dy + co * dz;
    }
  }

  /** How far (mm, + down) a lid point descends as its eye pitches by ``pitch`` rad (lids.follow_drop). */
  followDrop(lid, side, pitch) {
    const [share, up, down] = this.gaze.follow[side], rest = this.rest;
    const angle = ease(share * pitch, up, down, this.gaze.knee);
    const y = rest[3 * lid.point + 1] - rest[3 * lid.joint + 1], z = rest[3 * lid.point + 2] - rest[3 * lid.joint + 2];
    return y - (y * Math.cos(angle) - z * Math.sin(angle));
  }

  /** FAPs 19-22 and the lids' follow of the eyes' pitch (lids.lid_moves, apply_lids): each lid turned by its drop. */
  turnLids(v) {
    const rest = this.rest, slit = this.gaze.slit;
    for (const eye of this.gaze.eyes) {
      const vp = v[eye.pitch - 1], vu = v[eye.upper - 1], vl = v[eye.lower - 1];
      if (!(vp || vu || vl)) continue;
      const up = this.lids.get(eye.upper), low = this.lids.get(eye.lower);
      if (!up || !low) continue;
      const pitch = vp * this.angleUnit;
      let followU = pitch ? this.followDrop(up, "upper", pitch) : 0;
      const followL = pitch ? this.followDrop(low, "lower", pitch) : 0;
      const opening = rest[3 * up.point + 1] - rest[3 * low.point + 1];
      followU = Math.min(followU, followL + (1 - slit) * Math.max(opening, 0));
      const closeL = vl * this.irisd;  // mm each FAP closes its lid
      let closeU = vu * this.irisd;
      let tU = opening > 0 ? Math.min(Math.max(closeU / opening, 0), 1) : 0;
      const tL = opening > 0 ? Math.min(Math.max(closeL / opening, 0), 1) : 0;
      if (tU + tL > 1) {  // the lids meet: the upper comes down onto the raised lower lid (lids.lid_moves)
        tU = 1 - tL;
        closeU = tU * opening;
      }
      const moveU = followU + tU * (followL - followU), moveL = followL + tL * (followU - followL);
      if (closeU || moveU) this.turnLid(up, closeU + moveU);
      if (closeL || moveL) this.turnLid(low, -closeL + moveL);
    }
  }

  /** Every vertex (Float64Array, x y z per vertex, mm) posed by one row of 68 shown values. */
  pose(shown) {
    const p = this.p, rest = this.rest, v = this.saturate(shown);
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
      this.relieve(m);
    }
    this.turnLids(v);
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
        const whole = neckBow(pitch, yaw, h.throat_bow);  // a deep bow: the whole neck turns by its excess
        const part = partialRotation(whole ? mul(transpose(whole), r) : r), m = this.neckTurn;
        for (let k = 0; k < rows.length; k++) {
          part(h.fadeWeights[k], m);
          if (whole) m.set(mul(whole, m));
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
