// fba.js: an MPEG-4 FBA (face and body animation) bitstream decoder, for browsers and Node.
//
// A port of the reference decoder of mpeg4fa (mpeg4fa/fba: bits.py, arith.py, syntax.py, params.py,
// decoder.py): the same frames, the same errors at the same bit offsets. No dependencies; the
// standard's numbers come from spec.js, which tools/fbajs_spec.py writes from spec/.
//
//   import { decode, StreamDecoder } from "./fba.js";
//   const stream = decode(bytes);                 // {frames, objectStartCode, fps}; throws FbaError
//   const dec = new StreamDecoder();              // bytes in pieces, frames out as soon as complete
//   for (const frame of dec.push(chunk)) ...; for (const frame of dec.end()) ...;
//
// A frame (class Frame): {index, timestamp, objectMask, fapMask (Uint8Array 68), fapValues (Int32Array
// 68), viseme (Int32Array 4: select1, select2, blend, viseme_def), expression (Int32Array 6: select1,
// intensity1, select2, intensity2, init_face, expression_def), bapMask (Uint8Array 296), bapValues
// (Int32Array 296), skip, startCode, bits, params (intra headers only, else null)}.
import SPEC from "./spec.js";

export { SPEC };
export const OBJECT_START_CODE = 0x1BA;
export const OBJECT_START_CODE_OLD = 0x101;
export const PLANE_START_CODE = 0x1BB;
export const PLANE_START_CODE_OLD = 0x103;
export const END_CODE = 0x1B1;
export const DEFAULT_FPS = 30.0;  // frame rate assumed before an intra header sends one (visage DEF_FRAME_RATE)
const FACE_BIT = 1, BODY_BIT = 2;
const MASK_HOLD = 1, MASK_INTERPOLATE = 2, MASK_ALL = 3;
const RANGE_SET_NAMES = ["i_max", "i_min", "p_max", "p_min"];
const RANGE_DELTA = 60;  // a 5-bit range code c stands for c * 60 quantised units
const TOP = 65535, Q1 = 16384, Q2 = 32768, Q3 = 49152, MAX_FREQUENCY = 16383, MAX_ZERO_RUN = 22, REWIND_BITS = 14;
const N_FAPS = SPEC.n_faps, N_BAPS = SPEC.n_baps;

export const NO_END_CODE = "stream ends without the end code 0x000001B1 (truncated?)";
const SEGMENT_ENDS = "stream ends inside an arithmetic-coded segment";
const STUFFING_EXPECTED = "stuffing '1' expected after 22 zero bits";
const OBJECT_MASK_ZERO = "fba_object_mask is 0: the plane carries neither face nor body data";

/** A stream that cannot be decoded: where (bit offset, frame) and the frames decoded before it. */
export class FbaError extends Error {
  constructor(message, bitOffset = null, frame = null, hint = "") {
    super(message);
    this.name = "FbaError";
    this.bitOffset = bitOffset;
    this.frame = frame;
    this.hint = hint;
    this.partial = null;  // {frames, ...} decoded before the fault, filled in by decode()
  }
  /** "bit N (byte M), frame F", as the Python decoder words it. */
  get where() {
    const parts = [];
    if (this.bitOffset !== null) parts.push(`bit ${this.bitOffset} (byte ${Math.floor(this.bitOffset / 8)})`);
    if (this.frame !== null) parts.push(`frame ${this.frame}`);
    return parts.length ? parts.join(", ") : null;
  }
  toString() {
    const where = this.where;
    const text = where ? `${this.message} at ${where}` : this.message;
    return this.hint ? `${text} (${this.hint})` : text;
  }
}

class UnsupportedFeature extends FbaError {}

/** Thrown inside the decoder when a streaming input has not delivered enough bytes yet. */
const NEED_MORE = { needMore: true };

const truncated = (what, n, left) => `stream ends inside ${what} (needs ${n} bits, ${left} left)`;
const badStuffing = (bits, n) =>
  `stuffing bits ${bits.toString(2).padStart(n, "0")} before a start code should be ` +
  `${((1 << (n - 1)) - 1).toString(2).padStart(n, "0")} (a '0' then '1's)`;
const hex8 = (code) => "0x" + (code >>> 0).toString(16).toUpperCase().padStart(8, "0");

// ---- bits --------------------------------------------------------------------------------------
class BitReader {
  constructor() {
    this.buf = new Uint8Array(0);
    this.nbytes = 0;     // valid bytes in buf
    this.baseBits = 0;   // absolute bit offset of buf[0]
    this.p = 0;          // read index in bits into buf
    this.final = false;  // no more bytes will come: a short read is the stream's end
    this.wanted = 0;     // absolute bit count the last attempt needed: no retry before it has arrived
    this.stuffing = 0;   // stuffing bits before the start code peekStartCode() found
  }
  get pos() { return this.baseBits + this.p; }
  get nbits() { return this.nbytes * 8; }
  append(chunk) {
    const need = this.nbytes + chunk.length;
    if (need > this.buf.length) {
      const grown = new Uint8Array(Math.max(need, this.buf.length * 2, 4096));
      grown.set(this.buf.subarray(0, this.nbytes));
      this.buf = grown;
    }
    this.buf.set(chunk, this.nbytes);
    this.nbytes = need;
  }
  /** Forget the bytes before byte ``keep`` (a plane's start), so memory stays flat on a long stream. */
  drop(keepBits) {
    const dropBytes = Math.floor((keepBits - this.baseBits) / 8);
    if (dropBytes < 65536) return;
    this.buf.copyWithin(0, dropBytes, this.nbytes);
    this.nbytes -= dropBytes;
    this.baseBits += dropBytes * 8;
    this.p -= dropBytes * 8;
  }
  available(n) {
    if (this.p + n <= this.nbytes * 8) return true;
    if (this.final) return false;
    this.wanted = this.baseBits + this.p + n;
    throw NEED_MORE;
  }
  left() { return this.nbytes * 8 - this.p; }
  require(n, what) {
    if (!this.available(n)) throw new FbaError(truncated(what, n, this.left()), this.pos);
  }
  bitsAt(p, n) {
    const buf = this.buf, i = p >> 3;
    if (n <= 24 && i + 3 < this.nbytes) {  // four whole bytes hold them
      const word = ((buf[i] << 24) | (buf[i + 1] << 16) | (buf[i + 2] << 8) | buf[i + 3]) >>> 0;
      return (word >>> (32 - (p & 7) - n)) & ((1 << n) - 1);
    }
    let v = 0;
    for (let b = p; b < p + n; b++) v = v * 2 + ((buf[b >> 3] >> (7 - (b & 7))) & 1);
    return v;
  }
  read(n, what = "a field") {
    this.require(n, what);
    const v = this.bitsAt(this.p, n);
    this.p += n;
    return v;
  }
  /** The start code at the next byte boundary, its stuffing bits in ``stuffing``; -1 if none (see bits.py). */
  peekStartCode() {
    const rest = 8 - (this.p & 7);
    for (let skip = rest === 8 ? 0 : rest; skip <= rest; skip += 8) {
      if (!this.available(skip + 32)) continue;
      const i = (this.p + skip) >> 3;  // a byte boundary: the word is four whole bytes
      const buf = this.buf;
      const word = ((buf[i] << 24) | (buf[i + 1] << 16) | (buf[i + 2] << 8) | buf[i + 3]) >>> 0;
      if (word >>> 8 === 1) { this.stuffing = skip; return word; }
    }
    return -1;
  }
  skipStuffing(n) {
    if (n === 0) return;
    const start = this.pos;
    const bits = this.read(n, "next_start_code() stuffing");
    if (bits !== (1 << (n - 1)) - 1) throw new FbaError(badStuffing(bits, n), start);
  }
}

