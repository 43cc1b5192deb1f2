// lashes.js: the browser head's eyelashes, cards grown from the posed lid margins every frame.
//
// The cards are the GLB's ``lashes`` primitive (mpeg4fa/export/gltf.py: the renderer's lash cards at rest, their
// strands a texture of the shader's, alpha-masked); here they are grown as the Python renderer grows them
// (mpeg4fa/render/lashes.py, lash_vertices) from the layout in the head's key (mpeg4fa/serve/fap_head.py,
// lash_data): each lash leaves the lid's front edge along the eyeball's outward direction, turned about the
// margin's tangent by its lift on the first half and by lift + curl on the second, so the lashes turn with the
// lids whatever they do.
const MM = 0.001;  // millimetres -> the GLB's metres

export class Lashes {
  /** The GLB's lash ``mesh``, posed by :meth:`update` from the rig's posed vertices by the layout ``data`` (the
   * key's ``lashes``). */
  constructor(data, mesh) {
    this.data = data;
    this.mesh = mesh;
    const k = data.rows.length;
    this.k = k;
    this.position = mesh.geometry.attributes.position;
    this.normal = mesh.geometry.attributes.normal;
    if (this.position.count !== 3 * k) throw new Error("the head's lashes: vertex count differs from its key");
    if (this.position.isInterleavedBufferAttribute || this.normal.isInterleavedBufferAttribute) {
      throw new Error("the head's lashes: interleaved vertex data (the pose writes plain arrays)");
    }
    this.positions = new Float32Array(9 * k);  // roots, middles, tips (mm, what tests read back)
    // strands thinner than a pixel far off: their coverage, not an all-or-nothing cut, with the canvas's samples
    mesh.material.alphaToCoverage = true;
    mesh.material.alphaTest = 0.05;
    mesh.frustumCulled = false;  // they move with the lids
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
