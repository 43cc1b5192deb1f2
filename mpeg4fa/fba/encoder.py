"""fba_object() encoding.

Encoding is two steps. :func:`plan` decides the coding parameters (which frames
are intra and what their headers say, skip counts, plane start codes) from the
data and :class:`EncodeOptions`; :func:`write` turns a fully planned
:class:`FapStream` into bits, exactly as planned. A decoded stream is already
fully planned, which is why re-encoding it gives the same bytes.
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Sequence

import numpy as np

from . import syntax
from .arith import SegmentEnd, encode_segment, lookahead_desyncs
from .bits import BitWriter
from .errors import FbaError
from .limits import check_span, fps_problem
from .params import BODY, FACE, RANGE_DELTA, FieldCoder, PartSpec, ValueCoder, dequantise, quantise
from .stream import (BODY as BODY_BIT, CONTENT_FIELDS, END_CODE, FACE as FACE_BIT, N_BAPS, PLANE_START_CODE,
                     CodingParams, FapStream, FrameRate, PartParams, RangeSet, TimeCode)

MAX_REPAIRS = 32


@dataclass
class EncodeOptions:
    """Coding choices; ``None`` keeps what the stream carries (or a sensible default)."""

    fap_quant: int | None = None
    bap_quant: int | None = None
    intra_period: int | None = None
    """Frames from one intra frame to the next; 0 = only the first frame (and mask changes)."""
    mask_types: Sequence[int] | None = None
    """Per FAP group (10): 0 none, 1 hold unsent FAPs, 2 interpolate them, 3 all. Types 0 and 3 must match the data."""
    fps: float | None = None
    start_codes: bool | None = None
    """Send a plane start code before every intra plane."""
    skip_repeats: bool = False
    """Fold frames equal to their predecessor into the predecessor's skip count."""
    time_codes: bool = False
    """Send a time code in every intra header that falls on a whole second (time codes hold whole seconds)."""
    optimize: bool = False
    """Smallest stream with the same decoded values: tight ranges per intra period, repeats folded."""

    def __post_init__(self) -> None:
        """Refuse options no stream can carry, so a bad value fails here and says which."""
        for name in ("fap_quant", "bap_quant"):
            value = getattr(self, name)
            if value is not None and (not _is_int(value) or not 0 <= value <= 31):
                raise FbaError(f"EncodeOptions {name}={value!r} is not an integer in 0..31",
                               hint="the quantiser is a 5-bit field; 0 sends values unquantised")
        if self.intra_period is not None and (not _is_int(self.intra_period) or self.intra_period < 0):
            raise FbaError(f"EncodeOptions intra_period={self.intra_period!r} is not an integer >= 0",
                           hint="0 sends an intra frame only where the mask changes")
        if self.fps is not None and (problem := fps_problem(self.fps)) is not None:
            raise FbaError(f"EncodeOptions fps={self.fps!r}: {problem}",
                           hint="an intra header carries 1/16 to 255 15/16 frames per second")


def _is_int(value: object) -> bool:
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def encode(stream: FapStream, options: EncodeOptions | None = None, *, backend: str = "auto") -> bytes:
    """Encode a stream; with no options a decoded stream re-encodes with its own parameters.

    ``backend``: ``"auto"`` (compiled when numba is there), ``"compiled"`` or ``"python"`` (the
    reference); both write the same bytes and raise the same errors.
    """
    if options is None and 0 in stream.intra:
        return write(stream, backend=backend)
    return write(plan(stream, options or EncodeOptions(), backend=backend), backend=backend)