// ---- the adaptive arithmetic decoder ----------------------------------------------------------
// A uniform intra model is a number (its alphabet size). An adaptive model counts its n symbols (all
// from 1); arith.py keeps the descending cumulative table cum[j] = count(j) + ... + count(n-1) and adds
// 1 to cum[0..s] when symbol s is seen, which is count(s) += 1. Here the counts sit in a Fenwick tree
// over the symbols in reverse order (prefix m = cum[n - m]), so finding a symbol and counting it take
// O(log n) where the table took O(n): P models of wide ranges have thousands of symbols.
//
// All the models of one segment live in one bank of flat typed arrays (as the compiled Python path
// lays them out): the decoder's loop then touches no object but the bank, and V8 sees one shape.
//
// The Fenwick sums at multiples of 32 (the nodes a search visits first and an update last) sit apart,
// in ``coarse``: 66 models of 3,721 symbols keep those in 15 KB that stay in the L1 cache, so that a
// symbol costs two cache lines of the big arrays (its 32-node block of ``tree``, its count) where the
// plain tree cost one per level (12), which is where the decoder's time went on wide ranges.
const BLOCK_BITS = 5, BLOCK = 1 << BLOCK_BITS;

let LOWBITS = new Int16Array(0);
/** x & -x for x = 0 .. n at least: the Fenwick sums of a fresh model (every count 1), copied in at once
 * where a loop in the interpreter cost as much as the intra frame's headers (an intra header is rare,
 * so V8 seldom compiles what it runs). */
function lowbits(n) {
  if (LOWBITS.length <= n) {
    LOWBITS = new Int16Array(2 * n + 2);
    for (let x = 1; x < LOWBITS.length; x++) LOWBITS[x] = x & -x;
  }
  return LOWBITS;
}

/** The adaptive models of one segment: model m has size[m] symbols, counts at freq[foff[m] + s] and
 * its Fenwick sums at tree[toff[m] + x], x = 1 .. 2 * top[m] - 1 (top: the largest power of two <= n),
 * those at x = 32 j read from coarse[coff[m] + j]. Sums past n read as "too much" (0x7fff). */
class ModelBank {
  /** Fresh models of ``sizes`` symbols each, or (``from`` given) a copy of a bank. */
  constructor(sizes, from = null) {
    if (from !== null) {
      this.count = from.count;
      this.size = from.size;  // shared: never written after construction
      this.top = from.top;
      this.foff = from.foff;
      this.toff = from.toff;
      this.coff = from.coff;
      this.total = from.total.slice();
      this.freq = from.freq.slice();
      this.tree = from.tree.slice();
      this.coarse = from.coarse.slice();
      return;
    }
    const count = sizes.length;
    this.count = count;
    this.size = Int32Array.from(sizes);
    this.top = new Int32Array(count);
    this.foff = new Int32Array(count);
    this.toff = new Int32Array(count);
    this.coff = new Int32Array(count);
    this.total = new Int32Array(count);
    let nf = 0, nt = 0, nc = 0;
    for (let m = 0; m < count; m++) {
      const n = this.size[m];
      let top = 1;
      while (top * 2 <= n) top *= 2;
      this.top[m] = top;
      this.foff[m] = nf;
      this.toff[m] = nt;
      this.coff[m] = nc;
      nf += n;
      nt += 2 * top;
      nc += (2 * top) >> BLOCK_BITS;
    }
    // counts and their sums never pass 16383 (the halving), so 16 bits hold them: half the memory of
    // 66 models of up to 3,721 symbols, which is what the decoder's time goes on (cache misses)
    this.freq = new Int16Array(nf).fill(1);
    this.tree = new Int16Array(nt);
    this.coarse = new Int16Array(nc);
    const tree = this.tree, coarse = this.coarse;
    for (let m = 0; m < count; m++) {
      const n = this.size[m], t0 = this.toff[m], c0 = this.coff[m], top2 = 2 * this.top[m];
      tree.set(lowbits(n).subarray(1, n + 1), t0 + 1);  // every count 1: sum over (x - lowbit x, x]
      for (let j = 1; j <= n >> BLOCK_BITS; j++) coarse[c0 + j] = tree[t0 + (j << BLOCK_BITS)];
      // sums past n read as "too much", so the search needs no bounds test
      tree.fill(0x7fff, t0 + n + 1, t0 + top2);
      coarse.fill(0x7fff, c0 + (n >> BLOCK_BITS) + 1, c0 + (top2 >> BLOCK_BITS));
      this.total[m] = n;
    }
  }
  /** Model m's Fenwick sums from its counts, in O(n). */
  build(m) {
    const n = this.size[m], freq = this.freq, tree = this.tree, f0 = this.foff[m], t0 = this.toff[m];
    tree.fill(0, t0, t0 + n + 1);
    for (let x = 1; x <= n; x++) {
      tree[t0 + x] += freq[f0 + n - x];  // reversed position x - 1 holds symbol n - x
      const parent = x + (x & -x);
      if (parent <= n) tree[t0 + parent] += tree[t0 + x];
    }
    const coarse = this.coarse, c0 = this.coff[m];
    for (let j = 1; j <= n >> BLOCK_BITS; j++) coarse[c0 + j] = tree[t0 + (j << BLOCK_BITS)];
  }
  /** Halve every count of model m (its total reached 16383), as arith.py. */
  halve(m) {
    const n = this.size[m], freq = this.freq, f0 = this.foff[m];
    let total = 0;
    for (let j = f0; j < f0 + n; j++) { freq[j] = (freq[j] + 1) >> 1; total += freq[j]; }
    this.total[m] = total;
    this.build(m);
  }
  /** Take back one count of symbol ``s`` of model m (streaming input: a plane cut short by the end of
   * the bytes so far is decoded again when more arrive). Never across a halving. */
  uncount(m, s) {
    const n = this.size[m], t0 = this.toff[m], c0 = this.coff[m], tree = this.tree, coarse = this.coarse;
    this.freq[this.foff[m] + s] -= 1;
    this.total[m] -= 1;
    let x = n - s;
    for (; x <= n && (x & (BLOCK - 1)) !== 0; x += x & -x) tree[t0 + x] -= 1;
    if (x <= n) for (let j = x >> BLOCK_BITS, nj = n >> BLOCK_BITS; j <= nj; j += j & -j) coarse[c0 + j] -= 1;
  }
  copy() { return new ModelBank(null, this); }
}

