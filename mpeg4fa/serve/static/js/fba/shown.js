// shown.js: the 68 FAP values a decoder shows at each frame, from the frames fba.js decodes.
//
// A port of mpeg4fa.decoded.resolve, one frame at a time (the rules look only at the current and
// earlier frames): hold (an unsent FAP keeps its last value), interpolate (mask type 2: an unsent
// FAP copies its left/right, then inner/outer, counterpart sent in the same frame), FAP 1 / FAP 2
// expanded through the viseme and expression profiles of spec/ (a low-level FAP once sent
// overrides them), and clamping to what a face can show. Numbers from spec.js (tools/fbajs_spec.py).
import SPEC from "./spec.js";

const N = SPEC.n_faps;
const GROUP_OF = SPEC.fap_group.map((g) => g - 1);
const SLICES = SPEC.fap_group_slices;
const PARTNERS = SPEC.fap_partners;
const FULL = SPEC.full_intensity;
const LOWER = SPEC.shown_lower.map((x) => (x === null ? -Infinity : x));
const UPPER = SPEC.shown_upper.map((x) => (x === null ? Infinity : x));
const MASK_INTERPOLATE = 2;

/** A row of FAP 1 / FAP 2 fields outside its range: the message expand_high_level gives. */
export class HighLevelError extends Error {
  constructor(message, frame) { super(`${message} at frame ${frame}`); this.name = "HighLevelError"; this.frame = frame; }
}

function checkRow(fap, row, frame) {
  const limits = SPEC.high_level_limits[String(fap)];
  limits.forEach(([name, lo, hi, kind], k) => {
    const v = row[k];
    if (v >= lo && v <= hi) return;
    const what = kind === "select" ? `is not ${fap === 1 ? "a viseme" : "an expression"} (${lo}..${hi})`
      : kind === "flag" ? "is not a flag (0 or 1)" : `is out of range ${lo}..${hi}`;
    throw new HighLevelError(`FAP ${fap} ${name} = ${v} ${what}`, frame);
  });
}

/** Feed decoded frames in order; ``push(frame)`` gives the Float64Array of 68 values it shows. */
export class Shown {
  constructor() {
    this.held = new Float64Array(N);
    this.known = new Uint8Array(N);
    this.viseme = new Int32Array(4);
    this.expression = new Int32Array(6);
    this.headerTypes = null;  // the latest intra header's face mask types, once one came
    this.frames = 0;
  }

  groupTypes(frame) {
    if (frame.params && frame.params.face) this.headerTypes = frame.params.face.maskTypes;
    if (this.headerTypes) return this.headerTypes;
    // a frame no header governs reads as an encoder sends it: 0 none of the group, 3 all, else hold
    return SLICES.map(([a, b]) => {
      let sent = 0;
      for (let i = a; i < b; i++) sent += frame.fapMask[i];
      return sent === 0 ? 0 : sent === b - a ? 3 : 1;
    });
  }

  push(frame) {
    const mask = frame.fapMask, values = frame.fapValues;
    const types = this.groupTypes(frame);
    const out = new Float64Array(N);
    const nowKnown = new Uint8Array(N);
    for (let i = 2; i < N; i++) {
      let value = values[i], sent = mask[i] === 1;
      if (!sent && types[GROUP_OF[i]] === MASK_INTERPOLATE) {
        for (const k of [0, 1]) {  // the left/right partner wins over the inner/outer one
          const j = PARTNERS[i][k];
          if (j >= 0 && mask[j]) { value = values[j]; sent = true; break; }
        }
      }
      if (sent) { out[i] = value; nowKnown[i] = 1; } else if (this.known[i]) { out[i] = this.held[i]; nowKnown[i] = 1; }
    }
    if (mask[0]) this.viseme = frame.viseme.slice();
    if (mask[1]) this.expression = frame.expression.slice();
    const vis = this.viseme, exp = this.expression;
    if (vis.some((x) => x !== 0) || exp.some((x) => x !== 0)) {
      checkRow(1, vis, this.frames);
      checkRow(2, exp, this.frames);
      const V = SPEC.viseme_profiles, E = SPEC.expression_profiles;
      const w = Math.min(Math.max(vis[2], 0), FULL) / FULL;
      const i1 = Math.min(Math.max(exp[1], 0), FULL) / FULL, i2 = Math.min(Math.max(exp[3], 0), FULL) / FULL;
      const v1 = V[vis[0]], v2 = V[vis[1]], e1 = E[exp[0]], e2 = E[exp[2]];
      for (let i = 2; i < N; i++) {
        if (nowKnown[i]) continue;
        // the same operations in the same order as numpy's, so the values are the same to the bit
        let high = v1[i] * w + v2[i] * (1.0 - w);
        high += e1[i] * i1;
        high += e2[i] * i2;
        out[i] = high;
      }
    }
    for (let i = 0; i < N; i++) {
      if (i < 2) { out[i] = 0; continue; }
      if (out[i] < LOWER[i]) out[i] = LOWER[i];
      else if (out[i] > UPPER[i]) out[i] = UPPER[i];
    }
    this.held = out.slice();
    this.known = nowKnown;
    this.frames += 1;
    return out;
  }
}

/** Every frame's shown values: an array of Float64Array(68). */
export function shownValues(frames) {
  const s = new Shown();
  return frames.map((f) => s.push(f));
}