# ---- planning -----------------------------------------------------------------------------
def plan(stream: FapStream, options: EncodeOptions, *, backend: str = "auto") -> FapStream:
    """Fill in intra headers, skips and start codes for ``stream`` according to ``options``
    (``backend`` as for :func:`encode`: who runs the closed-loop range search)."""
    from .compiled import use_compiled

    compiled = use_compiled(backend)
    if not len(stream):
        raise FbaError("cannot encode a stream with no frames")
    first = stream.first_params
    out = stream.copy()
    out.intra = {}
    out.object_mask = np.where(out.object_mask == 0, FACE_BIT, out.object_mask).astype(np.uint8)
    fps = options.fps if options.fps is not None else stream.fps
    frame_rate = FrameRate.from_fps(fps)
    check_span(stream, fps)
    face_quant = _pick(options.fap_quant, first.face.quant if first and first.face else None, 1)
    body_quant = _pick(options.bap_quant, first.body.quant if first and first.body else None, 1)
    period = options.intra_period or 0
    use_start_codes = _pick(options.start_codes, bool(stream.start_code.any()), False)

    intended = stream.group_mask_types()  # how unsent FAPs read in the source: kept, unless options say otherwise
    changed = np.zeros(len(out), dtype=bool)  # frames whose masks differ from the frame before
    changed[1:] = ((out.object_mask[1:] != out.object_mask[:-1]) | (out.fap_mask[1:] != out.fap_mask[:-1]).any(axis=1)
                   | (out.bap_mask[1:] != out.bap_mask[:-1]).any(axis=1))
    if options.mask_types is None:
        changed[1:] |= (intended[1:] != intended[:-1]).any(axis=1)
    intra_frames = [0]
    for k, new_masks in enumerate(changed.tolist()):
        if k and (new_masks or (period and k - intra_frames[-1] >= period)):
            intra_frames.append(k)
    required = {0, *np.flatnonzero(changed).tolist()}  # the first frame and mask changes: fixed places
    source = list(range(len(out)))  # the source frame of each frame of out
    if options.skip_repeats or options.optimize:  # after choosing intra frames, so they stay where they were
        out, source = _fold_repeats(out, protect=intra_frames)
        intra_frames = [source.index(k) for k in intra_frames]
        required = {source.index(k) for k in required}
    intra_frames = _fit_intra_frames(out, intra_frames, required, face_quant, body_quant, compiled)
    bounds = intra_frames[1:] + [len(out)]

    wide = {}
    if not options.optimize:  # one set of ranges, wide enough for the whole stream
        wide["face"] = _range_codes(out, FACE, face_quant, intra_frames, bounds, compiled)
        wide["body"] = _range_codes(out, BODY, body_quant, intra_frames, bounds, compiled)
    for g, (k, stop) in enumerate(zip(intra_frames, bounds)):
        params = CodingParams(frame_rate=frame_rate)
        if options.time_codes and float(out.timestamps[k]).is_integer():
            params.time_code = TimeCode.from_seconds(out.timestamps[k])
        if out.object_mask[k] & FACE_BIT:
            codes = wide["face"] if wide else _range_codes(out, FACE, face_quant, [k], [stop], compiled)
            params.face = PartParams(face_quant, _mask_types(out.fap_mask[k], FACE, options.mask_types,
                                                             intended[source[k]]),
                                     out.fap_mask[k].copy(), ranges=_ranges(codes, out.fap_mask[k], FACE, options))
        if out.object_mask[k] & BODY_BIT:
            codes = wide["body"] if wide else _range_codes(out, BODY, body_quant, [k], [stop], compiled)
            params.body = PartParams(body_quant, _mask_types(out.bap_mask[k], BODY, None, None),
                                     out.bap_mask[k].copy(), ranges=_ranges(codes, out.bap_mask[k], BODY, options))
        out.intra[k] = params
    out.start_code[:] = 0
    if use_start_codes:
        out.start_code[intra_frames] = PLANE_START_CODE
    out.timestamps = _grid_times(out, fps)
    return out


def _ranges(codes: np.ndarray, mask: np.ndarray, part: PartSpec, options: EncodeOptions) -> RangeSet:
    """The four range sets of an intra header: all sent, except (``optimize``) where the header
    masks no parameter that has ranges (FAP 1 and 2 have none), so no range is in use and every
    decoder reads the same values whatever it keeps."""
    send = not options.optimize or any(bool(mask[list(group)].any()) for group in part.range_groups)
    return RangeSet((send,) * 4, codes)