/** The fault where the segment's next bit should be: more bytes needed (streaming), the stream's end,
 * or a stuffed bit that is not '1'. Returned, for the caller to throw, so that no closure holds ``p``. */
function segmentFault(r, p, nbits) {
  if (p >= nbits) {
    if (!r.final) { r.wanted = r.baseBits + p + 1; return NEED_MORE; }
    return new FbaError(SEGMENT_ENDS, r.baseBits + p);
  }
  return new FbaError(STUFFING_EXPECTED, r.baseBits + p - 1);
}

/** Bits of one segment one at a time, the stuffed '1' after 22 zeros dropped, as arith.py reads them. */
class SegmentBits {
  constructor(r) {
    this.r = r;
    this.p = r.p;
    this.nbits = r.nbytes * 8;
    this.zerorun = 0;
  }
  next() {
    const r = this.r;
    for (;;) {
      if (this.p >= this.nbits) throw segmentFault(r, this.p, this.nbits);
      const bit = (r.buf[this.p >> 3] >> (7 - (this.p & 7))) & 1;
      this.p++;
      if (this.zerorun === MAX_ZERO_RUN) {
        if (!bit) throw segmentFault(r, this.p, this.nbits);
        this.zerorun = 0;
        continue;
      }
      this.zerorun = bit === 0 ? this.zerorun + 1 : 0;
      return bit;
    }
  }
}

/** An intra segment of ``seg`` (a SegmentCoder): uniform models of ``seg.isize[m]`` symbols, renormalised
 * bit by bit as arith.py (one segment per intra header: plain code, kept out of the P path so that V8
 * optimises that one for what it sees on every frame). Each symbol becomes a value at once (its level
 * times its quantiser step) written into ``dest[at + field]``, or into ``seg.values`` in coding order
 * when ``dest`` is null. The products stay exact as doubles (Math.floor): a size may pass 2**15. */
function decodeUniform(r, seg, dest, at) {
  const bits = new SegmentBits(r);
  let code = 0;
  for (let i = 0; i < 16; i++) code = (code << 1) | bits.next();
  const sizes = seg.isize, lo = seg.imin, qstep = seg.qstep, prev = seg.prev, idx = seg.idx, values = seg.values;
  let low = 0, high = TOP;
  for (let m = 0; m < idx.length; m++) {
    const total = sizes[m], length = high - low + 1;
    const target = Math.floor(((code - low + 1) * total - 1) / length);
    const symbol = total - target - 1;
    high = low - 1 + Math.floor((length * (target + 1)) / total);
    low = low + Math.floor((length * target) / total);
    for (;;) {
      if (high < Q2) {
        // nothing
      } else if (low >= Q2) {
        code -= Q2; low -= Q2; high -= Q2;
      } else if (low >= Q1 && high < Q3) {
        code -= Q1; low -= Q1; high -= Q1;
      } else break;
      low <<= 1;
      high = (high << 1) | 1;
      code = (code << 1) | bits.next();
    }
    const level = symbol + lo[m], field = idx[m], q = qstep[m];
    const v = q === 0 ? level : level * q;
    prev[field] = v;
    if (dest === null) values[m] = v; else dest[at + field] = v;
  }
  r.p = bits.p - REWIND_BITS;
}

/** A predictive segment of ``seg``: the adaptive models of ``bank``, counted; each symbol becomes a
 * value at once (level times step, plus the prediction), written as decodeUniform writes them. The
 * integer arithmetic stays under 2**31 (lengths <= 2**16, totals <= 16383). The decoder's time is
 * spent here: one code path for every P frame, no allocation, no closure. */
