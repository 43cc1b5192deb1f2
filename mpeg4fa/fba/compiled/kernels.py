"""Every compiled function of the codec, in one file, so that numba's on-disk cache stays right.

numba keys a cached function on its own source file only: a function calling one from another
file would keep its cached machine code when that other file changes (a stale kernel after an
upgrade). With all kernels here, any change to any of them recompiles them all.

Sections: adaptive models as Fenwick trees; the arithmetic decoder of one segment; runs of P
planes. :mod:`mpeg4fa.fba.fastpath` drives them.
"""
from __future__ import annotations

import numpy as np

from . import jit

try:  # LLVM's count-leading/trailing-zeros, for renormalising several bits at once
    from numba.cpython.unsafe.numbers import leading_zeros, trailing_zeros
except ImportError:  # pragma: no cover - without numba the kernels run as plain Python
    def leading_zeros(x):
        return 64 - int(x).bit_length()

    def trailing_zeros(x):
        return (int(x) & -int(x)).bit_length() - 1 if x else 64


# ==== adaptive models as Fenwick trees ==========================================================
# Adaptive frequency models as Fenwick trees over flat arrays (the compiled path's model search).
#
# The reference (:class:`mpeg4fa.fba.arith.AdaptiveModel`) keeps a cumulative table, finds a
# symbol by binary search and adapts in O(n); real ranges reach 3,721 symbols (a FAP with step 1
# and range code 31), so here each model is a Fenwick (binary indexed) tree over its counts:
# search and update in O(log n), identical symbols. All models of a part share three arrays:
#
# * ``freq[foff + s]``: count of symbol ``s`` (every count starts at 1);
# * ``tree[toff + j]``, ``j = 1..n``: the Fenwick sums of those counts (``tree[toff]`` unused);
# * ``total[m]``: the model's total count (``cum[0]`` of the reference).

MAX_FREQUENCY = 16383
"""A model whose total reaches this halves every count before counting the next symbol (SYNTAX.md 9)."""


@jit
def build(freq, foff, tree, toff, n):
    """Fenwick sums of ``freq[foff:foff+n]`` into ``tree[toff+1:toff+n+1]`` in O(n)."""
    for j in range(1, n + 1):
        tree[toff + j] = freq[foff + j - 1]
    for j in range(1, n + 1):
        k = j + (j & -j)
        if k <= n:
            tree[toff + k] += tree[toff + j]


@jit
def prefix(tree, toff, i):
    """Sum of the counts of symbols ``0..i-1``."""
    s = 0
    while i > 0:
        s += tree[toff + i]
        i -= i & -i
    return s


@jit
def find(tree, toff, n, top, t):
    """The symbol ``s`` with ``prefix(s) < t <= prefix(s + 1)``, and ``prefix(s)``.

    ``top`` is the largest power of two <= n. Counts are positive, so prefixes strictly grow.
    """
    pos = 0
    rem = t
    step = top
    while step:
        nxt = pos + step
        if nxt <= n and tree[toff + nxt] < rem:
            pos = nxt
            rem -= tree[toff + nxt]
        step >>= 1
    return pos, t - rem


@jit
def count(freq, foff, tree, toff, n, total, m, s):
    """Count symbol ``s`` in model ``m``; first halve every count when the total reached 16383."""
    if total[m] == MAX_FREQUENCY:
        t = 0
        for j in range(n):
            f = (freq[foff + j] + 1) // 2
            freq[foff + j] = f
            t += f
        total[m] = t
        build(freq, foff, tree, toff, n)
    freq[foff + s] += 1
    total[m] += 1
    j = s + 1
    while j <= n:
        tree[toff + j] += 1
        j += j & -j


def highest_power_of_two(n: np.ndarray) -> np.ndarray:
    """The largest power of two <= n, for each n >= 1: where :func:`find` starts its walk."""
    exponent = np.frexp(np.asarray(n, dtype=np.float64))[1]  # n = m * 2**e with 0.5 <= m < 1, exact for ints
    return np.left_shift(1, exponent - 1).astype(np.int64)