def _limits(part: PartSpec, quant: int) -> tuple[np.ndarray, int]:
    """Quantiser steps of ``part`` at ``quant`` and the largest level a 5-bit range code covers (31 x 60 / scaler)."""
    step = part.step_multiplier(quant)
    return part.quant_step * step, 31 * RANGE_DELTA // (step or 1)


def _intra_overflow(s: FapStream, part: PartSpec, quant: int, k: int) -> tuple[int, int] | None:
    """(column, level) of the first parameter frame ``k`` cannot send as an intra value, or None."""
    values, masks = (s.fap_values, s.fap_mask) if part is FACE else (s.bap_values, s.bap_mask)
    if not s.object_mask[k] & (FACE_BIT if part is FACE else BODY_BIT):
        return None
    qstep, limit = _limits(part, quant)
    level = quantise(values[k], qstep)
    bad = np.flatnonzero(masks[k] & (np.abs(level) > limit))
    return (int(bad[0]), int(level[bad[0]])) if bad.size else None


def _p_overflow(s: FapStream, part: PartSpec, quant: int, a: int, b: int, compiled: bool) -> tuple[int, int, int] | None:
    """(frame, column, level) of the first P change in a+1..b-1 beyond every range code, or None."""
    values, masks = (s.fap_values, s.fap_mask) if part is FACE else (s.bap_values, s.bap_mask)
    if b - a < 2 or not s.object_mask[a] & (FACE_BIT if part is FACE else BODY_BIT) or not masks[a].any():
        return None
    qstep, limit = _limits(part, quant)
    if compiled:
        from .compiled.kernels import first_overflow

        k, i, level = first_overflow(_kernel_rows(values, a, b), np.ascontiguousarray(qstep, dtype=np.int64),
                                     np.ascontiguousarray(masks[a]), limit, 0, b - a)
        return None if k < 0 else (a + int(k), int(i), int(level))
    recon = dequantise(quantise(values[a], qstep), qstep)
    for k in range(a + 1, b):
        level = quantise(values[k] - recon, qstep)
        bad = np.flatnonzero(masks[a] & (np.abs(level) > limit))
        if bad.size:
            return k, int(bad[0]), int(level[bad[0]])
        recon = recon + dequantise(level, qstep)
    return None


def _cannot_send(s: FapStream, part: PartSpec, quant: int, k: int, i: int, level: int, why: str) -> FbaError:
    """The error for a value no stream with these options can carry, saying which, why and what would."""
    qstep, limit = _limits(part, quant)
    values = s.fap_values if part is FACE else s.bap_values
    label, name = ("FAP", "fap_quant") if part is FACE else ("BAP", "bap_quant")
    step = int(qstep[i])
    if quant == 0:
        hint = f"{name} 0 sends values unquantised, so a level is the value itself; use {name} 1 or more"
    else:
        hint = f"ranges reach {limit} levels of step {step}; a coarser {name} or a shorter intra period"
    return FbaError(f"{label} {i + 1} = {int(values[k, i])}: {why} needs level {level}, beyond the "
                    f"largest range 31*60/{part.step_multiplier(quant) or 1} = {limit}", frame=k, hint=hint)