function decodeAdaptive(r, seg, bank, dest, at) {
  const buf = r.buf, nbytes = r.nbytes, nbits = nbytes * 8;
  let p = r.p, zerorun = 0, code = 0, bit = 0;
  // the first 16 bits in one read: a run of 22 zeros cannot fit in them, so no stuffed bit is there
  const i0 = p >> 3;
  if (p + 16 <= nbits && i0 + 2 < nbytes) {
    code = (((buf[i0] << 16) | (buf[i0 + 1] << 8) | buf[i0 + 2]) >> (8 - (p & 7))) & TOP;
    zerorun = code ? 31 - Math.clz32(code & -code) : 16;
    p += 16;
  } else for (let i = 0; i < 16; i++) {
    // one bit, the stuffed '1' after 22 zeros dropped (inlined twice: V8 runs it faster so)
    for (;;) {
      if (p >= nbits) throw segmentFault(r, p, nbits);
      bit = (buf[p >> 3] >> (7 - (p & 7))) & 1;
      p++;
      if (zerorun === MAX_ZERO_RUN) {
        if (!bit) throw segmentFault(r, p, nbits);
        zerorun = 0;
        continue;
      }
      zerorun = bit === 0 ? zerorun + 1 : 0;
      break;
    }
    code = (code << 1) | bit;
  }
  const freq = bank.freq, tree = bank.tree, totals = bank.total, top = bank.top, size = bank.size;
  const coarse = bank.coarse, foff = bank.foff, toff = bank.toff, coff = bank.coff;
  const lo = seg.pmin, qstep = seg.qstep, prev = seg.prev, idx = seg.idx, values = seg.values, symbols = seg.symbols;
  let low = 0, high = TOP;
  const nm = idx.length;
  for (let m = 0; m < nm; m++) {
    const length = high - low + 1;
    const total = totals[m];
    const target = (((code - low + 1) * total - 1) / length) | 0;
    // the largest pos whose first pos reversed counts sum to <= target: cum[i] <= target < cum[i - 1],
    // i = n - pos. With branches: skewed counts take the same path again and again, and the CPU that
    // predicts it loads the next node before this one arrives (a branchless search waited: 1.5x slower)
    const t0 = toff[m], c0 = coff[m], nsym = size[m];
    let pos = 0, rem = target, step = top[m];
    for (; step >= BLOCK; step >>= 1) {  // nodes at multiples of 32
      const t = coarse[c0 + ((pos + step) >> BLOCK_BITS)];
      if (t <= rem) { pos += step; rem -= t; }
    }
    for (; step > 0; step >>= 1) {  // within one block of 32
      const t = tree[t0 + pos + step];
      if (t <= rem) { pos += step; rem -= t; }
    }
    const symbol = nsym - 1 - pos;
    symbols[m] = symbol;  // before it is counted: a plane cut short uncounts it (SegmentCoder.rollback)
    const cumLo = target - rem, cumHi = cumLo + freq[foff[m] + symbol];
    high = low - 1 + (((length * cumHi) / total) | 0);
    low = low + (((length * cumLo) / total) | 0);
    // count the symbol (arith.py: halve every count first when the total reached 16383)
    if (total === MAX_FREQUENCY) bank.halve(m);
    freq[foff[m] + symbol] += 1;
    totals[m] += 1;
    let x = nsym - symbol;
    for (; x <= nsym && (x & (BLOCK - 1)) !== 0; x += x & -x) tree[t0 + x] += 1;
    if (x <= nsym) for (let j = x >> BLOCK_BITS, nj = nsym >> BLOCK_BITS; j <= nj; j += j & -j) coarse[c0 + j] += 1;
    // Renormalise in one step where no stuffed bit can be among the bits read: while low and high
    // share their top bit the interval lies in one half (n doublings, the bits they share), then
    // each doubling of the middle half (low '01..', high '10..') is a doubling modulo 2**16 with
    // the top bit flipped (k of them, the run of '1' in low over '0' in high that follows).
    const n = Math.clz32(low ^ high) - 16;
    const low2 = (low << n) & TOP, high2 = ((high << n) | ((1 << n) - 1)) & TOP;
    const k = Math.clz32((((low2 & ~high2) << 1) & TOP) ^ TOP) - 16;
    const bits = n + k;
    const i = p >> 3;
    if (bits === 0) {
      // the interval is wide: nothing to read
    } else if (zerorun + bits <= MAX_ZERO_RUN && p + bits <= nbits && i + 2 < nbytes) {
      const word = (buf[i] << 16) | (buf[i + 1] << 8) | buf[i + 2];
      const w = (word >> (24 - (p & 7) - bits)) & ((1 << bits) - 1);
      const flip = k ? Q2 : 0;
      low = ((low2 << k) & TOP) ^ flip;
      high = (((high2 << k) | ((1 << k) - 1)) & TOP) ^ flip;
      code = (((code << bits) | w) & TOP) ^ flip;
      zerorun = w ? 31 - Math.clz32(w & -w) : zerorun + bits;
      p += bits;
    } else for (;;) {  // bit by bit, as arith.py
      if (high < Q2) {
        // nothing
      } else if (low >= Q2) {
        code -= Q2; low -= Q2; high -= Q2;
      } else if (low >= Q1 && high < Q3) {
        code -= Q1; low -= Q1; high -= Q1;
      } else break;
      low <<= 1;
      high = (high << 1) | 1;
      for (;;) {
        if (p >= nbits) throw segmentFault(r, p, nbits);
        bit = (buf[p >> 3] >> (7 - (p & 7))) & 1;
        p++;
        if (zerorun === MAX_ZERO_RUN) {
          if (!bit) throw segmentFault(r, p, nbits);
          zerorun = 0;
          continue;
        }
        zerorun = bit === 0 ? zerorun + 1 : 0;
        break;
      }
      code = (code << 1) | bit;
    }
    const level = symbol + lo[m], field = idx[m], q = qstep[m];
    const v = (q === 0 ? level : level * q) + prev[field];
    prev[field] = v;
    if (dest === null) values[m] = v; else dest[at + field] = v;
  }
  r.p = p - REWIND_BITS;
}

// ---- the two parts: face (FAP) and body (BAP) --------------------------------------------------
const groupRanges = (slices) => slices.map(([a, b]) => Array.from({ length: b - a }, (_, k) => a + k));
const FACE = {
  name: "face", label: "FAP", n: N_FAPS,
  maskGroups: groupRanges(SPEC.fap_group_slices),
  rangeGroups: groupRanges(SPEC.fap_group_slices.slice(1)),
  quantStep: SPEC.fap_quant_step,
  stepMultiplier: (q) => q,
  defaultI: SPEC.fap_i_max_default, defaultP: SPEC.fap_p_max_default,
};
const BODY = {
  name: "body", label: "BAP", n: N_BAPS,
  maskGroups: SPEC.bap_groups, rangeGroups: SPEC.bap_groups,
  quantStep: SPEC.bap_quant_step,
  stepMultiplier: (q) => SPEC.bap_pred_scale[q],
  defaultI: null, defaultP: null,
};
for (const part of [FACE, BODY]) part.order = part.rangeGroups.flat();

const floorDiv = (a, b) => Math.floor(a / b);

/** What a segment needs from its coder, in one shape for both coders: the fields coded (``idx``), the
 * quantiser steps, the I and P ranges (minimum, size), the predictions, the models since the intra
 * header, and the values of the last segment (reused, no allocation per frame). */