def uniform_bank(sizes: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Fresh models of the given sizes (every count 1): ``foff``, ``toff``, ``freq``, ``tree``, ``total``.

    Counts and sums stay below 2**15 (a model halves at 16383), so the tables are int32: a face with
    every range at its widest holds 66 models of 3,721 symbols, 2 MB of tables rather than 4.
    """
    sizes = np.asarray(sizes, dtype=np.int64)
    ends = np.cumsum(sizes)
    foff = ends - sizes
    toff = foff + np.arange(len(sizes), dtype=np.int64)  # each tree takes n + 1 slots
    freq = np.ones(int(ends[-1]) if len(sizes) else 0, dtype=np.int32)
    tree = np.zeros(len(freq) + len(sizes), dtype=np.int32)
    _uniform_trees(sizes, toff, tree)
    return foff, toff, freq, tree, sizes.copy()


@jit
def _uniform_trees(sizes, toff, tree):
    """A uniform Fenwick tree per model: tree[j] = lowbit(j), the count of 1s it sums."""
    for m in range(sizes.shape[0]):
        for j in range(1, sizes[m] + 1):
            tree[toff[m] + j] = j & -j


# ==== the arithmetic decoder of one segment =====================================================
# The adaptive arithmetic decoder of one segment, on unpacked bits and Fenwick models.
#
# Step for step the reference's :func:`mpeg4fa.fba.arith.decode_segment` (``spec/SYNTAX.md`` 9):
# 16 bits of look-ahead, one symbol per model, a stuffed '1' dropped after 22 zeros, 14 bits
# given back at the end. Symbols go straight to values (level = symbol + P min, times the
# quantiser step, plus the previous value: SYNTAX.md 8), since P planes are all this path decodes.

TOP, Q1, Q2, Q3 = 65535, 16384, 32768, 49152
MAX_ZERO_RUN = 22
REWIND_BITS = 14
END_OF_DATA, BAD_STUFFING = -1, -2
"""Error results of :func:`segment`: the bits ran out, or a '0' stood where a stuffed '1' must."""

# columns of a model table (one row per model, in coding order)
BANK, COL, PREV, QSTEP, PMIN, SIZE, FOFF, TOFF, TOPSTEP, SELMAX = range(10)
META_COLUMNS = 10
VISEME, EXPRESSION, FAP, BAP = range(4)


@jit
def _bit(buf, p, nbuf, zeros):
    """(bit, p, zeros): the next bit, skipping a stuffed '1'; bit END_OF_DATA / BAD_STUFFING on a fault."""
    while True:
        if p >= nbuf:
            return END_OF_DATA, p, zeros
        bit = buf[p]
        p += 1
        if zeros == MAX_ZERO_RUN:
            if bit == 0:
                return BAD_STUFFING, p, zeros
            zeros = 0
            continue
        zeros = zeros + 1 if bit == 0 else 0
        return bit, p, zeros


@jit
def _look_ahead(buf, p, nbuf):
    """A segment's first 16 bits: (code, p, zeros, 0), or (0, fault position, zeros, error)."""
    zeros = 0
    code = 0
    for _ in range(16):
        bit, p, zeros = _bit(buf, p, nbuf, zeros)
        if bit < 0:
            return 0, p, zeros, bit
        code = (code << 1) | bit
    return code, p, zeros, 0


@jit
def _renormalise(buf, p, nbuf, zeros, low, high, code):
    """Double the interval while it lies in one half or the middle half, reading a bit each time:
    (low, high, code, p, zeros, 0), or a fault as the last item."""
    while True:
        if high < Q2 or low >= Q2:  # one half: doubling modulo 2**16 drops the half (code lies between)
            low = (low << 1) & TOP
            high = ((high << 1) | 1) & TOP
            code = (code << 1) & TOP
        elif low >= Q1 and high < Q3:
            low = (low - Q1) << 1
            high = ((high - Q1) << 1) | 1
            code = (code - Q1) << 1
        else:
            break
        if p >= nbuf:
            return low, high, code, p, zeros, END_OF_DATA
        bit = buf[p]
        p += 1
        if zeros == MAX_ZERO_RUN:  # a stuffed '1' after 22 zeros: dropped
            if bit == 0:
                return low, high, code, p, zeros, BAD_STUFFING
            zeros = 0
            if p >= nbuf:
                return low, high, code, p, zeros, END_OF_DATA
            bit = buf[p]
            p += 1
        zeros = (zeros + 1) * (1 - bit)
        code |= bit
    return low, high, code, p, zeros, 0


@jit
def _renormalise_fast(buf, packed, p, nbuf, zeros, low, high, code):
    """:func:`_renormalise` in one step: the doublings counted at once and their bits read from
    ``packed`` (``buf`` packed 8 bits a byte, 8 spare zero bytes at the end) when no stuffed bit can
    lie among them and the window holds them all; otherwise :func:`_renormalise` bit by bit.

    While low and high agree in their top bit the interval lies in one half; the first bit where
    they differ is low's 0 and high's 1, and from then on each doubling of the middle half (low
    '01..', high '10..') is a doubling modulo 2**16 with the top bit flipped. So ``n`` half
    doublings (the leading bits low and high share) are followed by ``k`` middle doublings (the
    run of '1' in low over '0' in high that follows), and no half doubling can come after those.
    """
    n = leading_zeros(np.int64(low ^ high)) - 48
    low2 = (low << n) & TOP
    high2 = ((high << n) | ((1 << n) - 1)) & TOP
    run = ((low2 & ~high2) << 1) & TOP
    k = leading_zeros(np.int64(run ^ TOP)) - 48
    bits = n + k
    if bits == 0:
        return low, high, code, p, zeros, 0
    if zeros + bits > MAX_ZERO_RUN or p + bits > nbuf:
        return _renormalise(buf, p, nbuf, zeros, low, high, code)
    i = p >> 3
    word = (np.int64(packed[i]) << 32) | (np.int64(packed[i + 1]) << 24) | (np.int64(packed[i + 2]) << 16) \
        | (np.int64(packed[i + 3]) << 8) | np.int64(packed[i + 4])
    w = (word >> (40 - (p & 7) - bits)) & ((1 << bits) - 1)
    flip = Q2 if k else 0
    low = ((low2 << k) & TOP) ^ flip
    high = (((high2 << k) | ((1 << k) - 1)) & TOP) ^ flip
    code = (((code << bits) | w) & TOP) ^ flip
    zeros = trailing_zeros(w) if w else zeros + bits
    return low, high, code, p + bits, zeros, 0


@jit
def segment(buf, packed, p, nbuf, meta, lo, hi, total, freq, tree, prev, values):
    """Decode models ``lo..hi-1`` of ``meta`` from ``buf[p:]``; return (position after the rewind, 0)
    or (fault position, END_OF_DATA / BAD_STUFFING). Values land in ``prev`` and ``values[m - lo]``."""
    code, p, zeros, err = _look_ahead(buf, p, nbuf)
    if err < 0:
        return p, err
    low = 0
    high = TOP
    for m in range(lo, hi):
        n = meta[m, SIZE]
        foff = meta[m, FOFF]
        toff = meta[m, TOFF]
        t = total[m]
        length = high - low + 1
        target = ((code - low + 1) * t - 1) // length
        s, before = find(tree, toff, n, meta[m, TOPSTEP], t - target)
        cum_hi = t - before
        cum_lo = cum_hi - freq[foff + s]
        high = low - 1 + (length * cum_hi) // t
        low = low + (length * cum_lo) // t
        low, high, code, p, zeros, err = _renormalise_fast(buf, packed, p, nbuf, zeros, low, high, code)
        if err < 0:
            return p, err
        count(freq, foff, tree, toff, n, total, m, s)
        level = s + meta[m, PMIN]
        q = meta[m, QSTEP]
        value = prev[meta[m, PREV]] + (level * q if q != 0 else level)
        prev[meta[m, PREV]] = value
        values[m - lo] = value
    return p - REWIND_BITS, 0


@jit
def uniform_segment(buf, p, nbuf, sizes, symbols):
    """Decode one symbol per intra (uniform, never adapting) model of ``sizes``: (position after the
    rewind, 0) or (fault position, END_OF_DATA / BAD_STUFFING), as :func:`segment`."""
    code, p, zeros, err = _look_ahead(buf, p, nbuf)
    if err < 0:
        return p, err
    low = 0
    high = TOP
    for m in range(sizes.shape[0]):
        t = sizes[m]
        length = high - low + 1
        target = ((code - low + 1) * t - 1) // length
        s = t - target - 1
        high = low - 1 + (length * (t - s)) // t
        low = low + (length * (t - s - 1)) // t
        low, high, code, p, zeros, err = _renormalise(buf, p, nbuf, zeros, low, high, code)
        if err < 0:
            return p, err
        symbols[m] = s
    return p - REWIND_BITS, 0


# ==== runs of P planes ==========================================================================
# Runs of predicted (P) planes, decoded in one compiled call (``spec/SYNTAX.md`` 2-4, 10, 11).
#
# :func:`decode_planes` reads plane after plane from an unpacked bit window until it meets
# something the Python driver handles: an intra plane (its headers set up the models), the end
# code, the end of the window, a full output block, or a fault. It never stops inside a plane
# with half its state changed: a plane that might not fit in the window is left for the driver
# to load more bits first, so the driver can always call again at the returned position.
#
# Results go in ``res``: ``res[STATUS]`` one of the statuses below, ``res[POS]`` the window
# position to continue from (for INTRA: the plane's first bit, after its start code; for ERROR:
# where the fault is), ``res[ROWS]`` the planes written, ``res[CODE]`` the plane start code before
# an intra plane; for ERROR ``res[FAULT]`` says which (the FAULT_* codes) and ``res[ARG0:]`` its
# details. ``times[0]`` carries the next presentation time in and out.

FULL, END, INTRA, NEED_MORE, ERROR = range(5)
STATUS, POS, ROWS, CODE, FAULT, ARG0, ARG1, ARG2 = range(8)
RESULT_SIZE = 8

# faults, with their arguments (SYNTAX.md sections); the driver words them as the reference does
(TRUNCATED_FIELD,      # field id (FIELD_NAMES), bits needed, bits left
 NO_END_CODE,          # -
 BAD_START_CODE,       # code (its position is res[POS])
 BAD_STUFFING_BITS,    # bits read, how many
 OBJECT_MASK_ZERO,     # -
 NO_FACE_INTRA,        # -
 NO_BODY_INTRA,        # -
 SEGMENT_TRUNCATED,    # -
 SEGMENT_STUFFING,     # -
 SELECT_OUT_OF_RANGE,  # model row, value
 ) = range(10)
FIELD_NAMES = ("is_intra", "fba_object_mask", "skip_frames", "number_of_frames_to_skip", "viseme_def",
               "init_face", "expression_def")
(IS_INTRA, OBJECT_MASK, SKIP_FLAG, SKIP_CHUNK, VISEME_DEF, INIT_FACE, EXPRESSION_DEF) = range(7)

END_CODE, PLANE_START_CODE, PLANE_START_CODE_OLD = 0x000001B1, 0x000001BB, 0x00000103
SYMBOL_BITS = 64
"""A generous bound on the bits one symbol of a segment can take (at most 16 doublings after a
symbol of frequency 1 in 16383, plus stuffing), so a plane's segments fit when this many per
symbol plus 64 per segment are in the window."""


@jit
def _word(buf, p, n):
    v = 0
    for i in range(p, p + n):
        v = (v << 1) | buf[i]
    return v


@jit
def _fail(res, fault, pos, a0, a1, a2):
    res[STATUS] = ERROR
    res[FAULT] = fault
    res[POS] = pos
    res[ARG0] = a0
    res[ARG1] = a1
    res[ARG2] = a2


@jit
def _short(buf, p, n, nbuf, eof, restart, field, res):
    """Whether fewer than ``n`` bits are left for ``field``: then NEED_MORE (restart at ``restart``)
    while the stream goes on, else a TRUNCATED_FIELD fault, is set in ``res``."""
    if p + n <= nbuf:
        return False
    if eof:
        _fail(res, TRUNCATED_FIELD, p, field, n, nbuf - p)
    else:
        res[STATUS] = NEED_MORE
        res[POS] = restart
    return True


@jit
def _start_code(buf, p, nbuf, eof, base):
    """The look-ahead before a plane: (found, code, stuffing bits, need_more)."""
    phase = (base + p) % 8  # the window need not start on a byte boundary of the stream
    for attempt in range(2):
        if attempt == 0 and phase != 0:
            continue
        skip = 0 if attempt == 0 else 8 - phase
        if p + skip + 32 > nbuf:
            if not eof:
                return False, 0, 0, True
            continue
        word = _word(buf, p + skip, 32)
        if word >> 8 == 1:
            return True, word, skip, False
    return False, 0, 0, False


@jit
def _face_segments(fmeta):
    """Rows of each face segment in the model table: visemes lo..hi, expressions lo..hi, FAPs from."""
    vis_hi, exp_lo, exp_hi, fap_lo = 0, 0, 0, 0
    for m in range(fmeta.shape[0]):
        b = fmeta[m, BANK]
        if b == VISEME:
            vis_hi = exp_lo = exp_hi = fap_lo = m + 1
        elif b == EXPRESSION:
            exp_hi = fap_lo = m + 1
    return 0, vis_hi, exp_lo, exp_hi, fap_lo


@jit
def _high_level(buf, packed, p, nbuf, meta, lo, hi, total, freq, tree, prev, scratch, out, row, nraw, first_raw, res):
    """A FAP 1 or FAP 2 segment and its raw bits into ``out[row]``; the new position, or -1 after a fault."""
    seg_start = p
    p, err = segment(buf, packed, p, nbuf, meta, lo, hi, total, freq, tree, prev, scratch)
    if err != 0:
        _segment_fault(res, p, err)
        return -1
    for m in range(lo, hi):
        top = meta[m, SELMAX]
        v = scratch[m - lo]
        if top >= 0 and (v < 0 or v > top):
            _fail(res, SELECT_OUT_OF_RANGE, seg_start, m, v, 0)
            return -1
        out[row, meta[m, COL]] = v
    for j in range(nraw):
        if p + 1 > nbuf:
            _fail(res, TRUNCATED_FIELD, p, first_raw + j, 1, nbuf - p)
            return -1
        out[row, hi - lo + j] = buf[p]
        p += 1
    return p


@jit
def _segment_fault(res, p, err):
    if err == BAD_STUFFING:
        _fail(res, SEGMENT_STUFFING, p - 1, 0, 0, 0)
    else:
        _fail(res, SEGMENT_TRUNCATED, p, 0, 0, 0)


@jit
def decode_planes(buf, packed, base, p, nbuf, eof,
                  fmeta, ftotal, ffreq, ftree, fprev, face_ready, vis_on, exp_on,
                  bmeta, btotal, bfreq, btree, bprev, body_ready,
                  fps, times,
                  o_obj, o_skip, o_code, o_ts, o_bits, o_vis, o_exp, o_fap, o_bap, max_rows, res, scratch):
    rows = 0
    nf = fmeta.shape[0]
    nb = bmeta.shape[0]
    face_bound = 64 * 3 + SYMBOL_BITS * nf + 8
    body_bound = 64 + SYMBOL_BITS * nb
    has_bap_out = o_bap.shape[0] > 0
    vis_lo, vis_hi, exp_lo, exp_hi, fap_lo = _face_segments(fmeta)
    res[CODE] = 0
    while True:
        res[ROWS] = rows
        if rows == max_rows:
            res[STATUS] = FULL
            res[POS] = p
            return
        restart = p
        found, code, stuffing, more = _start_code(buf, p, nbuf, eof, base)
        if more:
            res[STATUS] = NEED_MORE
            res[POS] = restart
            return
        plane_code = 0
        if not found:
            if nbuf - p < 8:
                if not eof:
                    res[STATUS] = NEED_MORE
                    res[POS] = restart
                    return
                _fail(res, NO_END_CODE, p, 0, 0, 0)
                return
        else:
            if code != END_CODE and code != PLANE_START_CODE and code != PLANE_START_CODE_OLD:
                _fail(res, BAD_START_CODE, p + stuffing, code, 0, 0)
                return
            if stuffing:
                bits = _word(buf, p, stuffing)
                if bits != (1 << (stuffing - 1)) - 1:
                    _fail(res, BAD_STUFFING_BITS, p, bits, stuffing, 0)
                    return
            p += stuffing + 32
            if code == END_CODE:
                res[STATUS] = END
                res[POS] = p
                return
            plane_code = code
        start = p
        # ---- header: is_intra, fba_object_mask, skip_frames (SYNTAX.md 3)
        if _short(buf, p, 1, nbuf, eof, restart, IS_INTRA, res):
            return
        if buf[p]:
            res[STATUS] = INTRA
            res[POS] = start
            res[CODE] = plane_code
            return
        p += 1
        if _short(buf, p, 2, nbuf, eof, restart, OBJECT_MASK, res):
            return
        mask = _word(buf, p, 2)
        p += 2
        if mask == 0:
            _fail(res, OBJECT_MASK_ZERO, start + 1, 0, 0, 0)
            return
        skip = 0
        if _short(buf, p, 1, nbuf, eof, restart, SKIP_FLAG, res):
            return
        p += 1
        if buf[p - 1]:
            while True:
                if _short(buf, p, 4, nbuf, eof, restart, SKIP_CHUNK, res):
                    return
                chunk = _word(buf, p, 4)
                p += 4
                skip += chunk
                if chunk != 15:
                    break
        if mask & 1 and not face_ready:
            _fail(res, NO_FACE_INTRA, p, 0, 0, 0)
            return
        need = (face_bound if mask & 1 else 0) + (body_bound if mask & 2 else 0)
        if not eof and nbuf - p < need:
            res[STATUS] = NEED_MORE
            res[POS] = restart
            return
        # ---- face data (SYNTAX.md 10)
        for j in range(4):
            o_vis[rows, j] = 0
        for j in range(6):
            o_exp[rows, j] = 0
        for j in range(o_fap.shape[1]):
            o_fap[rows, j] = 0
        if mask & 1:
            if vis_on:
                p = _high_level(buf, packed, p, nbuf, fmeta, vis_lo, vis_hi, ftotal, ffreq, ftree, fprev, scratch,
                                o_vis, rows, 1, VISEME_DEF, res)
                if p < 0:
                    return
            if exp_on:
                p = _high_level(buf, packed, p, nbuf, fmeta, exp_lo, exp_hi, ftotal, ffreq, ftree, fprev, scratch,
                                o_exp, rows, 2, INIT_FACE, res)
                if p < 0:
                    return
            p, err = segment(buf, packed, p, nbuf, fmeta, fap_lo, nf, ftotal, ffreq, ftree, fprev, scratch)
            if err != 0:
                _segment_fault(res, p, err)
                return
            for m in range(fap_lo, nf):
                o_fap[rows, fmeta[m, COL]] = scratch[m - fap_lo]
        # ---- body data (SYNTAX.md 11)
        if has_bap_out:
            for j in range(o_bap.shape[1]):
                o_bap[rows, j] = 0
        if mask & 2:
            if not body_ready:
                _fail(res, NO_BODY_INTRA, p, 0, 0, 0)
                return
            p, err = segment(buf, packed, p, nbuf, bmeta, 0, nb, btotal, bfreq, btree, bprev, scratch)
            if err != 0:
                _segment_fault(res, p, err)
                return
            if has_bap_out:
                for m in range(nb):
                    o_bap[rows, bmeta[m, COL]] = scratch[m]
        # ---- the frame (SYNTAX.md 4)
        t = times[0]
        o_obj[rows] = mask
        o_skip[rows] = skip
        o_code[rows] = plane_code
        o_ts[rows] = t
        o_bits[rows] = p - start
        times[0] = t + (skip + 1) / fps
        rows += 1


# ==== the encoder: segments and runs of P planes ================================================
# The mirror of the above for the encoder (``mpeg4fa.fba.encoder``): quantise against the
# closed-loop prediction, code one segment with the same models, and write runs of P planes
# into an unpacked bit array, recording each frame's bit span and each segment's end (for the
# writer's hazard checks). Faults stop the run and are worded by the driver as the reference does.

(RANGE_ERROR,          # model row, the change, its level
 NO_FACE_BEFORE,       # -
 NO_BODY_BEFORE,       # -
 FIELD_TOO_WIDE,       # field id (ENCODE_FIELD_NAMES), value, width
 ) = range(4)
ENCODE_FIELD_NAMES = ("fba_object_mask", "viseme_def", "init_face", "expression_def", "number_of_frames_to_skip")
(E_OBJECT_MASK, E_VISEME_DEF, E_INIT_FACE, E_EXPRESSION_DEF, E_SKIP_CHUNK) = range(5)


@jit
def quantise(x, q):
    """The reference quantiser (SYNTAX.md 8): 0 when |x| <= q/2, else round(|x|/q) half up; sign kept."""
    if q == 0:
        return x
    a = -x if x < 0 else x
    level = 0 if a <= q // 2 else (a + q // 2) // q
    return -level if x < 0 else level


@jit
def _put(out, o, bit, pending, zeros):
    """Emit ``bit`` then ``pending`` opposite bits, stuffing a '1' after 22 zeros: (o, zeros)."""
    for j in range(pending + 1):
        b = bit if j == 0 else 1 - bit
        if zeros == MAX_ZERO_RUN:
            out[o] = 1
            o += 1
            zeros = 0
        out[o] = b
        o += 1
        zeros = zeros + 1 if b == 0 else 0
    return o, zeros


@jit
def encode_segment(out, o, meta, lo, hi, total, freq, tree, symbols):
    """Code ``symbols[m - lo]`` with models ``lo..hi-1``, adapting them, and flush: (o, trailing zeros)."""
    low = 0
    high = TOP
    pending = 0
    zeros = 0
    for m in range(lo, hi):
        s = symbols[m - lo]
        t = total[m]
        foff = meta[m, FOFF]
        toff = meta[m, TOFF]
        before = prefix(tree, toff, s)
        cum_hi = t - before
        cum_lo = cum_hi - freq[foff + s]
        length = high - low + 1
        high = low - 1 + (length * cum_hi) // t
        low = low + (length * cum_lo) // t
        while True:
            if high < Q2:
                o, zeros = _put(out, o, 0, pending, zeros)
                pending = 0
            elif low >= Q2:
                o, zeros = _put(out, o, 1, pending, zeros)
                pending = 0
                low -= Q2
                high -= Q2
            elif low >= Q1 and high < Q3:
                pending += 1
                low -= Q1
                high -= Q1
            else:
                break
            low <<= 1
            high = (high << 1) | 1
        count(freq, foff, tree, toff, meta[m, SIZE], total, m, s)
    o, zeros = _put(out, o, 0 if low < Q1 else 1, pending + 1, zeros)  # the flush (SYNTAX.md 9)
    return o, zeros


@jit
def _symbols(meta, lo, hi, prev, values, symbols, res):
    """P-frame symbols of models ``lo..hi-1`` for ``values`` (indexed by column), the prediction updated;
    False (and a RANGE_ERROR in ``res``) when a change falls outside its model."""
    for m in range(lo, hi):
        j = meta[m, PREV]
        q = meta[m, QSTEP]
        diff = values[meta[m, COL]] - prev[j]
        level = quantise(diff, q)
        s = level - meta[m, PMIN]
        if s < 0 or s >= meta[m, SIZE]:
            res[FAULT] = RANGE_ERROR
            res[ARG0] = m
            res[ARG1] = diff
            res[ARG2] = level
            return False
        symbols[m - lo] = s
        prev[j] += level * q if q != 0 else level
    return True


@jit
def _bits(out, o, value, n):
    for i in range(n - 1, -1, -1):
        out[o] = (value >> i) & 1
        o += 1
    return o


@jit
def encode_planes(out, base, first, stop, obj, skip, codes, pads, vis, exp, faps, baps,
                  fmeta, ftotal, ffreq, ftree, fprev, face_ready, vis_on, exp_on,
                  bmeta, btotal, bfreq, btree, bprev, body_ready,
                  spans, ends, res, scratch):
    """Write P frames ``first..stop-1`` from ``out[0]`` on (``base``: the stream bits before it).

    ``spans[r] = (start, end)`` of frame ``first + r`` (absolute, after its start code), ``ends[e] =
    (frame, end, trailing zeros, last-in-frame)`` per segment. ``res[STATUS]`` FULL when every frame
    was written, ERROR with ``res[ROWS]`` the frame and ``res[POS]`` the bit of the fault.
    Returns the bits written and the segments recorded.
    """
    o = 0
    e = 0
    nf = fmeta.shape[0]
    vis_lo, vis_hi, exp_lo, exp_hi, fap_lo = _face_segments(fmeta)
    nb = bmeta.shape[0]
    res[STATUS] = FULL
    for k in range(first, stop):
        res[ROWS] = k
        if codes[k] != 0:  # next_start_code() then the plane start code (SYNTAX.md 2)
            n = 8 - (base + o) % 8
            o = _bits(out, o, (1 << (n - 1)) - 1, n)
            o = _bits(out, o, codes[k], 32)
        start = o
        mask = obj[k]
        o = _bits(out, o, 0, 1)  # is_intra
        if mask > 3:
            _fail(res, FIELD_TOO_WIDE, base + o, E_OBJECT_MASK, mask, 2)
            return o, e
        o = _bits(out, o, mask, 2)
        count_skip = skip[k]
        if count_skip > 0 or pads[k]:  # skip_frames: 4-bit chunks while a chunk is 15 (SYNTAX.md 3)
            o = _bits(out, o, 1, 1)
            remaining = count_skip
            while True:
                chunk = remaining if remaining < 15 else 15
                if chunk < 0:
                    _fail(res, FIELD_TOO_WIDE, base + o, E_SKIP_CHUNK, chunk, 4)
                    return o, e
                o = _bits(out, o, chunk, 4)
                remaining -= chunk
                if chunk != 15:
                    break
        else:
            o = _bits(out, o, 0, 1)
        last = -1
        if mask & 1:
            if not face_ready:
                _fail(res, NO_FACE_BEFORE, base + o, 0, 0, 0)
                return o, e
            for part in range(2):
                on = vis_on if part == 0 else exp_on
                if not on:
                    continue
                lo = vis_lo if part == 0 else exp_lo
                hi = vis_hi if part == 0 else exp_hi
                row = vis[k] if part == 0 else exp[k]
                if not _symbols(fmeta, lo, hi, fprev, row, scratch, res):
                    res[STATUS], res[POS], res[CODE] = ERROR, base + o, 0
                    return o, e
                o, z = encode_segment(out, o, fmeta, lo, hi, ftotal, ffreq, ftree, scratch)
                ends[e, 0], ends[e, 1], ends[e, 2], ends[e, 3] = k, base + o, z, 0
                last = e
                e += 1
                for j in range(1 if part == 0 else 2):
                    v = row[hi - lo + j]
                    if v < 0 or v > 1:
                        _fail(res, FIELD_TOO_WIDE, base + o, (E_VISEME_DEF if part == 0 else E_INIT_FACE) + j, v, 1)
                        return o, e
                    o = _bits(out, o, v, 1)
            if not _symbols(fmeta, fap_lo, nf, fprev, faps[k], scratch, res):
                res[STATUS], res[POS], res[CODE] = ERROR, base + o, 0
                return o, e
            o, z = encode_segment(out, o, fmeta, fap_lo, nf, ftotal, ffreq, ftree, scratch)
            ends[e, 0], ends[e, 1], ends[e, 2], ends[e, 3] = k, base + o, z, 0
            last = e
            e += 1
        if mask & 2:
            if not body_ready:
                _fail(res, NO_BODY_BEFORE, base + o, 0, 0, 0)
                return o, e
            if not _symbols(bmeta, 0, nb, bprev, baps[k], scratch, res):
                res[STATUS], res[POS], res[CODE] = ERROR, base + o, 1
                return o, e
            o, z = encode_segment(out, o, bmeta, 0, nb, btotal, bfreq, btree, scratch)
            ends[e, 0], ends[e, 1], ends[e, 2], ends[e, 3] = k, base + o, z, 0
            last = e
            e += 1
        if last >= 0:
            ends[last, 3] = 1
        spans[k - first, 0] = base + start
        spans[k - first, 1] = base + o
    return o, e


@jit
def closed_loop_extremes(values, qstep, a, b, out):
    """Largest P level up and down of each parameter over frames a+1..b-1 of an intra period starting
    at a, against the closed-loop reconstruction (what ``_range_codes`` needs), into ``out[0:2]``; the
    intra levels into ``out[2:4]``."""
    n = values.shape[1]
    for i in range(n):
        q = qstep[i]
        level = quantise(values[a, i], q)
        recon = level * q if q != 0 else level
        out[2, i] = level
        out[3, i] = -level
        up = 0
        down = 0
        for k in range(a + 1, b):
            level = quantise(values[k, i] - recon, q)
            recon += level * q if q != 0 else level
            if level > up:
                up = level
            if -level > down:
                down = -level
        out[0, i] = up
        out[1, i] = down


@jit
def first_overflow(values, qstep, mask, limit, a, b):
    """The first frame in a+1..b-1 whose closed-loop P level of a masked parameter is beyond
    +-``limit``, with that column and level; (-1, -1, 0) when the whole period fits."""
    n = values.shape[1]
    recon = np.zeros(n, dtype=np.int64)
    for i in range(n):
        q = qstep[i]
        level = quantise(values[a, i], q)
        recon[i] = level * q if q != 0 else level
    for k in range(a + 1, b):
        for i in range(n):
            if not mask[i]:
                continue
            q = qstep[i]
            level = quantise(values[k, i] - recon[i], q)
            if level > limit or level < -limit:
                return k, i, level
            recon[i] += level * q if q != 0 else level
    return -1, -1, 0