def _fit_intra_frames(s: FapStream, intra: Sequence[int], required: set[int], face_quant: int, body_quant: int,
                      compiled: bool) -> list[int]:
    """Intra frames where every level fits a 5-bit range code (SYNTAX.md 6-8), moving or adding them as needed.

    An intra frame the period asked for moves to the next frame that can carry its values; where a
    P change would need a level beyond every range code, an intra frame is added there. Frames that
    must be intra (the first, mask changes) and values no frame can carry are errors that say so.
    """
    parts = ((FACE, face_quant), (BODY, body_quant))
    frames = sorted(set(intra))
    out: list[int] = []
    i = 0
    while i < len(frames):
        k = frames[i]
        stop = frames[i + 1] if i + 1 < len(frames) else len(s)
        problem = next(((part, q, hit) for part, q in parts if (hit := _intra_overflow(s, part, q, k))), None)
        if problem is not None:
            part, q, (col, level) = problem
            if k in required:
                raise _cannot_send(s, part, q, k, col, level, "an intra value")
            if k + 1 < stop:
                frames[i] = k + 1  # try the next frame of the period
            else:
                del frames[i]      # the period before runs on
            if out:                # so check the period before again, now that it is longer
                out.pop()          # (out mirrors frames[:i])
                i -= 1
            continue
        hit = next(((part, q, found) for part, q in parts if (found := _p_overflow(s, part, q, k, stop, compiled))), None)
        out.append(k)
        if hit is not None:
            part, q, (j, col, level) = hit
            if _intra_overflow(s, part, q, j) is not None or any(_intra_overflow(s, p, qq, j) for p, qq in parts):
                raise _cannot_send(s, part, q, j, col, level, "the change from the previous frame")
            frames.insert(i + 1, j)
            required.add(j)
        i += 1
    return out


def _pick(option, carried, default):
    return option if option is not None else (carried if carried is not None else default)


def _fold_repeats(s: FapStream, protect: Sequence[int]) -> tuple[FapStream, list[int]]:
    """Drop frames equal to the frame before (except ``protect``ed ones), adding them to its skip count.

    Returns the folded stream and the indices of the frames it kept.
    """
    same = np.ones(len(s), dtype=bool)
    same[0] = False
    for name in CONTENT_FIELDS:
        eq = getattr(s, name)[1:] == getattr(s, name)[:-1]
        same[1:] &= eq.all(axis=tuple(range(1, eq.ndim))) if eq.ndim > 1 else eq
    same[list(protect)] = False
    keep: list[int] = []
    skip: list[int] = []
    for k in range(len(s)):
        if same[k]:
            skip[-1] += 1 + int(s.skip[k])
        else:
            keep.append(k)
            skip.append(int(s.skip[k]))
    out = s.take(keep)
    out.skip = np.array(skip, dtype=np.int32)
    return out, keep


def _grid_times(s: FapStream, fps: float) -> np.ndarray:
    slots = np.concatenate([[0], np.cumsum(s.skip[:-1].astype(np.int64) + 1)])
    return s.timestamps[0] + slots / fps


def _mask_types(mask: np.ndarray, part: PartSpec, requested, carried) -> tuple[int, ...]:
    """Per group: none or all where the mask says so, else the requested type, else the source's (hold by default)."""
    types = []
    for g, members in enumerate(part.mask_groups):
        sent = mask[list(members)]
        if requested is not None:
            t = int(requested[g])
            if (t == syntax.MASK_NONE and sent.any()) or (t == syntax.MASK_ALL and not sent.all()):
                raise FbaError(f"mask type {t} for FAP group {g + 1} does not match the FAPs present")
        elif not sent.any():
            t = syntax.MASK_NONE
        elif sent.all():
            t = syntax.MASK_ALL
        elif carried is not None and carried[g] in (syntax.MASK_HOLD, syntax.MASK_INTERPOLATE):
            t = carried[g]
        else:
            t = syntax.MASK_HOLD
        types.append(t)
    return tuple(types)


def _at_least(array: np.ndarray, dtype) -> np.ndarray:
    """``array`` contiguous and at least as wide as ``dtype``, the type the compiled kernels are used with: a
    decoded stream's arrays may be narrower (:data:`~mpeg4fa.fba.stream.STORAGE`), and numba would compile
    a version of each kernel per dtype; wider ones (hand-made int64) are kept, never cut."""
    return np.ascontiguousarray(array, dtype=np.promote_types(array.dtype, dtype))