class SegmentCoder {
  constructor(n) {
    this.idx = new Int32Array(n);
    this.qstep = new Float64Array(n);
    this.imin = new Float64Array(n);
    this.isize = new Float64Array(n);
    this.pmin = new Float64Array(n);
    this.psize = new Float64Array(n);
    this.prev = null;       // Float64Array: the last value of every field of the part, by field
    this.pModels = null;    // ModelBank, made at the first P segment after an intra header
    this.symbols = new Int32Array(n);  // the last P segment's symbols
    this.values = new Float64Array(n);
  }
  /** The P models before a plane, for streaming input: the bank and its totals, or a whole copy when
   * a model is about to halve (a halving cannot be taken back). A copy per plane cost a megabyte on
   * wide ranges. */
  mark() {
    const bank = this.pModels;
    if (bank === null) return { bank, totals: null, copy: null };
    if (bank.total.includes(MAX_FREQUENCY)) return { bank, totals: null, copy: bank.copy() };
    return { bank, totals: bank.total.slice(), copy: null };
  }
  /** Back to ``mark``: a plane has at most one P segment per coder, so the models it counted are those
   * whose total moved (a prefix, if the segment stopped midway), each with its symbol in ``symbols``. */
  rollback(mark) {
    if (mark.copy !== null) { this.pModels = mark.copy; return; }
    this.pModels = mark.bank;
    if (mark.bank === null) return;
    const bank = mark.bank, totals = bank.total;
    for (let m = bank.count - 1; m >= 0; m--) if (totals[m] !== mark.totals[m]) bank.uncount(m, this.symbols[m]);
  }
  /** The adaptive models of the P segments, made on first use after the intra header. */
  bank() {
    if (this.pModels === null) this.pModels = new ModelBank(this.psize, null);
    return this.pModels;
  }
}

/** FAPs 3..68 or the BAPs: ranges, quantiser steps, prediction and models since the last intra header. */
class ValueCoder {
  constructor(part) {
    this.part = part;
    this.ranges = [0, 1, 2, 3].map(() => new Float64Array(part.n));  // I max, I min, P max, P min
    this.defaultsApplied = false;
    this.prev = new Float64Array(part.n);
    this.savedPrev = new Float64Array(part.n);  // prev at the last snapshot (streaming input)
    this.seg = new SegmentCoder(0);
    this.seg.prev = this.prev;
  }
  startIntra(params) {
    const part = this.part;
    this.ranges = this.ranges.map((a) => a.slice());  // new arrays: a snapshot holds the old ones
    const step = part.stepMultiplier(params.quant);
    const scaler = step || 1;
    if (!this.defaultsApplied && part.defaultI !== null) {
      for (const [k, def] of [[0, part.defaultI], [2, part.defaultP]]) {
        for (let i = 0; i < part.n; i++) {
          const rounded = -floorDiv(-def[i], RANGE_DELTA) * RANGE_DELTA;
          this.ranges[k][i] = floorDiv(rounded, scaler);
          this.ranges[k + 1][i] = -this.ranges[k][i];
        }
      }
    }
    this.defaultsApplied = true;
    for (let k = 0; k < 4; k++) {
      if (!params.ranges.flags[k]) continue;
      for (let i = 0; i < part.n; i++) {
        if (!params.mask[i]) continue;
        const magnitude = floorDiv(params.ranges.codes[k][i] * RANGE_DELTA, scaler);
        this.ranges[k][i] = k % 2 === 0 ? magnitude : -magnitude;
      }
    }
    const idx = part.order.filter((i) => params.mask[i]);
    const seg = new SegmentCoder(idx.length);
    seg.prev = this.prev;
    const [iMax, iMin, pMax, pMin] = this.ranges;
    idx.forEach((i, k) => {
      seg.idx[k] = i;
      seg.qstep[k] = part.quantStep[i] * step;
      seg.imin[k] = iMin[i];
      seg.isize[k] = iMax[i] - iMin[i] + 1;
      seg.pmin[k] = pMin[i];
      seg.psize[k] = pMax[i] - pMin[i] + 1;
    });
    this.seg = seg;
  }
  /** The state before a plane (streaming input), without copying what a plane never changes in place. */
  snapshot() {
    this.savedPrev.set(this.prev);
    return { ranges: this.ranges, defaultsApplied: this.defaultsApplied, seg: this.seg, models: this.seg.mark() };
  }
  restore(s) {
    this.ranges = s.ranges; this.defaultsApplied = s.defaultsApplied;
    this.prev.set(this.savedPrev);
    this.seg = s.seg;
    this.seg.rollback(s.models);
  }
}

const FIELDS = SPEC.high_level_fields;

/** The fields of FAP 1 (viseme) or FAP 2 (expression), whose ranges are fixed. */
class FieldCoder {
  constructor(fap) {
    this.fields = FIELDS.filter((f) => f.fap === fap);
    const n = this.fields.length;
    this.quantised = this.fields.map((f) => f.quantised);
    this.iMax = this.fields.map((f) => f.i_max);
    this.pMax = this.fields.map((f) => f.p_max);
    this.pmin = this.fields.map((f) => f.p_min);
    this.prev = new Float64Array(n);
    this.savedPrev = new Float64Array(n);
    this.names = this.fields.map((f) => `FAP ${fap} ${f.field}`);
    this.seg = new SegmentCoder(n);
    this.seg.prev = this.prev;
  }
  startIntra(q) {
    this.iMax = this.iMax.slice(); this.pMax = this.pMax.slice(); this.pmin = this.pmin.slice();  // a snapshot holds the old
    if (q) {
      const top = floorDiv(SPEC.full_intensity + (q >> 1), q);
      this.fields.forEach((f, k) => {
        if (f.quantised) { this.iMax[k] = top; this.pMax[k] = top; this.pmin[k] = -top; }
      });
    }
    const seg = new SegmentCoder(this.fields.length);
    seg.prev = this.prev;
    this.fields.forEach((f, k) => {
      seg.idx[k] = k;
      seg.qstep[k] = this.quantised[k] ? q : 0;
      seg.imin[k] = f.i_min;
      seg.isize[k] = this.iMax[k] - f.i_min + 1;
      seg.pmin[k] = this.pmin[k];
      seg.psize[k] = this.pMax[k] - this.pmin[k] + 1;
    });
    this.seg = seg;
  }
  /** Selects must name a viseme 0..14 / expression 0..6. */
  checkSelects(values, bitOffset, frame) {
    for (let k = 0; k < values.length; k++) {
      if (this.quantised[k]) continue;
      const v = values[k], max = this.fields[k].i_max;
      if (!(v >= 0 && v <= max)) throw new FbaError(`${this.names[k]} decodes to ${v}, outside 0..${max}`, bitOffset, frame);
    }
  }
  snapshot() {
    this.savedPrev.set(this.prev);
    return { iMax: this.iMax, pMax: this.pMax, pmin: this.pmin, seg: this.seg, models: this.seg.mark() };
  }
  restore(s) {
    this.iMax = s.iMax; this.pMax = s.pMax; this.pmin = s.pmin;
    this.prev.set(this.savedPrev);
    this.seg = s.seg;
    this.seg.rollback(s.models);
  }
}

