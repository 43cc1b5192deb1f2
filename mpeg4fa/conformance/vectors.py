"""The suite's vectors as small builders: what each stream sends and why, nothing about files.

A decode vector builds a :class:`FapStream` and either :class:`EncodeOptions` (planned by the
encoder) or intra headers of its own (for header features the planner never chooses: default
ranges, no frame rate, legacy start codes, a P plane with fewer parts). Every value sent is an exact
multiple of its quantiser step (``QUANT_STEP[i] * fap_quant``, blend/intensity ``fap_quant``, BAP
``BQP * bap_pred_scale``; any integer when the quantiser is 0), so quantisation is lossless and what
a decoder must output equals what was sent. A reject vector takes a valid stream and breaks one
field; its ``bit_offset`` is argued from the syntax in its description (``spec/SYNTAX.md``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator, Sequence

import numpy as np

from mpeg4fa.conformance.faces import FACES
from mpeg4fa.conformance.reference import DIRECTIONS
from mpeg4fa.fba import EncodeOptions, FapStream, FbaError, decode, plan, write
from mpeg4fa.fba.stream import (BODY, FACE, OBJECT_START_CODE_OLD, PLANE_START_CODE_OLD,
                                FrameRate, RangeSet, TimeCode)
from mpeg4fa.spec import (BAP_PRED_SCALE, BAP_QUANT_STEP, FAP_GROUP_SLICES, FAP_PARTNERS, FAPS,
                          FULL_INTENSITY, N_FAP_GROUPS, N_FAPS, QUANT_STEP)


def semantic_face(fap: int) -> str:
    """The face FAP ``fap``'s semantics vector uses: the faces in turn, among those that have every
    point the FAP moves (a subset face would leave the FAP's motion unchecked)."""
    points = FAPS[fap - 1].feature_point
    usable = [f.name for f in FACES if f.labels is None or all(p in f.labels for p in points)]
    return usable[(fap - 3) % len(usable)]


@dataclass
class Built:
    """A decode vector's planned stream (what was sent) and its bytes."""

    stream: FapStream
    data: bytes


@dataclass
class Broken:
    """A reject vector's bytes and where a decoder must see the fault."""

    data: bytes
    bit_offset: int
    frames_before: int


@dataclass(frozen=True)
class VectorDef:
    id: str
    group: str
    confidence: str
    description: str
    build: Callable[[], "Built | Broken"]
    rules: tuple[str, ...] = ()
    face: str | None = None

    @property
    def expect(self) -> str:
        return "reject" if self.group == "reject" else "decode"


# ---- stream building ------------------------------------------------------------------------
def step(fap: int, quant: int) -> int:
    """The coded step of FAP ``fap`` (1-based) at ``quant``; 1 when unquantised (any integer is exact)."""
    return int(QUANT_STEP[fap - 1]) * quant if quant else 1


def levels(fap: int, quant: int, n: int) -> int:
    """``n`` quantiser levels of FAP ``fap`` as a FAPU value: lossless by construction."""
    return n * step(fap, quant)


def face_stream(n: int, values: dict[int, Sequence[int]] | None = None, viseme=None, expression=None) -> FapStream:
    """``n`` face frames sending the given FAPs (1-based: per-frame values) and FAP 1/2 fields."""
    s = FapStream.empty(n)
    for fap, vals in (values or {}).items():
        s.fap_mask[:, fap - 1] = True
        s.fap_values[:, fap - 1] = np.asarray(vals, dtype=np.int32)
    if viseme is not None:
        s.fap_mask[:, 0] = True
        s.viseme[:] = np.asarray(viseme, dtype=np.int32)
    if expression is not None:
        s.fap_mask[:, 1] = True
        s.expression[:] = np.asarray(expression, dtype=np.int32)
    return s


def encoded(s: FapStream, options: EncodeOptions | None = None,
            tweak: Callable[[FapStream], None] | None = None) -> Built:
    """Plan ``s`` (fps 25 unless the options say), let ``tweak`` edit the plan, write it."""
    planned = plan(s, options or EncodeOptions(fps=25))
    if tweak is not None:
        tweak(planned)
    return Built(planned, write(planned))


def _wave(n: int, amplitude: int, phase: int = 0) -> list[int]:
    """A small deterministic waveform of multiples of ``amplitude`` (-2..2 times)."""
    shape = (0, 1, 2, 1, 0, -1, -2, -1)
    return [amplitude * shape[(k + phase) % 8] for k in range(n)]


def _low_level(n: int, faps: Sequence[int], quant: int = 1, scale: int = 3) -> dict[int, list[int]]:
    """A wave per FAP; never negative on the five unidirectional FAPs (a value no face can show)."""
    out = {}
    for f in faps:
        wave = _wave(n, levels(f, quant, scale), phase=f)
        out[f] = [abs(x) for x in wave] if FAPS[f - 1].unidirectional else wave
    return out


def _closed_subset(faps: Sequence[int]) -> list[int]:
    """About half of ``faps``, closed under left/right and inner/outer partners inside ``faps``, so an
    unsent FAP never has a sent counterpart: hold and interpolate then show the same."""
    chosen = set(faps[::2])
    changed = True
    while changed:
        changed = False
        for f in list(chosen):
            for p in FAP_PARTNERS[f - 1]:
                if p >= 0 and p + 1 in faps and p + 1 not in chosen:
                    chosen.add(p + 1)
                    changed = True
    return sorted(chosen)


def _group_faps(g: int) -> list[int]:
    a, b = FAP_GROUP_SLICES[g]
    return list(range(a + 1, b + 1))


# ---- syntax -----------------------------------------------------------------------------------
HIGH_LEVEL_NOTE = ("; the sent fields are [V]/[S] syntax, but what FAP 1/2 show comes from this project's "
                   "viseme/expression profiles [M], so the vector is informative")
BASIC = (3, 4, 5, 19, 31, 48, 51)
"""A few FAPs from several groups (jaw, lips, eyelid, brow, head, outer lip)."""


def _basic(n: int, quant: int = 1) -> FapStream:
    return face_stream(n, _low_level(n, BASIC, quant))


def _syntax() -> Iterator[VectorDef]:
    yield VectorDef("syntax/intra-only", "syntax", "V", "one intra plane, 7 FAPs in 5 groups (per-FAP masks)",
                    lambda: encoded(_basic(1)), ("SYNTAX.md 3, 5, 6, 10",))
    yield VectorDef("syntax/intra-p", "syntax", "V", "an intra plane then 11 P planes (closed-loop prediction)",
                    lambda: encoded(_basic(12)), ("SYNTAX.md 8, 10",))
    for q in (0, 1, 2, 5, 8, 16, 31):
        def build(q=q) -> Built:
            n = 10
            s = face_stream(n, _low_level(n, BASIC, q, scale=2 if q == 31 else 3))
            if q == 0:
                s.fap_values[:, [2, 3]] += np.array([7, -13], dtype=np.int32)  # odd values: no step at all
            return encoded(s, EncodeOptions(fps=25, fap_quant=q))
        yield VectorDef(f"syntax/quant-{q:02d}", "syntax", "V" if q == 1 else "S",
                        f"fap_quant {q}: FAP 3-68 steps QUANT_STEP x {q}"
                        + (" (0: values sent unquantised, odd values)" if q == 0 else "")
                        + "; values are exact multiples of the step, so nothing is lost",
                        build, ("SYNTAX.md 5 fap_quant", "SYNTAX.md 8"))
    yield from _mask_vectors()
    yield from _range_vectors()
    yield from _temporal_vectors()
    yield from _high_level_vectors()
    yield from _body_vectors()
    yield from _start_code_vectors()


def _mask_vectors() -> Iterator[VectorDef]:
    for g in range(N_FAP_GROUPS):
        faps = _group_faps(g)
        for t in (1, 2, 3):
            def build(g=g, t=t, faps=faps) -> Built:
                n = 6
                sent = faps if t == 3 else _closed_subset(faps)
                low = [f for f in sent if f > 2]
                s = face_stream(n, _low_level(n, low),
                                viseme=[[1 + k, 14 - k, 20 + k, 0] for k in range(n)] if 1 in sent else None,
                                expression=[[1 + k % 6, 30 + k, 6 - k % 6, 10, 0, 0] for k in range(n)] if 2 in sent else None)
                types = [0] * N_FAP_GROUPS
                types[g] = t
                return encoded(s, EncodeOptions(fps=25, mask_types=types))
            conf = "S" if t == 3 else "V"
            group = "syntax"
            if g == 0:  # FAP 1/2 are shown through the project's profiles: informative (see HIGH_LEVEL_NOTE)
                conf, group = "M", "informative"
            yield VectorDef(f"{group}/mask-g{g + 1:02d}-t{t}", group, conf,
                            f"FAP group {g + 1} alone with mask type {t}"
                            + (" (all its FAPs)" if t == 3 else
                               " (per-FAP mask; the unsent FAPs have no sent counterpart, so hold and interpolate agree)")
                            + "; the other 9 groups type 0" + (HIGH_LEVEL_NOTE if g == 0 else ""), build, ("SYNTAX.md 5 fap_mask_type",))

    def mixed() -> Built:
        n = 6
        types = [0] + [3 if g % 3 == 0 else (1 if g % 3 == 1 else 2) for g in range(1, N_FAP_GROUPS)]
        keep = [f for g in range(1, N_FAP_GROUPS) if types[g] for f in
                (_group_faps(g) if types[g] == 3 else _closed_subset(_group_faps(g)))]
        return encoded(face_stream(n, _low_level(n, keep)), EncodeOptions(fps=25, mask_types=types))
    yield VectorDef("syntax/mask-mixed", "syntax", "S", "mask types 0, 3, 1 and 2 on different groups of one header",
                    mixed, ("SYNTAX.md 5 fap_mask_type",))

    def all66() -> Built:
        n = 8
        return encoded(face_stream(n, _low_level(n, range(3, 69), scale=2)))
    yield VectorDef("syntax/all-faps", "syntax", "S", "all 66 low-level FAPs every frame (groups 2-10 type 3)",
                    all66, ("SYNTAX.md 5", "SYNTAX.md 10"))


def _no_ranges(s: FapStream) -> None:
    for k, p in s.intra.items():
        if p.face is not None:
            p.face.ranges = RangeSet.none(len(p.face.mask))


_BEYOND_A_FACE = (47, 48, 49, 50)
"""FAPs whose largest level (1860 steps: 512 or 170 AU each) is more than half a turn: a decoder may clamp them."""


def _range_vectors() -> Iterator[VectorDef]:
    def defaults() -> Built:
        n = 8
        return encoded(_basic(n), tweak=_no_ranges)
    yield VectorDef("syntax/ranges-default", "syntax", "S",
                    "no new_minmax set sent: the faps.csv default ranges (rounded up to 60, // fap_quant) apply",
                    defaults, ("SYNTAX.md 6", "SYNTAX.md 7 default ranges"))

    def partial() -> Built:
        def tweak(s: FapStream) -> None:
            r = s.intra[0].face.ranges
            r.flags = (True, False, False, True)  # I max and P min sent; I min and P max keep the defaults
        return encoded(_basic(8), tweak=tweak)
    yield VectorDef("syntax/ranges-partial", "syntax", "S",
                    "only the I-max and P-min sets sent (smallest codes that fit); I min and P max are the defaults",
                    partial, ("SYNTAX.md 6", "SYNTAX.md 7"))

    def explicit() -> Built:
        def tweak(s: FapStream) -> None:
            s.intra[0].face.ranges.codes[:] = np.where(s.intra[0].face.mask, 31, 0)
        return encoded(_basic(8), tweak=tweak)
    yield VectorDef("syntax/ranges-31", "syntax", "V", "all four sets with code 31 for every masked FAP (+-1860 levels), as real streams send",
                    explicit, ("SYNTAX.md 6",))

    def carry() -> Built:
        def tweak(s: FapStream) -> None:
            for k in sorted(s.intra)[1:]:
                s.intra[k].face.ranges = RangeSet.none(N_FAPS)
        return encoded(_basic(12), EncodeOptions(fps=25, intra_period=4), tweak)
    yield VectorDef("syntax/ranges-carry", "syntax", "S",
                    "three intra planes; only the first sends ranges, the later ones keep them (defaults applied once)",
                    carry, ("SYNTAX.md 7 range state",))

    def fit() -> Built:
        return encoded(_basic(12), EncodeOptions(fps=25, intra_period=4, optimize=True))
    yield VectorDef("syntax/ranges-per-period", "syntax", "S",
                    "optimize: tight ranges chosen per intra period (codes differ from one intra to the next)",
                    fit, ("SYNTAX.md 6", "SYNTAX.md 12"))

    def halving() -> Built:
        # P model of FAP 3 with range code 31: 3721 symbols; its total reaches 16383 after 12662 P
        # symbols. Quiet frames (difference 0) cost a few bits each; a change every 97 frames.
        n = 12700
        vals = np.zeros(n, dtype=np.int32)
        vals[::97] = levels(3, 1, 5)
        vals[1::97] = levels(3, 1, 5)
        vals[-20:] = [levels(3, 1, 5 + k % 5) for k in range(20)]
        s = face_stream(n, {3: vals})
        return encoded(s, tweak=lambda p: p.intra[0].face.ranges.codes.__setitem__(slice(None), 31))
    yield VectorDef("syntax/adaptation-halving", "syntax", "S",
                    "12,700 frames of FAP 3 (P model of 3721 symbols, code 31): its total reaches MAX_FREQUENCY 16383 "
                    "at frame 12663 and every count is halved before the increment; values keep decoding after it",
                    halving, ("SYNTAX.md 9 adaptation",))

    def stuffing() -> Built:
        # Every low-level FAP at its I maximum: the last symbol of each model takes the bottom of the
        # interval and codes as zeros, long runs that need the coder's stuffing '1' after 22 zeros.
        n = 2
        shown_ok = [f for f in range(3, 69) if f not in _BEYOND_A_FACE]
        s = face_stream(n, {f: [levels(f, 1, 1860)] * n for f in shown_ok})
        return encoded(s, tweak=lambda p: p.intra[0].face.ranges.codes.__setitem__(slice(None), 31))
    yield VectorDef("syntax/arith-stuffing", "syntax", "V",
                    "62 low-level FAPs at their I maximum (+1860 levels, code 31; not FAPs 47-50, where 1860 steps "
                    "exceed half a turn): the segment holds zero runs with stuffing '1's after 22 zeros",
                    stuffing, ("SYNTAX.md 9 get_bit stuffing",))


RATE_FRAMES = 100
"""Frames of each frame-rate vector: enough that leaving out the 1000/1001 factor puts the last frame
3 ms off (at 30000/1001 fps), six times the timestamp tolerance."""


def _temporal_vectors() -> Iterator[VectorDef]:
    for fps, conf in ((25, "V"), (30, "V"), (30000 / 1001, "S"), (12.5, "S"), (24000 / 1001, "S")):
        name = {25: "25", 30: "30", 12.5: "12.5"}.get(fps, f"{fps:.3f}")
        yield VectorDef(f"syntax/fps-{name}", "syntax", conf,
                        f"frame rate {name} (frame_rate {FrameRate.from_fps(fps).frame_rate}, seconds "
                        f"{FrameRate.from_fps(fps).seconds}, frequency_offset {FrameRate.from_fps(fps).frequency_offset})"
                        + ("; fps = (frame_rate + seconds/16) x 1000/1001 in real arithmetic, not 0 and not left out "
                           f"({RATE_FRAMES} frames: the last is {(RATE_FRAMES - 1) / fps:.4f} s, "
                           f"{(RATE_FRAMES - 1) / fps - (RATE_FRAMES - 1) / round(fps):.4f} s later than without the factor)"
                           if FrameRate.from_fps(fps).frequency_offset else f" ({RATE_FRAMES} frames)"),
                        lambda fps=fps: encoded(_basic(RATE_FRAMES), EncodeOptions(fps=fps)), ("SYNTAX.md 3 fps", "SYNTAX.md 4"))

    def no_rate() -> Built:
        def tweak(s: FapStream) -> None:
            s.intra[0].frame_rate = None
        return encoded(_basic(6), tweak=tweak)
    yield VectorDef("syntax/fps-absent", "syntax", "S", "no frame rate sent: 30 fps is assumed", no_rate,
                    ("SYNTAX.md 3 DEFAULT_FPS",))

    def skips() -> Built:
        s = _basic(8)
        s.skip[:] = [0, 1, 14, 15, 30, 2, 0, 0]
        return encoded(s)
    yield VectorDef("syntax/skip-frames", "syntax", "S",
                    "skip counts 1, 14, 15 (chunks 15 + 0), 30 (15 + 15 + 0), 2: frame k's count delays frame k+1",
                    skips, ("SYNTAX.md 3 skip_frames", "SYNTAX.md 4"))

    def repeats() -> Built:
        s = _basic(20)
        s.fap_values[5:12] = s.fap_values[5]
        return encoded(s, EncodeOptions(fps=25, skip_repeats=True))
    yield VectorDef("syntax/skip-repeats", "syntax", "S", "repeated frames folded into a skip count of 6",
                    repeats, ("SYNTAX.md 3 skip_frames", "SYNTAX.md 12"))

    def codes() -> Built:
        s = _basic(60)
        s.timestamps[:] = np.arange(60) / 25  # the encoder writes a time code on the intras at whole seconds
        return encoded(s, EncodeOptions(fps=25, intra_period=25, time_codes=True))
    yield VectorDef("syntax/time-codes", "syntax", "S", "intra planes at 0, 1 and 2 s each send a time code (hh:mm:ss)",
                    codes, ("SYNTAX.md 3 time code", "SYNTAX.md 4"))

    def late() -> Built:
        def tweak(s: FapStream) -> None:
            s.intra[0].time_code = TimeCode(1, 2, 3)
        return encoded(_basic(10), tweak=tweak)
    yield VectorDef("syntax/time-code-start", "syntax", "S",
                    "the first plane's time code 01:02:03 anchors the stream at 3723 s; the P planes follow at 1/25 s",
                    late, ("SYNTAX.md 4",))

    def intras() -> Built:
        return encoded(_basic(16), EncodeOptions(fps=25, intra_period=4))
    yield VectorDef("syntax/intra-period", "syntax", "S", "an intra plane every 4 frames (16 frames, 4 intra)",
                    intras, ("SYNTAX.md 7", "SYNTAX.md 10"))

    def mask_change() -> Built:
        s = _basic(12)
        s.fap_mask[6:, [2, 3]] = False
        s.fap_values[5:, [2, 3]] = 0  # last sent as 0: hold and "unsent shows 0" agree
        s.fap_mask[6:, 40] = True
        s.fap_values[6:, 40] = levels(41, 1, 10)
        return encoded(s)
    yield VectorDef("syntax/mask-change", "syntax", "S",
                    "the mask changes at frame 6 (FAP 3, 4 leave after sending 0, FAP 41 comes): a new intra plane there",
                    mask_change, ("SYNTAX.md 12",))


def _high_level_vectors() -> Iterator[VectorDef]:
    def visemes() -> Built:
        n = 16
        return encoded(face_stream(n, viseme=[[k % 15, (k + 7) % 15, (4 * k) % 64, 0] for k in range(n)]))
    yield VectorDef("informative/syntax-fap1-only", "informative", "M", "FAP 1 alone (as the en/* streams): selects 0..14, blends 0..60" + HIGH_LEVEL_NOTE,
                    visemes, ("SYNTAX.md 10",))

    def viseme_def() -> Built:
        n = 6
        return encoded(face_stream(n, _low_level(n, (4, 5)), viseme=[[k + 1, k + 2, FULL_INTENSITY - k, k % 2] for k in range(n)]))
    yield VectorDef("informative/syntax-fap1-viseme-def", "informative", "M", "FAP 1 with viseme_def 1 on odd frames, beside FAPs 4 and 5" + HIGH_LEVEL_NOTE,
                    viseme_def, ("SYNTAX.md 10 viseme_def",))

    def expressions() -> Built:
        n = 8
        return encoded(face_stream(n, expression=[[1 + k % 6, 9 * k % 64, (k + 3) % 7, FULL_INTENSITY - 5 * k, 0, 0] for k in range(n)]))
    yield VectorDef("informative/syntax-fap2-only", "informative", "M", "FAP 2 alone, nonzero selects and intensities" + HIGH_LEVEL_NOTE,
                    expressions, ("SYNTAX.md 10 expression order",))

    def flags() -> Built:
        n = 6
        return encoded(face_stream(n, expression=[[1, 40, 2, 20, k % 2, (k // 2) % 2] for k in range(n)]))
    yield VectorDef("informative/syntax-fap2-init-face-def", "informative", "M",
                    "FAP 2 with init_face and expression_def taking every combination of 0 and 1" + HIGH_LEVEL_NOTE,
                    flags, ("SYNTAX.md 10 init_face, expression_def",))

    def both() -> Built:
        n = 10
        return encoded(face_stream(n, _low_level(n, BASIC), viseme=[[k % 15, 14 - k, 6 * k, 0] for k in range(n)],
                                   expression=[[k % 7, 60 - 6 * k, 6 - k % 7, 6 * k, 1, 0] for k in range(n)]))
    yield VectorDef("informative/syntax-fap1-fap2-low", "informative", "M", "FAP 1, FAP 2 and low-level FAPs in every plane (as headmotion_long)" + HIGH_LEVEL_NOTE,
                    both, ("SYNTAX.md 10",))

    def quant_fields() -> Built:
        n = 6
        q = 5
        return encoded(face_stream(n, viseme=[[2, 9, q * k, 0] for k in range(n)],
                                   expression=[[3, q * (12 - k), 5, q * 2 * k, 0, 1] for k in range(n)]),
                       EncodeOptions(fps=25, fap_quant=q))
    yield VectorDef("informative/syntax-fap12-quant-05", "informative", "M",
                    "FAP 1/2 blend and intensities quantised with fap_quant 5: ranges (63 + 2) // 5 = 13 levels" + HIGH_LEVEL_NOTE,
                    quant_fields, ("SYNTAX.md 7 blend range",))


def _bap_step(bap: int, quant: int) -> int:
    return int(BAP_QUANT_STEP[bap - 1]) * int(BAP_PRED_SCALE[quant]) if quant else 1


def _body(s: FapStream, baps: Sequence[int], quant: int = 1) -> None:
    n = len(s)
    s.bap_mask = np.zeros((n, s.bap_mask.shape[1]), dtype=bool)
    s.bap_values = np.zeros((n, s.bap_mask.shape[1]), dtype=np.int32)
    for b in baps:
        s.bap_mask[:, b - 1] = True
        s.bap_values[:, b - 1] = _wave(n, 4 * _bap_step(b, quant), phase=b)


def _body_vectors() -> Iterator[VectorDef]:
    def face_body() -> Built:
        s = _basic(8)
        s.object_mask[:] = FACE | BODY
        _body(s, (1, 2, 3, 50, 51))
        return encoded(s)
    yield VectorDef("syntax/face-body", "syntax", "V", "fba_object_mask 3: face data then body data (5 BAPs, per-BAP mask)",
                    face_body, ("SYNTAX.md 3", "SYNTAX.md 11"))

    def body_only() -> Built:
        s = FapStream.empty(8, object_mask=BODY)
        _body(s, range(1, 20))
        return encoded(s, EncodeOptions(fps=30))
    yield VectorDef("syntax/body-only", "syntax", "V", "fba_object_mask 2: body only (BAPs 1-19), 30 fps from the body's temporal header",
                    body_only, ("SYNTAX.md 3", "SYNTAX.md 11"))

    def body_quant() -> Built:
        s = FapStream.empty(6, object_mask=BODY)
        _body(s, (1, 4, 9), quant=3)
        return encoded(s, EncodeOptions(fps=30, bap_quant=3))
    yield VectorDef("syntax/body-quant-03", "syntax", "S", "bap_quant 3: BAP steps BQP x bap_pred_scale[3]",
                    body_quant, ("SYNTAX.md 8 qstep[b]",))

    def fewer_parts() -> Built:
        s = _basic(6)
        s.object_mask[:] = FACE | BODY
        _body(s, (1, 2))
        s.object_mask[3:] = FACE
        s.bap_mask[3:] = False
        s.bap_values[3:] = 0
        planned = plan(s, EncodeOptions(fps=25))
        first = planned.intra[0]
        planned.intra = {0: first}  # no new intra where the body leaves: P planes with the face only
        return Built(planned, write(planned))
    yield VectorDef("syntax/p-fewer-parts", "syntax", "S",
                    "face+body intra, then P planes with fewer parts (face only) and no new intra",
                    fewer_parts, ("SYNTAX.md 3 P plane parts",))


def _start_code_vectors() -> Iterator[VectorDef]:
    def old_object() -> Built:
        s = _basic(6)
        planned = plan(s, EncodeOptions(fps=25))
        planned.object_start_code = OBJECT_START_CODE_OLD
        return Built(planned, write(planned))
    yield VectorDef("syntax/start-code-101", "syntax", "S", "legacy object start code 0x00000101 instead of 0x000001BA",
                    old_object, ("SYNTAX.md 2",))

    def old_plane() -> Built:
        planned = plan(_basic(6), EncodeOptions(fps=25))
        planned.start_code[0] = PLANE_START_CODE_OLD
        return Built(planned, write(planned))
    yield VectorDef("syntax/start-code-103", "syntax", "V", "legacy plane start code 0x00000103 (after 0x7F stuffing) before plane 0",
                    old_plane, ("SYNTAX.md 2",))

    def plane_codes() -> Built:
        return encoded(_basic(12), EncodeOptions(fps=25, intra_period=4, start_codes=True))
    yield VectorDef("syntax/start-code-1bb", "syntax", "S",
                    "plane start code 0x000001BB, after next_start_code() stuffing, before every intra plane",
                    plane_codes, ("SYNTAX.md 2 next_start_code",))

    def aligned() -> Built:
        # The first _basic(n) whose last plane ends on a byte boundary: the writer puts a whole 0x7F
        # byte before the end code; this vector leaves it out, so the end code follows at once.
        for n in range(2, 64):
            built = encoded(_basic(n))
            end = _plane_starts(built.data)[-1]
            if end % 8 == 0:
                return Built(built.stream, built.data[: end // 8] + built.data[-4:])
        raise AssertionError("no stream of 2..63 frames ends aligned")
    yield VectorDef("syntax/aligned-end-code", "syntax", "S",
                    "the last plane ends on a byte boundary and the end code follows with no stuffing byte "
                    "(the writer would send 0x7F): a decoder must also look for the code at the current position",
                    aligned, ("SYNTAX.md 2 look-ahead",))

    def hidden() -> Built:
        # FAP 3 at 0 in three frames: the last P plane is a few bits inside one byte before the end
        # code, and its first bits after the boundary would read as a start-code prefix. write() finds
        # both hazards and sends frame 2 as an intra plane (found by searching small streams).
        n = 3
        return encoded(face_stream(n, {3: [0] * n}))
    yield VectorDef("syntax/repair-hidden-frame", "syntax", "S",
                    "a last P plane that would hide inside the stuffing before the end code (and open with a "
                    "start-code prefix): the encoder repairs it by sending frame 2 as an intra plane; a decoder "
                    "must still see 3 frames",
                    hidden, ("SYNTAX.md 12 hidden short frame", "SYNTAX.md 2 look-ahead"))

    def lookahead() -> Built:
        # Found by searching small streams: frame 1's last segment ends in zeros that run into the
        # decoder's 14 look-ahead bits; write() makes frames 1 and 2 intra planes.
        s = face_stream(6, {24: [896, 896, 0, 896, -896, 896], 38: [0, 0, -7, -7, -7, 7], 58: [14, -14, 14, 0, 0, 0]})
        return encoded(s)
    yield VectorDef("syntax/repair-lookahead", "syntax", "S",
                    "a segment whose trailing zeros would run into the decoder's 14-bit look-ahead (and a start-code "
                    "prefix at a plane start): the encoder repairs it with forced intra planes at frames 1 and 2 "
                    "that repeat the first header's parameters",
                    lookahead, ("SYNTAX.md 9 zero run", "SYNTAX.md 12 zero run into the look-ahead"))


# ---- semantics --------------------------------------------------------------------------------
def semantic_value(fap: int) -> int:
    """A clearly visible value of ``fap`` at fap_quant 1: 200 FAPU, or about 0.15 rad for an angle."""
    qp = step(fap, 1)
    target = 15000 if FAPS[fap - 1].fapu == "AU" else 200
    return max(1, round(target / qp)) * qp


def _semantic_stream(fap: int) -> FapStream:
    v = semantic_value(fap)
    half = (v // step(fap, 1) // 2) * step(fap, 1)
    if FAPS[fap - 1].unidirectional:
        vals = [v, v, half, v, 0, half]
    else:
        vals = [v, v, -v, -v, 0, half]
    return face_stream(len(vals), {fap: vals})


def _motion(fap: int) -> str:
    """What FAP ``fap`` does to the face's points, as the reference model checks it (its rules 15-20)."""
    f = FAPS[fap - 1]
    points = ", ".join(f.feature_point) or "no point"
    if f.fapu == "AU" and f.name.startswith("head_"):
        return f"turns the head, every point, about 7.1 ({f.direction}: right-handed about its axis)"
    if f.fapu == "AU":
        return f"rotates {points} ({f.direction}); no source gives the centre, so no point is checked"
    if f.direction not in DIRECTIONS:
        return f"{f.direction} at {points}; no point moves"
    return f"moves {points} {f.direction} by value x {f.fapu}"


def _semantics() -> Iterator[VectorDef]:
    for fap in range(3, 69):
        f = FAPS[fap - 1]
        face = semantic_face(fap)
        v = semantic_value(fap)
        sign = "+v only (unidirectional)" if f.unidirectional else "+v and -v"
        yield VectorDef(
            f"semantics/fap-{fap:02d}", "semantics", "S",
            f"FAP {fap} {f.name} alone, v = {v} {f.fapu} ({sign}), frames v, v, {'v/2' if f.unidirectional else '-v'}, "
            f"{'v' if f.unidirectional else '-v'}, 0, v/2 with intra planes at 0 and 3; {_motion(fap)} on face '{face}'",
            lambda fap=fap: encoded(_semantic_stream(fap), EncodeOptions(fps=25, intra_period=3)),
            ("facts 1 FAPU", "facts 2 direction", "SYNTAX.md 8"), face)
    yield from _high_level_semantics()
    yield from _unsent_semantics()


def _high_level_semantics() -> Iterator[VectorDef]:
    def visemes() -> Built:
        n = 15
        return encoded(face_stream(n, viseme=[[k, 0, FULL_INTENSITY, 0] for k in range(n)]))
    yield VectorDef("informative/visemes", "informative", "M",
                    "FAP 1: each viseme 0..14 at full blend (63) in turn; shown through this project's viseme profiles "
                    "(spec/viseme_faps.csv: the standard does not say which FAPs a viseme moves)",
                    visemes, ("facts 4.1", "spec/README.md profiles"), "adult")

    def blended() -> Built:
        n = 8
        return encoded(face_stream(n, viseme=[[10, 1, 9 * k, 0] for k in range(n)]))
    yield VectorDef("informative/viseme-blend", "informative", "M",
                    "FAP 1: AA (10) blended with PP (1), blend 0..63: shown = v1 x b/63 + v2 x (1 - b/63)",
                    blended, ("facts 4.1 blend [S]", "spec/README.md profiles"), "child")

    def expressions() -> Built:
        n = 7
        return encoded(face_stream(n, expression=[[k, FULL_INTENSITY, 0, 0, 0, 0] for k in range(n)]))
    yield VectorDef("informative/expressions", "informative", "M",
                    "FAP 2: each expression 0..6 at intensity 63 in turn, through this project's expression profiles",
                    expressions, ("facts 4.2", "spec/README.md profiles"), "long")

    def expression_blend() -> Built:
        n = 6
        return encoded(face_stream(n, expression=[[1, 10 * k, 6, 60 - 10 * k, 0, 0] for k in range(n)]))
    yield VectorDef("informative/expression-blend", "informative", "M",
                    "FAP 2: joy and surprise at independent intensities: shown = e1 x i1/63 + e2 x i2/63",
                    expression_blend, ("facts 4.2", "spec/README.md profiles"), "adult")

    def mixed() -> Built:
        n = 6
        return encoded(face_stream(n, {3: [levels(3, 1, 40)] * n, 31: [levels(31, 1, 30)] * n},
                                   viseme=[[4, 10, 30, 0]] * n, expression=[[2, 40, 0, 0, 0, 0]] * n))
    yield VectorDef("informative/high-low-mix", "informative", "M",
                    "FAP 1 and FAP 2 with FAP 3 and 31 sent: a sent low-level FAP overrides its high-level value",
                    mixed, ("spec/README.md profiles",), "subset")


def _unsent_semantics() -> Iterator[VectorDef]:
    def hold() -> Built:
        n = 8
        s = face_stream(n, {4: [levels(4, 1, 50)] * n, 5: [levels(5, 1, 40)] * n, 19: [levels(19, 1, 100)] * n})
        s.fap_mask[4:, 3] = False  # FAP 4 stops being sent at frame 4 (a new intra there)
        s.fap_values[4:, 3] = 0
        s.fap_mask[2:6, 18] = False  # FAP 19 unsent in frames 2..5
        s.fap_values[2:6, 18] = 0
        return encoded(s, EncodeOptions(fps=25, mask_types=[0, 1, 1, 0, 0, 0, 0, 0, 0, 0]))
    yield VectorDef("informative/unsent-hold", "informative", "M",
                    "mask type 1: FAP 4 and FAP 19 stop being sent; each holds its last sent value",
                    hold, ("facts 5.3 mask type 1 [M]",), "adult")

    def never() -> Built:
        n = 4
        return encoded(face_stream(n, {3: [levels(3, 1, 30)] * n}), EncodeOptions(fps=25, mask_types=[0, 1] + [0] * 8))
    yield VectorDef("semantics/unsent-never", "semantics", "S",
                    "FAPs never sent (group type 0, or left out of a type-1 group) show 0: the neutral face",
                    never, ("facts 1 neutral face",), "child")

    def lr() -> Built:
        n = 6
        s = face_stream(n, {31: _wave(n, levels(31, 1, 40)), 33: [levels(33, 1, 60)] * n, 19: [levels(19, 1, 200)] * n})
        return encoded(s, EncodeOptions(fps=25, mask_types=[0, 0, 2, 2, 0, 0, 0, 0, 0, 0]))
    yield VectorDef("informative/interpolate-left-right", "informative", "M",
                    "mask type 2: left FAPs 19, 31, 33 sent, their right partners 20, 32, 34 not: they copy the left values",
                    lr, ("facts 5.3 mask type 2 [M]", "facts 2 interpolation [S]"), "long")

    def io() -> Built:
        n = 6
        s = face_stream(n, {3: [levels(3, 1, 30)] * n, **_low_level(n, range(51, 61), scale=20)})
        return encoded(s, EncodeOptions(fps=25, mask_types=[0, 2, 0, 0, 0, 0, 0, 3, 0, 0]))
    yield VectorDef("informative/interpolate-inner-outer", "informative", "M",
                    "mask type 2 on group 2: outer lip FAPs 51-60 sent, inner 4-13 not: they copy the outer values",
                    io, ("facts 5.3 mask type 2 [M]", "facts 2 interpolation [S]"), "adult")

    def lr_hold() -> Built:
        n = 6
        s = face_stream(n, {31: _wave(n, levels(31, 1, 40)), 33: [levels(33, 1, 60)] * n})
        return encoded(s, EncodeOptions(fps=25, mask_types=[0, 0, 0, 1, 0, 0, 0, 0, 0, 0]))
    yield VectorDef("informative/hold-left-right", "informative", "M",
                    "mask type 1: left brow FAPs 31, 33 sent; the right partners are not copied (they stay 0)",
                    lr_hold, ("facts 5.3 mask type 1 [M]",), "child")


# ---- reject -----------------------------------------------------------------------------------
def _bits_put(data: bytes, offset: int, width: int, value: int) -> bytes:
    buf = bytearray(data)
    for j in range(width):
        bit = (value >> (width - 1 - j)) & 1
        byte, shift = divmod(offset + j, 8)
        mask = 0x80 >> shift
        buf[byte] = (buf[byte] | mask) if bit else (buf[byte] & ~mask)
    return bytes(buf)


def _bit(data: bytes, offset: int) -> int:
    return (data[offset // 8] >> (7 - offset % 8)) & 1


def _plane_starts(data: bytes) -> list[int]:
    """Bit offset of every plane of a stream without plane start codes (32 + the bits of the planes before)."""
    bits = decode(data).bits
    return [32 + int(x) for x in np.concatenate([[0], np.cumsum(bits)])]


def _base() -> bytes:
    """A valid 6-frame face stream: frame rate, no time code, group 2 per-FAP mask (FAPs 3, 4, 5) only."""
    n = 6
    return encoded(face_stream(n, _low_level(n, (3, 4, 5)))).data


HEADER = 32 + 1 + 2 + 1 + 13 + 1 + 1
"""Bit of fap_quant in the first plane of :func:`_base`: start code 32, is_intra 1, mask 2, is_frame_rate 1,
frame rate 8+4+1, is_time_code 1, skip_frames 1."""


def _reject() -> Iterator[VectorDef]:
    rules = ("SYNTAX.md 2", "SYNTAX.md 3")

    def start() -> Broken:
        return Broken(_bits_put(_base(), 24, 8, 0xBC), 0, 0)
    yield VectorDef("reject/bad-object-start-code", "reject", "V",
                    "starts with 0x000001BC: not fba_object_start_code (0x1BA) nor 0x101; detectable at bit 0",
                    start, rules)

    def short() -> Broken:
        return Broken(_base()[:3], 0, 0)
    yield VectorDef("reject/shorter-than-start-code", "reject", "S", "3 bytes: no room for the 32-bit start code (bit 0)",
                    short, rules)

    def mask0() -> Broken:
        return Broken(_bits_put(_base(), 33, 2, 0), 33, 0)
    yield VectorDef("reject/object-mask-0", "reject", "S",
                    "fba_object_mask 0 in plane 0: the field is bits 33-34 (after the 32-bit start code and is_intra)",
                    mask0, rules)

    def mask0_p() -> Broken:
        data = _base()
        k = 3
        at = _plane_starts(data)[k]
        return Broken(_bits_put(data, at + 1, 2, 0), at + 1, k)
    yield VectorDef("reject/object-mask-0-p", "reject", "S",
                    "fba_object_mask 0 in P plane 3: bit 1 of that plane (32 + the bits of planes 0-2 + 1); 3 frames decode",
                    mask0_p, rules)

    def rate0() -> Broken:
        return Broken(_bits_put(_base(), 36, 13, 0), 32, 0)
    yield VectorDef("reject/frame-rate-0", "reject", "S",
                    "frame_rate 0, seconds 0 (bits 36-48): fps 0 is refused; the fault is reported at the plane's first bit, 32",
                    rate0, ("SYNTAX.md 3 fps",))

    def marker() -> Broken:
        return Broken(_bits_put(_base(), HEADER + 5, 1, 0), HEADER + 5, 0)
    yield VectorDef("reject/marker-group-mask", "reject", "S",
                    f"marker bit of FAP group 1 is 0: bit {HEADER + 5} = start code 32 + is_intra 1 + fba_object_mask 2 + "
                    "is_frame_rate 1 + frame rate 8+4+1 + is_time_code 1 + skip_frames 1 + fap_quant 5",
                    marker, ("SYNTAX.md 3 marker bits", "SYNTAX.md 5"))

    def marker_minmax() -> Broken:
        # group masks: 10 x (marker + type) = 30 bits + 16 mask bits of group 2; gender, coding_type, 4 flags
        at = HEADER + 5 + 30 + 16 + 2 + 4
        return Broken(_bits_put(_base(), at, 1, 0), at, 0)
    yield VectorDef("reject/marker-new-minmax", "reject", "S",
                    "first marker bit of new_minmax() is 0: after fap_quant, 10 x 3 group bits, 16 mask bits of group 2, "
                    "gender, coding_type and the 4 set flags",
                    marker_minmax, ("SYNTAX.md 6",))

    def marker_tc() -> Broken:
        n = 4
        data = encoded(face_stream(n, _low_level(n, (3,))), tweak=lambda s: setattr(s.intra[0], "time_code", TimeCode(0, 0, 0))).data
        at = 32 + 1 + 2 + 1 + 13 + 1 + 5 + 6  # is_time_code at 49, hours 5, minutes 6
        return Broken(_bits_put(data, at, 1, 0), at, 0)
    yield VectorDef("reject/marker-time-code", "reject", "S",
                    "time code marker bit 0: bit 61 (is_time_code at 49, then hours 5 and minutes 6)",
                    marker_tc, ("SYNTAX.md 3 time code",))

    def p_first() -> Broken:
        data = b"\x00\x00\x01\xba" + bytes([0b00100000, 0xFF, 0xFF]) + b"\x7f\x00\x00\x01\xb1"
        return Broken(data, 36, 0)
    yield VectorDef("reject/p-plane-first", "reject", "S",
                    "the first plane is predicted (is_intra 0, mask 1, skip 0: bits 32-35) with face data no intra set up: bit 36",
                    p_first, ("SYNTAX.md 3 P plane parts",))

    def body_p() -> Broken:
        n = 4
        s = _basic(n)
        planned = plan(s, EncodeOptions(fps=25))
        data = write(planned)
        starts = _plane_starts(data)
        # plane 2 claims face+body: its face data (unchanged) still decodes and ends where the plane
        # ended, at the start of plane 3; the body data that no intra plane set up starts there
        return Broken(_bits_put(data, starts[2] + 1, 2, 3), starts[3], 2)
    yield VectorDef("reject/p-body-without-intra", "reject", "S",
                    "P plane 2's fba_object_mask set to 3: its face data decodes unchanged, then body data that no "
                    "intra plane set up, reported where it starts (the old end of plane 2)",
                    body_p, ("SYNTAX.md 3 P plane parts",))

    def code() -> Broken:
        data = _base()
        return Broken(data[:-1] + b"\xb5", (len(data) - 4) * 8, 6)
    yield VectorDef("reject/unexpected-start-code", "reject", "S",
                    "the end code replaced by 0x000001B5 (visual_object_start_code): not a plane or end code; "
                    "reported at its first bit, 8 x (length - 4); all 6 frames decode",
                    code, rules)

    def stuffing() -> Broken:
        data = _base()
        end = _plane_starts(data)[-1]
        return Broken(_bits_put(data, end, 1, 1), end, 6)
    yield VectorDef("reject/bad-stuffing", "reject", "S",
                    "the next_start_code() stuffing before the end code starts with '1' instead of '0': "
                    "reported at the stuffing's first bit, the end of the last plane",
                    stuffing, ("SYNTAX.md 2 next_start_code",))

    def no_end() -> Broken:
        data = _base()
        cut = len(data) - 4
        return Broken(data[:cut], 8 * cut, _decodable(data, cut))
    yield VectorDef("reject/no-end-code", "reject", "S",
                    "the end code cut off: the last plane's arithmetic decoder reads 14 bits past its segment "
                    "(16 at the start, a 14-bit rewind at the end), past the last byte; reported at 8 x length, "
                    "the 5 planes before decode",
                    no_end, rules + ("SYNTAX.md 9 rewind",))

    def truncated() -> Broken:
        data = _base()
        cut = _plane_starts(data)[4] // 8
        return Broken(data[:cut], 8 * cut, _decodable(data, cut))
    yield VectorDef("reject/truncated", "reject", "S",
                    "cut at the byte where plane 4 starts: a plane decodes only when its end + 14 look-ahead bits "
                    "lie before the cut (3 planes), then the decoder needs bits past the last byte (reported at 8 x length)",
                    truncated, ("SYNTAX.md 9 rewind",))

    def select() -> Broken:
        n = 3
        s = face_stream(n, viseme=[[14, 0, 0, 0], [14, 0, 0, 0], [20, 0, 0, 0]])
        planned = plan(s, EncodeOptions(fps=25))
        data = write(planned)
        starts = _plane_starts_lenient(data, 2)
        return Broken(data, starts[2] + 4, 2)
    yield VectorDef("reject/viseme-select-20", "reject", "S",
                    "P plane 2 codes a viseme_select1 difference of +6 from 14 (inside the P model's +-14): select 20, "
                    "outside 0..14; reported at the segment's first bit (the plane's bit 4, after is_intra, mask, skip)",
                    select, ("SYNTAX.md 8 selects",))

    def zero_run() -> Broken:
        vec = next(v for v in _syntax() if v.id == "syntax/arith-stuffing")
        built = vec.build()
        data = built.data
        at = _stuffing_bit(data, _intra_header_bits(built.stream, 0))
        return Broken(_bits_put(data, at, 1, 0), at, 0)
    yield VectorDef("reject/stuffing-bit-0", "reject", "S",
                    "syntax/arith-stuffing with its first stuffing '1' (after 22 zeros inside the segment) made '0': "
                    "reported at that bit",
                    zero_run, ("SYNTAX.md 9 get_bit",))


def _plane_starts_lenient(data: bytes, k: int) -> list[int]:
    """Plane starts up to plane ``k`` of a stream that fails in plane ``k`` (from the partial decode)."""
    try:
        bits = decode(data).bits
    except FbaError as exc:  # its partial stream holds the planes before the fault
        bits = exc.partial.bits
    return [32 + int(x) for x in np.concatenate([[0], np.cumsum(bits)])][: k + 1]


def _decodable(data: bytes, cut: int) -> int:
    """Planes of ``data`` still whole when it is cut to ``cut`` bytes: those whose end plus the
    arithmetic decoder's 14 look-ahead bits lie inside the cut."""
    ends = _plane_starts(data)[1:]
    return sum(1 for end in ends if end + 14 <= 8 * cut)


def _intra_header_bits(s: FapStream, k: int) -> int:
    """Bits of intra plane ``k``'s header, up to its first segment (object start code included for k = 0)."""
    from mpeg4fa.fba import syntax
    from mpeg4fa.fba.bits import BitWriter
    from mpeg4fa.fba.params import FACE as FACE_SPEC
    w = BitWriter()
    io = syntax.Writing(w)
    p = s.intra[k]
    io.flag(True, "is_intra")
    io.u(2, int(s.object_mask[k]), "fba_object_mask")
    syntax.temporal_header(io, True, p.frame_rate, p.time_code, int(s.skip[k]))
    syntax.part_intra_header(io, p.face, FACE_SPEC)
    return 32 + w.pos


def _stuffing_bit(data: bytes, segment_start: int) -> int:
    """The first bit after 22 zero bits counted from a segment's start (the coder's zero counter)."""
    run = 0
    for pos in range(segment_start, 8 * len(data)):
        if _bit(data, pos) == 0:
            run += 1
        else:
            if run >= 22:
                return pos
            run = 0
    raise AssertionError("no stuffing bit found")


def all_vectors() -> list[VectorDef]:
    """Every vector of the suite, in manifest order."""
    out = list(_syntax()) + list(_semantics()) + list(_reject())
    order = {"syntax": 0, "semantics": 1, "reject": 2, "informative": 3}
    return sorted(out, key=lambda v: order[v.group])