def _kernel_rows(values: np.ndarray, a: int, b: int) -> np.ndarray:
    """Rows ``a..b-1`` of a value array for the compiled kernels (:func:`_at_least` int32): only the rows a
    call reads are copied."""
    return _at_least(values[a:b], np.int32)


def _period_levels(values: np.ndarray, qstep: np.ndarray, a: int, b: int, compiled: bool = False) -> np.ndarray:
    """(4, n): the intra level, its negation, and the largest P level up and down over frames a+1..b-1,
    each against the closed-loop reconstruction the decoder will have."""
    gop = np.zeros((4, values.shape[1]), dtype=np.int64)
    if compiled:
        from .compiled.kernels import closed_loop_extremes

        raw = np.zeros_like(gop)
        closed_loop_extremes(_kernel_rows(values, a, b), np.ascontiguousarray(qstep, dtype=np.int64), 0, b - a, raw)
        gop[0], gop[1], gop[2], gop[3] = raw[2], raw[3], raw[0], raw[1]
        return gop
    level = quantise(values[a], qstep)
    recon = dequantise(level, qstep)
    gop[0], gop[1] = level, -level
    for k in range(a + 1, b):
        level = quantise(values[k] - recon, qstep)
        recon = recon + dequantise(level, qstep)
        gop[2] = np.maximum(gop[2], level)
        gop[3] = np.maximum(gop[3], -level)
    return gop