// ---- header syntax (syntax.py) ----------------------------------------------------------------
function flag(r, what) { return r.read(1, what) === 1; }

function marker(r, what) {
  const pos = r.pos;
  if (r.read(1, what) !== 1) throw new FbaError(`marker bit of ${what} is 0`, pos);
}

/** Many fixed-width fields: the stream's end is checked for all before any marker (as syntax.py). */
function fields(r, widths, what, markers) {
  let total = 0;
  for (const w of widths) total += w;
  if (!r.available(total)) {
    for (let f = 0; f < widths.length; f++) { r.require(widths[f], what(f)); r.p += widths[f]; }
  }
  const start = r.pos, out = new Array(widths.length);
  let p = r.p;
  for (let f = 0; f < widths.length; f++) { out[f] = r.bitsAt(p, widths[f]); p += widths[f]; }
  r.p = p;
  let offset = 0;
  for (let f = 0; f < widths.length; f++) {
    if (markers[f] && out[f] !== 1) throw new FbaError(`marker bit of ${what(f)} is 0`, start + offset);
    offset += widths[f];
  }
  return out;
}

function frameRate(r) {
  if (!flag(r, "is_frame_rate")) return null;
  const frameRate = r.read(SPEC.frame_rate_bits, "frame_rate");
  const seconds = r.read(SPEC.seconds_bits, "seconds");
  const frequencyOffset = r.read(SPEC.frequency_offset_bits, "frequency_offset");
  let fps = frameRate + seconds / SPEC.fps_steps;
  if (frequencyOffset) fps = fps * 1000.0 / 1001.0;
  return { frameRate, seconds, frequencyOffset, fps };
}

function timeCode(r) {
  if (!flag(r, "is_time_code")) return null;
  const hours = r.read(5, "time_code_hours");
  const minutes = r.read(6, "time_code_minutes");
  marker(r, "time_code");
  const seconds = r.read(6, "time_code_seconds");
  return { hours, minutes, seconds, totalSeconds: 3600 * hours + 60 * minutes + seconds };
}

function skipFrames(r) {
  if (!flag(r, "skip_frames")) return 0;
  let total = 0;
  for (;;) {
    const chunk = r.read(4, "number_of_frames_to_skip");
    total += chunk;
    if (chunk !== 15) return total;
  }
}

function groupMasks(r, groups, n, label) {
  const types = [], mask = new Uint8Array(n);
  groups.forEach((members, g) => {
    marker(r, `group ${g + 1} mask`);
    const t = r.read(2, `mask type of ${label} group ${g + 1}`);
    types.push(t);
    if (t === MASK_HOLD || t === MASK_INTERPOLATE) {
      const bits = fields(r, members.map(() => 1), (f) => `mask bit of ${label} ${members[f] + 1}`, members.map(() => false));
      members.forEach((i, f) => { mask[i] = bits[f]; });
    } else if (t === MASK_ALL) {
      for (const i of members) mask[i] = 1;
    }
  });
  return [types, mask];
}

function newMinmax(r, groups, mask, n, label) {
  const flags = RANGE_SET_NAMES.map((name) => flag(r, `is_${name}_new`));
  const codes = [0, 1, 2, 3].map(() => new Int32Array(n));
  const sets = [0, 1, 2, 3].filter((k) => flags[k]);
  if (!sets.length) return { flags, codes };
  const layout = [];
  for (const members of groups) {
    members.forEach((i, j) => {
      if (j % 4 === 0) layout.push(null);
      if (mask[i]) layout.push(i);
    });
  }
  const size = layout.length;
  const isMarker = layout.map((i) => i === null);
  const widths = [], markers = [];
  for (const _ of sets) for (const m of isMarker) { widths.push(m ? 1 : 5); markers.push(m); }
  const what = (f) => {
    const name = RANGE_SET_NAMES[sets[Math.floor(f / size)]], i = layout[f % size];
    return i === null ? `new ${name} ranges` : `new ${name} of ${label} ${i + 1}`;
  };
  const got = fields(r, widths, what, markers);
  sets.forEach((k, row) => {
    layout.forEach((i, j) => { if (i !== null) codes[k][i] = got[row * size + j]; });
  });
  return { flags, codes };
}

function partIntraHeader(r, part) {
  const label = part.label;
  const quant = r.read(5, `${label.toLowerCase()}_quant`);
  const [maskTypes, mask] = groupMasks(r, part.maskGroups, part.n, label);
  const gender = r.read(1, "suggested_gender");
  const pos = r.pos;
  const codingType = r.read(1, "coding_type");
  if (codingType === 1) {
    throw new UnsupportedFeature("DCT segment mode (coding_type 1) is not supported: its syntax is not " +
      "published in any source available to this project", pos);
  }
  const ranges = newMinmax(r, part.rangeGroups, mask, part.n, label);
  return { quant, maskTypes, mask, gender, codingType, ranges };
}

// ---- the decoder (decoder.py) -----------------------------------------------------------------
const VISEME_BITS = ["viseme_def"];
const EXPRESSION_BITS = ["init_face", "expression_def"];
const ZERO_BAP_MASK = new Uint8Array(N_BAPS);
const ZERO_BAP_VALUES = new Int32Array(N_BAPS);
// a frame's face arrays in its slab: values (int32 0..67), viseme (68..71), expression (72..77), mask bytes
const VISEME_AT = N_FAPS, EXPRESSION_AT = N_FAPS + 4, MASK_BYTE = (N_FAPS + 10) * 4;
const FRAME_BYTES = MASK_BYTE + Math.ceil(N_FAPS / 4) * 4, SLAB_FRAMES = 256;

/** A decoded frame. Its face arrays live in a slab that 256 frames share, written as the frame is
 * decoded; the typed arrays that show them are made when first read (and kept). A frame then costs the
 * garbage collector one small object, not five: a decoder holds thousands of frames, and V8's young
 * generation copies every live one at each collection. */
export class Frame {
  constructor(index, objectMask, skip, startCode, params, slab, at) {
    this.index = index;
    this.timestamp = 0.0;
    this.objectMask = objectMask;
    this.bapMask = ZERO_BAP_MASK;
    this.bapValues = ZERO_BAP_VALUES;
    this.skip = skip;
    this.startCode = startCode;
    this.bits = 0;
    this.params = params;
    this._slab = slab;
    this._at = at;  // byte offset in the slab
    this._fapMask = null;
    this._fapValues = null;
    this._viseme = null;
    this._expression = null;
  }
  /** Uint8Array(68): 1 where the frame sends the FAP. */
  get fapMask() { return this._fapMask ??= new Uint8Array(this._slab, this._at + MASK_BYTE, N_FAPS); }
  /** Int32Array(68): the FAP values (FAPU integers; unsent FAPs 0). */
  get fapValues() { return this._fapValues ??= new Int32Array(this._slab, this._at, N_FAPS); }
  /** Int32Array(4): FAP 1's select1, select2, blend, viseme_def. */
  get viseme() { return this._viseme ??= new Int32Array(this._slab, this._at + VISEME_AT * 4, 4); }
  /** Int32Array(6): FAP 2's select1, intensity1, select2, intensity2, init_face, expression_def. */
  get expression() { return this._expression ??= new Int32Array(this._slab, this._at + EXPRESSION_AT * 4, 6); }
}

function foreignKind(head) {
  const at = (offset, magic) => magic.every((b, k) => head[offset + k] === b);
  const four = String.fromCharCode(...head.slice(0, 4));
  if (["RIFF", "RIFX", "RF64"].includes(four)) {
    const form = String.fromCharCode(...head.slice(8, 12));
    return { WAVE: "a WAV audio file", "AVI ": "an AVI video", WEBP: "a WebP image" }[form] || "a RIFF file";
  }
  for (const [offset, magic, kind] of SPEC.signatures) {
    if (head.length >= offset + magic.length && at(offset, magic)) return kind;
  }
  if (head.length >= 2 && head[0] === 0xFF && (head[1] & 0xF6) === 0xF0) return "an AAC (ADTS) audio file";
  if (head.length >= 2 && head[0] === 0xFF && (head[1] & 0xE0) === 0xE0 && (head[1] & 0x06)) return "an MP3 audio file";
  return null;
}

class Decoder {
  constructor() {
    this.r = new BitReader();
    this.faps = new ValueCoder(FACE);
    this.baps = new ValueCoder(BODY);
    this.viseme = new FieldCoder(1);
    this.expression = new FieldCoder(2);
    this.face = null;
    this.body = null;
    this.fps = DEFAULT_FPS;
    this.nextPts = 0.0;
    this.objectStartCode = null;  // set once the object start code is read
    this.k = 0;
    this.done = false;
    this.slab = null;      // ArrayBuffer of the frames being decoded, and views of all of it to write them
    this.slabInts = null;
    this.slabBytes = null;
    this.slabUsed = 0;
  }

  /** The byte offset of a frame's face arrays (values, viseme, expression, mask) in ``this.slab``, one
   * buffer shared by 256 frames: a typed array's own buffer costs V8 far more than a share of one. */
  frameSlot() {
    if (this.slab === null || this.slabUsed === SLAB_FRAMES) {
      this.slab = new ArrayBuffer(SLAB_FRAMES * FRAME_BYTES);
      this.slabInts = new Int32Array(this.slab);
      this.slabBytes = new Uint8Array(this.slab);
      this.slabUsed = 0;
    }
    return FRAME_BYTES * this.slabUsed++;
  }

  objectStart() {
    const r = this.r;
    if (!r.available(32)) throw new FbaError("stream is shorter than a start code: not an FBA stream", 0);
    const code = r.read(32);
    if (code !== OBJECT_START_CODE && code !== OBJECT_START_CODE_OLD) {
      const more = [96, 64, 32, 0].find((n) => r.available(n));
      const head = [code >>> 24, (code >> 16) & 255, (code >> 8) & 255, code & 255];
      for (let b = 0; b < more / 8; b++) head.push(r.read(8));
      const kind = foreignKind(head);
      throw new FbaError(`not an FBA stream: starts with ${hex8(code)}${kind ? ` (${kind})` : ""}, expected ` +
        `the fba_object_start_code ${hex8(OBJECT_START_CODE)}`, 0);
    }
    this.objectStartCode = code;
  }

  /** Consume a plane start code (returned, 0 if none) or the end code (null). */
  betweenPlanes() {
    const r = this.r;
    const code = r.peekStartCode();
    if (code === -1) {
      if (!r.available(8)) throw new FbaError(NO_END_CODE, r.pos);
      return 0;
    }
    const stuffing = r.stuffing;
    if (code !== END_CODE && code !== PLANE_START_CODE && code !== PLANE_START_CODE_OLD) {
      throw new FbaError(`unexpected start code ${hex8(code)} between planes`, r.pos + stuffing);
    }
    r.skipStuffing(stuffing);
    r.read(32);
    return code === END_CODE ? null : code;
  }

  /** One segment of ``coder``: its values into ``dest[at + field]``, or (``dest`` null) returned in coding
   * order (``seg.values``: read before the next segment of this coder). */
  segment(coder, intra, dest, at) {
    const seg = coder.seg;
    if (intra) decodeUniform(this.r, seg, dest, at); else decodeAdaptive(this.r, seg, seg.bank(), dest, at);
    return seg.values;
  }

  plane(k, planeCode) {
    const r = this.r;
    const pos = r.pos;
    const isIntra = flag(r, "is_intra");
    const mask = r.read(2, "fba_object_mask");
    if (mask === 0) throw new FbaError(OBJECT_MASK_ZERO, pos + 1);
    const fr = isIntra ? frameRate(r) : null;
    const tc = isIntra ? timeCode(r) : null;
    const skip = skipFrames(r);
    const params = isIntra ? { frameRate: fr, timeCode: tc, face: null, body: null } : null;
    if (fr !== null) {
      if (fr.fps <= 0) throw new FbaError("frame rate 0 in the intra header", pos);
      this.fps = fr.fps;
    }
    const at = this.frameSlot();
    const frame = new Frame(k, mask, skip, planeCode, params, this.slab, at);
    if (mask & FACE_BIT) this.faceData(frame, isIntra);
    if (mask & BODY_BIT) this.bodyData(frame, isIntra);
    frame.timestamp = tc !== null ? tc.totalSeconds : this.nextPts;
    this.nextPts = frame.timestamp + (skip + 1) / this.fps;
    return frame;
  }