def _range_codes(s: FapStream, part: PartSpec, quant: int, starts: Sequence[int], stops: Sequence[int],
                 compiled: bool = False) -> np.ndarray:
    """The smallest 5-bit range codes that cover every level coded in frames starts[i]..stops[i]."""
    values, masks = (s.fap_values, s.fap_mask) if part is FACE else (s.bap_values, s.bap_mask)
    step = part.step_multiplier(quant)
    qstep = part.quant_step * step
    scaler = step or 1
    extremes = np.zeros((4, part.n), dtype=np.int64)  # max I, -min I, max P, -min P (all >= 0)
    for a, b in zip(starts, stops):
        gop = _period_levels(values, qstep, int(a), int(b), compiled)
        extremes = np.maximum(extremes, gop * masks[a][None, :])  # only what this intra period sends
    codes = -(-extremes * scaler // RANGE_DELTA)         # first guess, then fix C rounding below
    codes = np.minimum(codes, 31)
    while True:
        short = (codes * RANGE_DELTA // scaler < extremes) & (codes < 31)
        if not short.any():
            break
        codes[short] += 1
    too_big = codes * RANGE_DELTA // scaler < extremes
    if too_big.any():
        k, i = (int(x[0]) for x in np.nonzero(too_big))
        label = "FAP" if part is FACE else "BAP"
        raise FbaError(f"{label} {i + 1}: level {int(extremes[k, i])} exceeds the largest range 31*60/{scaler}; "
                       f"use a coarser quantiser (a larger {'fap' if part is FACE else 'bap'}_quant)")
    return codes.astype(np.int16)


# ---- writing ------------------------------------------------------------------------------
NO_FACE_INTRA = "face data in a predicted frame before any face intra frame"
NO_BODY_INTRA = "body data in a predicted frame before any body intra frame"


class _Writer:
    def __init__(self, stream: FapStream, pads: set[int], compiled: bool = False) -> None:
        self.s = stream
        self.pads = pads
        self.w = BitWriter()
        self.io = syntax.Writing(self.w)
        self.faps, self.baps = ValueCoder(FACE), ValueCoder(BODY)
        self.viseme, self.expression = FieldCoder(1), FieldCoder(2)
        self.face: PartParams | None = None
        self.body: PartParams | None = None
        self.spans: list[tuple[int, int]] = []
        self.ends: list[tuple[int, SegmentEnd, bool]] = []  # (frame, end, last segment of the frame)
        self.compiled = _CompiledPlanes(self) if compiled else None

    def run(self) -> None:
        s, w = self.s, self.w
        w.start_code(s.object_start_code)
        intra = sorted(s.intra)
        k = 0
        while k < len(s):
            if self.compiled is not None and k not in s.intra:  # P frames up to the next intra frame
                stop = next((j for j in intra if j > k), len(s))
                self.compiled.write(k, stop)
                k = stop
                continue
            if s.start_code[k]:
                w.next_start_code()
                w.start_code(int(s.start_code[k]))
            start = w.pos
            try:
                self.plane(k)
            except FbaError as exc:
                exc.frame = k if exc.frame is None else exc.frame
                exc.bit_offset = w.pos if exc.bit_offset is None else exc.bit_offset
                raise
            self.spans.append((start, w.pos))
            if self.ends and self.ends[-1][0] == k:
                f, end, _ = self.ends[-1]
                self.ends[-1] = (f, end, True)
            if self.compiled is not None:
                self.compiled.after_intra(k)
            k += 1
        w.next_start_code()
        w.start_code(END_CODE)

    def segment(self, k: int, coder, values, intra: bool) -> None:
        symbols = coder.encode(values, intra, k)
        self.ends.append((k, encode_segment(self.w, symbols, coder.models(intra), not intra), False))

    def plane(self, k: int) -> None:
        s, io = self.s, self.io
        params = s.intra.get(k)
        intra = params is not None
        mask = int(s.object_mask[k])
        io.flag(intra, "is_intra")
        io.u(2, mask, "fba_object_mask")
        syntax.temporal_header(io, intra, params.frame_rate if intra else None,
                               params.time_code if intra else None, int(s.skip[k]), k in self.pads)
        if mask & FACE_BIT:
            if intra:
                if params.face is None:
                    raise FbaError("intra frame with face data has no face parameters")
                self.face = syntax.part_intra_header(io, params.face, FACE)
                self.faps.start_intra(self.face)
                self.viseme.start_intra(self.face.quant)
                self.expression.start_intra(self.face.quant)
            elif self.face is None:
                raise FbaError(NO_FACE_INTRA)
            for fap, coder, fields, raw_bits in ((0, self.viseme, s.viseme[k], ("viseme_def",)),
                                                 (1, self.expression, s.expression[k], ("init_face", "expression_def"))):
                if self.face.mask[fap]:
                    n = len(coder.fields)
                    self.segment(k, coder, fields[:n], intra)
                    for j, name in enumerate(raw_bits):
                        io.u(1, fields[n + j], name)
            self.segment(k, self.faps, s.fap_values[k], intra)
        if mask & BODY_BIT:
            if intra:
                if params.body is None:
                    raise FbaError("intra frame with body data has no body parameters")
                self.body = syntax.part_intra_header(io, params.body, BODY)
                self.baps.start_intra(self.body)
            elif self.body is None:
                raise FbaError(NO_BODY_INTRA)
            self.segment(k, self.baps, s.bap_values[k], intra)

    def hazards(self) -> list[tuple[int, str]]:
        """Places where a decoder would miss or misread a frame, as (frame, kind).

        ``hidden``: a frame inside one byte right before a start code, which the
        decoder's start-code look-ahead jumps over; ``emulation``: a frame whose
        first bits after a byte boundary read as a start code prefix; ``lookahead``:
        a segment whose trailing zeros run into the decoder's 14-bit look-ahead
        (``next`` when the look-ahead reaches the following frame or start code).
        """
        s, buf = self.s, self.w.buf
        found = []
        for k, (a, b) in enumerate(self.spans):
            followed_by_code = k == len(s) - 1 or s.start_code[k + 1] != 0
            if followed_by_code and a // 8 == b // 8:
                found.append((k, "hidden"))
            if not s.start_code[k] and _start_code_at(buf, a):
                found.append((k, "emulation"))
        for k, end, last in self.ends:
            if end.zeros >= 8 and lookahead_desyncs(buf, end):
                found.append((k, "lookahead-next" if last else "lookahead"))
        return found


class _CompiledPlanes:
    """The writer's P frames on the compiled path (:func:`mpeg4fa.fba.compiled.kernels.encode_planes`):
    the reference writes the intra frames and sets up the coders; their P models become Fenwick
    tables here, and runs of P frames are coded in one call, with the same bits, spans, segment ends
    and faults as :meth:`_Writer.plane` would give."""

    def __init__(self, writer: "_Writer") -> None:
        from .compiled import kernels, tables

        self.k, self.t, self.writer = kernels, tables, writer
        self.fprev = tables.share_face_predictions(writer.viseme, writer.expression, writer.faps)
        self.fbank, self.bbank = tables.Bank.empty(), tables.Bank.empty()
        s = writer.s
        self.pads = np.zeros(len(s), dtype=np.bool_)
        self.pads[[k for k in writer.pads if 0 <= k < len(s)]] = True
        self.res = np.zeros(kernels.RESULT_SIZE, dtype=np.int64)
        self.scratch = np.zeros(N_BAPS + 8, dtype=np.int64)
        # the kernel's types, whatever the stream holds (a decoded stream's arrays may be narrow: STORAGE)
        self.arrays = tuple(_at_least(a, d) for a, d in (
            (s.object_mask, np.uint8), (s.skip, np.int32), (s.start_code, np.uint32), (self.pads, np.bool_),
            (s.viseme, np.int32), (s.expression, np.int32), (s.fap_values, np.int32)))
        self.baps: np.ndarray | None = None  # the body's values, made contiguous when a body part is coded

    def after_intra(self, k: int) -> None:
        """Intra frame ``k`` was written: the models it set up, as tables."""
        w, params = self.writer, self.writer.s.intra[k]
        if params.face is not None and w.face is not None and self.writer.s.object_mask[k] & FACE_BIT:
            self.fbank = self.t.face_bank(w.viseme, w.expression, w.faps, w.face.mask)
        if params.body is not None and w.body is not None and self.writer.s.object_mask[k] & BODY_BIT:
            self.bbank = self.t.body_bank(w.baps)

    def write(self, first: int, stop: int) -> None:
        w, k, fb, bb = self.writer, self.k, self.fbank, self.bbank
        obj, skip, codes, pads, vis, exp, faps = self.arrays
        symbols = len(fb.meta) + len(bb.meta)
        capacity = int(((skip[first:stop].astype(np.int64).clip(0) // 15 + 1) * 4).sum()) + (stop - first) * (
            80 + 3 * 64 + k.SYMBOL_BITS * symbols)
        out = np.empty(capacity, dtype=np.uint8)
        spans = np.empty((stop - first, 2), dtype=np.int64)
        ends = np.empty(((stop - first) * 4, 4), dtype=np.int64)
        if self.baps is None and bb.meta.shape[0]:
            self.baps = np.ascontiguousarray(w.s.bap_values)
        baps = self.baps if self.baps is not None else np.zeros((1, 1), dtype=np.int32)
        face = w.face
        written, segments = k.encode_planes(
            out, w.w.pos, first, stop, obj, skip, codes, pads, vis, exp, faps, baps,
            fb.meta, fb.total, fb.freq, fb.tree, self.fprev, face is not None,
            bool(face is not None and face.mask[0]), bool(face is not None and face.mask[1]),
            bb.meta, bb.total, bb.freq, bb.tree, w.baps.prev, w.body is not None, spans, ends, self.res, self.scratch)
        w.w.buf.extend(out[:written].tobytes())
        res = self.res
        done = (int(res[k.ROWS]) if res[k.STATUS] == k.ERROR else stop) - first
        w.spans.extend(map(tuple, spans[:done].tolist()))
        w.ends.extend((f, SegmentEnd(pos, zeros), bool(last)) for f, pos, zeros, last in ends[:segments].tolist())
        if res[k.STATUS] == k.ERROR:
            raise self._fault()

    def _fault(self) -> FbaError:
        """The kernel's fault as the reference words it."""
        k, res, w = self.k, self.res, self.writer
        fault, a0, a1, a2 = (int(res[i]) for i in (k.FAULT, k.ARG0, k.ARG1, k.ARG2))
        if fault == k.RANGE_ERROR:  # res[CODE]: 0 a face model, 1 a body model
            row = (self.bbank if res[k.CODE] else self.fbank).meta[a0]
            coder, j = self.t.coder_of(row, w.viseme, w.expression, w.faps, w.baps)
            message = coder.range_message(j, a1, a2, intra=False)
        elif fault == k.NO_FACE_BEFORE:
            message = NO_FACE_INTRA
        elif fault == k.NO_BODY_BEFORE:
            message = NO_BODY_INTRA
        else:  # FIELD_TOO_WIDE
            message = syntax.does_not_fit(k.ENCODE_FIELD_NAMES[a0], a1, a2)
        return FbaError(message, int(res[k.POS]), int(res[k.ROWS]))


def _start_code_at(buf: bytearray, pos: int) -> bool:
    """Would a decoder peeking for a start code before the plane at ``pos`` find a prefix 0x000001?"""
    skips = ([0] if pos % 8 == 0 else []) + [8 - pos % 8]
    return any(pos + skip + 24 <= len(buf) and not any(buf[pos + skip: pos + skip + 23]) and buf[pos + skip + 23]
               for skip in skips)


def write(stream: FapStream, *, backend: str = "auto") -> bytes:
    """Encode a fully planned stream (every intra frame has its :class:`CodingParams`).

    A stream that some decoder would misread (see :meth:`_Writer.hazards`) is
    repaired and written again: a pad (skip_frames sent with a count of 0) moves a
    frame's bits, an extra intra frame changes them. Decoded values never change.
    """
    if 0 not in stream.intra:
        raise FbaError("the first frame must be an intra frame with coding parameters", frame=0)
    check_span(stream, stream.fps)
    from .compiled import use_compiled

    compiled = use_compiled(backend)
    pads: set[int] = set()
    for _ in range(MAX_REPAIRS):
        writer = _Writer(stream, pads, compiled)
        writer.run()
        found = writer.hazards()
        if not found:
            return writer.w.getvalue()
        extra_intra: set[int] = set()
        new_pads: set[int] = set()
        for k, kind in found:
            if kind == "lookahead-next" and k + 1 < len(stream) and k + 1 not in stream.intra:
                extra_intra.add(k + 1)
            elif kind in ("hidden", "lookahead-next") and k not in pads:
                new_pads.add(k)
            elif k not in stream.intra:
                extra_intra.add(k)
            else:
                raise FbaError(f"frame {k} cannot be placed so that every decoder reads it ({kind}); "
                               f"try another quantiser or intra period", frame=k)
        if extra_intra:
            # Intra frames are kept in the decoded stream, pads are not: decide the pads again from
            # scratch, as a re-encoding of the decoded stream will, so that it gives the same bytes.
            pads = set()
            stream = stream.copy()
            for k in sorted(extra_intra):
                stream.intra[k] = _repeat_params(stream, k, compiled)
        else:
            pads |= new_pads
    raise FbaError("could not place frames so that every decoder reads them; please report this stream")


def _repeat_params(s: FapStream, k: int, compiled: bool = False) -> CodingParams:
    """Parameters for an extra intra frame at k: those of the intra frame before it, with ranges
    recomputed for the frames it now governs (up to the next intra frame)."""
    prev = s.intra[max(j for j in s.intra if j < k)]
    stop = min([j for j in s.intra if j > k], default=len(s))
    parts = {}
    for name, part in (("face", FACE), ("body", BODY)):
        old = getattr(prev, name)
        if old is not None:
            codes = _range_codes(s, part, old.quant, [k], [stop], compiled)
            parts[name] = replace(old, mask=old.mask.copy(), ranges=RangeSet((True,) * 4, codes))
    return replace(prev, time_code=None, **parts)