  faceData(frame, intra) {
    const r = this.r;
    if (intra) {
      this.face = partIntraHeader(r, FACE);
      frame.params.face = this.face;
      this.faps.startIntra(this.face);
      this.viseme.startIntra(this.face.quant);
      this.expression.startIntra(this.face.quant);
    } else if (this.face === null) {
      throw new FbaError("a predicted plane carries face data but no intra plane has set up the face", r.pos);
    }
    const mask = this.face.mask;
    const base = frame._at >> 2;
    if (mask[0]) this.highLevel(this.viseme, base + VISEME_AT, VISEME_BITS, frame.index, intra);
    if (mask[1]) this.highLevel(this.expression, base + EXPRESSION_AT, EXPRESSION_BITS, frame.index, intra);
    this.segment(this.faps, intra, this.slabInts, base);
    this.slabBytes.set(mask, frame._at + MASK_BYTE);
  }

  /** FAP 1 or FAP 2: its arithmetic-coded fields, then its one-bit flags. */
  highLevel(coder, at, rawBits, index, intra) {
    const r = this.r, out = this.slabInts;
    const pos = r.pos;
    const values = this.segment(coder, intra, null, 0);
    coder.checkSelects(values, pos, index);
    const n = values.length;
    for (let j = 0; j < n; j++) out[at + j] = values[j];
    for (let j = 0; j < rawBits.length; j++) out[at + n + j] = r.read(1, rawBits[j]);
  }

  bodyData(frame, intra) {
    const r = this.r;
    frame.bapMask = new Uint8Array(N_BAPS);
    frame.bapValues = new Int32Array(N_BAPS);
    if (intra) {
      this.body = partIntraHeader(r, BODY);
      frame.params.body = this.body;
      this.baps.startIntra(this.body);
    } else if (this.body === null) {
      throw new FbaError("a predicted plane carries body data but no intra plane has set up the body", r.pos);
    }
    this.segment(this.baps, intra, frame.bapValues, 0);
    frame.bapMask.set(this.body.mask);
  }

  snapshot() {
    return { p: this.r.p, face: this.face, body: this.body, fps: this.fps, nextPts: this.nextPts,
      faps: this.faps.snapshot(), baps: this.baps.snapshot(), viseme: this.viseme.snapshot(),
      expression: this.expression.snapshot() };
  }

  restore(s) {
    this.r.p = s.p; this.face = s.face; this.body = s.body; this.fps = s.fps; this.nextPts = s.nextPts;
    this.faps.restore(s.faps); this.baps.restore(s.baps); this.viseme.restore(s.viseme);
    this.expression.restore(s.expression);
  }

  /** Decode every frame the bytes so far allow; ``emit(frame)`` each. Stops quietly when more bytes are
   * needed (unless the input is final); throws FbaError at a fault, with ``frame`` set. */
  run(emit) {
    const r = this.r;
    if (this.done || (!r.final && r.baseBits + r.nbits < r.wanted)) return;
    if (this.objectStartCode === null) {
      try {
        this.objectStart();
      } catch (e) {
        if (e === NEED_MORE) { r.p = 0; return; }
        throw e;
      }
    }
    for (;;) {
      const streaming = !r.final;
      if (streaming) r.drop(r.pos);
      const saved = streaming ? this.snapshot() : null;
      try {
        const planeCode = this.betweenPlanes();
        if (planeCode === null) { this.done = true; return; }
        const start = r.pos;
        const frame = this.plane(this.k, planeCode);
        frame.bits = r.pos - start;
        emit(frame);
        this.k += 1;
      } catch (e) {
        if (e === NEED_MORE) { this.restore(saved); return; }
        if (e instanceof FbaError) {
          if (e.frame === null) e.frame = this.k;
          throw e;
        }
        // a guard, not an expected path: any stray error is a malformed stream at the current bit
        const err = new FbaError(`malformed stream (${e && e.name}: ${e && e.message})`, r.pos, this.k);
        throw err;
      }
    }
  }
}

/** Decode a whole stream (Uint8Array / ArrayBuffer). Returns {frames, objectStartCode, fps}; on a fault
 * throws an FbaError whose ``partial`` holds the same for the frames decoded before it. */
export function decode(bytes) {
  const data = bytes instanceof Uint8Array ? bytes : new Uint8Array(bytes);
  const dec = new Decoder();
  dec.r.buf = data;
  dec.r.nbytes = data.length;
  dec.r.final = true;
  const frames = [];
  const result = () => ({ frames, objectStartCode: dec.objectStartCode, fps: streamFps(frames) });
  try {
    dec.run((f) => frames.push(f));
  } catch (e) {
    e.partial = result();
    throw e;
  }
  return result();
}

/** Frame rate of the first intra header that sends one, else 30 (as FapStream.fps). */
export function streamFps(frames) {
  for (const f of frames) if (f.params && f.params.frameRate) return f.params.frameRate.fps;
  return DEFAULT_FPS;
}

/** Bytes in pieces, frames out as soon as complete: ``push(chunk)`` and ``end()`` return the new frames.
 * A fault throws an FbaError (``frame``: its index); its ``partial.frames`` are the frames that call
 * completed before the fault (the earlier ones were returned by earlier calls). */
export class StreamDecoder {
  constructor() { this.dec = new Decoder(); this.frames = 0; }
  get bitOffset() { return this.dec.r.pos; }
  get objectStartCode() { return this.dec.objectStartCode; }
  get finished() { return this.dec.done; }
  push(chunk) {
    this.dec.r.append(chunk instanceof Uint8Array ? chunk : new Uint8Array(chunk));
    return this._run();
  }
  end() {
    this.dec.r.final = true;
    return this._run();
  }
  _run() {
    const out = [];
    try {
      this.dec.run((f) => out.push(f));
    } catch (e) {
      // the frames this call completed before the fault: not returned, so they travel with the error
      e.partial = { frames: out, objectStartCode: this.dec.objectStartCode, fps: streamFps(out) };
      throw e;
    } finally {
      this.frames += out.length;
    }
    return out;
  }
}

/** A one-line summary of a decoded stream: frames, fps, duration, kbit/s (what `mpeg4fa info` shows). */
export function summary(stream, byteLength) {
  const frames = stream.frames, n = frames.length, fps = stream.fps;
  const duration = n ? frames[n - 1].timestamp - frames[0].timestamp + (frames[n - 1].skip + 1) / fps : 0;
  const bits = frames.reduce((s, f) => s + f.bits, 0);
  return { frames: n, fps, duration, bytes: byteLength, bitsPerFrame: n ? bits / n : 0,
    kbps: duration > 0 ? (byteLength * 8) / duration / 1000 : 0,
    intra: frames.filter((f) => f.params).length,
    body: frames.some((f) => f.objectMask & BODY_BIT), face: frames.some((f) => f.objectMask & FACE_BIT) };
}
