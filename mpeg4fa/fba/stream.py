"""The codec's data model: coding parameters plus frames held in numpy arrays.

A :class:`FapStream` is what a decoder returns and what an encoder takes. Its
arrays are indexed ``[frame, parameter]``: column ``i`` of ``fap_values`` is FAP
``i + 1`` (so FAP 3 is column 2). FAP 1 (viseme) and FAP 2 (expression) have no
single value; their fields live in ``viseme`` and ``expression`` and their
presence in columns 0 and 1 of ``fap_mask``.

``intra`` maps the index of every intra frame to the :class:`CodingParams` its
header carried; everything the bitstream says about a frame is kept, so that a
stream re-encodes to the same bytes.

Integer arrays come in two widths (:data:`STORAGE`). :meth:`FapStream.empty` and
hand-made streams use the widest (``fap_values`` int32, ...); a stream built from
frames (:func:`~mpeg4fa.fba.decode`, the ``.fap``/``.bap`` readers) holds each
array in the narrowest type of its ladder that keeps every value within half the
type's range, so that a decoded stream of small values costs about 230 bytes a
frame instead of 400: ``fap_values`` int16 or int32, ``viseme``/``expression``
int8, int16 or int32, ``skip`` int8, int16 or int32, ``start_code`` uint16 or
uint32, ``bits`` int16 or int32. The half-range margin means the sum or difference
of two values of one array cannot wrap; anything more (products, running sums)
widens first (``astype(np.int64)``), and writing larger values into a stream
calls :meth:`FapStream.widen` first.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Iterable, Iterator

import numpy as np

from mpeg4fa.fba.errors import FbaError
from mpeg4fa.spec.frame_rate import FPS_MAX, FPS_MIN, FPS_RANGE_TEXT, FPS_STEPS, FRAME_RATE_BITS
from mpeg4fa.spec import FAP_GROUP_SLICES, N_BAP_GROUPS, N_BAPS, N_FAP_GROUPS, N_FAPS  # noqa: F401  (the codec's vocabulary)

FACE = 1
BODY = 2

OBJECT_START_CODE = 0x1BA
OBJECT_START_CODE_OLD = 0x101
PLANE_START_CODE = 0x1BB
PLANE_START_CODE_OLD = 0x103
END_CODE = 0x1B1

STORAGE: dict[str, tuple[type, ...]] = {
    "fap_values": (np.int16, np.int32), "viseme": (np.int8, np.int16, np.int32),
    "expression": (np.int8, np.int16, np.int32), "skip": (np.int8, np.int16, np.int32),
    "start_code": (np.uint16, np.uint32), "bits": (np.int16, np.int32),
}
"""Integer per-frame arrays a stream built from frames may hold narrow: field -> dtypes, narrowest first;
the last is the field's dtype in :meth:`FapStream.empty` (see the module docstring)."""


def fits(dtype, low: int, high: int) -> bool:
    """Whether values ``low..high`` lie within half of integer ``dtype``'s range (the storage margin)."""
    info = np.iinfo(dtype)
    return info.min // 2 <= int(low) and int(high) <= info.max // 2


def storage_dtype(ladder: tuple[type, ...], low: int, high: int, at_least: int = 0) -> type:
    """The narrowest dtype of ``ladder`` (from index ``at_least`` on) that :func:`fits` ``low..high``;
    the widest when none does."""
    return next((d for d in ladder[at_least:-1] if fits(d, low, high)), ladder[-1])


def narrowed(values: np.ndarray, field: str) -> np.ndarray:
    """``values`` of per-frame array ``field`` as a stream built from frames holds them (:data:`STORAGE`)."""
    values = np.asarray(values)
    ladder = STORAGE[field]
    if not values.size:
        return values.astype(ladder[0])
    return values.astype(storage_dtype(ladder, values.min(), values.max()))


DEFAULT_FPS = 30.0
"""Frame rate assumed when no intra header sends one (visage ``DEF_FRAME_RATE``)."""


@dataclass(frozen=True)
class FrameRate:
    """The three fields of the intra header's frame rate."""

    frame_rate: int
    seconds: int = 0
    frequency_offset: int = 0

    @property
    def fps(self) -> float:
        """Frames per second, computed in floating point (never 0 for 29.97-type rates)."""
        fps = self.frame_rate + self.seconds / FPS_STEPS
        return fps * 1000.0 / 1001.0 if self.frequency_offset else fps

    @classmethod
    def from_fps(cls, fps: float) -> "FrameRate":
        """The closest representable rate: integer + sixteenths, with the 1000/1001 flag if it fits better.

        Raises :class:`~mpeg4fa.fba.errors.FbaError` for a rate the header cannot carry (not a finite
        number, <= 0, or outside ``FPS_MIN``..``FPS_MAX`` of ``spec/frame_rate.csv``: 1/16 to
        255 15/16 frames per second). The one home of this rule: every reader and the encoder call it.
        """
        hint = f"an intra header carries {FPS_RANGE_TEXT} frames per second"
        if isinstance(fps, bool) or not isinstance(fps, (int, float, np.integer, np.floating)):
            raise FbaError(f"frame rate {fps!r} is not a number", hint=hint)
        fps = float(fps)
        if not math.isfinite(fps) or fps <= 0:
            raise FbaError(f"frame rate {fps:g} is not a positive finite number", hint=hint)
        # checked before any arithmetic: 1e308 * 16 is infinity, which round() cannot make an integer
        slack = 1.0 / (2 * FPS_STEPS)
        if fps > FPS_MAX + slack or fps < (FPS_MIN - slack) * 1000.0 / 1001.0:
            side = "more" if fps > 1 else "less"
            raise FbaError(f"frame rate {fps:g} is {side} than the bitstream can carry", hint=hint)
        candidates = []
        for offset in (0, 1):
            nominal = fps * 1001.0 / 1000.0 if offset else fps
            steps = int(round(nominal * FPS_STEPS))
            rate, seconds = divmod(steps, FPS_STEPS)
            if 0 < steps and rate < 1 << FRAME_RATE_BITS:
                candidate = cls(rate, seconds, offset)
                candidates.append((abs(candidate.fps - fps), offset, candidate))
        if not candidates:
            side = "more" if fps > 1 else "less"
            raise FbaError(f"frame rate {fps:g} is {side} than the bitstream can carry", hint=hint)
        return min(candidates, key=lambda c: (c[0], c[1]))[2]


@dataclass(frozen=True)
class TimeCode:
    hours: int
    minutes: int
    seconds: int

    @property
    def total_seconds(self) -> int:
        return 3600 * self.hours + 60 * self.minutes + self.seconds

    @classmethod
    def from_seconds(cls, t: float) -> "TimeCode":
        s = int(t)
        return cls(s // 3600 % 32, s // 60 % 60, s % 60)


@dataclass
class RangeSet:
    """new_minmax(): which of the four range sets an intra header sends, and their 5-bit codes.

    ``codes[k, i]`` is the code sent for parameter ``i`` in set ``k`` (0 = I max,
    1 = I min, 2 = P max, 3 = P min); it only means something where ``flags[k]`` is
    set and parameter ``i`` is masked. A code ``c`` stands for a range magnitude of
    ``c * 60`` before division by the quantiser.
    """

    flags: tuple[bool, bool, bool, bool]
    codes: np.ndarray

    @classmethod
    def none(cls, n: int) -> "RangeSet":
        return cls((False, False, False, False), np.zeros((4, n), dtype=np.int16))


@dataclass
class PartParams:
    """The face (FAP) or body (BAP) part of an intra header.

    ``quant`` is fap_quant or bap_quant (0..31, 0 = no quantisation); ``mask`` has
    one entry per parameter (68 FAPs or 296 BAPs, parameter 1 in column 0).
    """

    quant: int
    mask_types: tuple[int, ...]
    mask: np.ndarray
    gender: int = 0
    coding_type: int = 0
    ranges: RangeSet = field(default_factory=lambda: RangeSet.none(N_FAPS))


@dataclass
class CodingParams:
    """Everything an intra plane header sends besides the frame's values."""

    frame_rate: FrameRate | None = None
    time_code: TimeCode | None = None
    face: PartParams | None = None
    body: PartParams | None = None


@dataclass
class Frame:
    """One decoded plane: what the streaming iterator yields."""

    index: int
    timestamp: float
    object_mask: int
    fap_mask: np.ndarray
    fap_values: np.ndarray
    viseme: np.ndarray
    expression: np.ndarray
    bap_mask: np.ndarray
    bap_values: np.ndarray
    skip: int = 0
    start_code: int = 0
    bits: int = 0
    params: CodingParams | None = None
    stream: "FapStream | None" = field(default=None, repr=False, compare=False)
    """The stream this frame is a view of (set by :meth:`FapStream.frame`), so that what the frame
    shows can be resolved with the frames before it; None for a frame read on its own."""

    @property
    def is_intra(self) -> bool:
        return self.params is not None


@dataclass
class FapStream:
    """Coding parameters plus frames: see the module docstring for the layout."""

    fap_mask: np.ndarray        # (n, 68) bool
    fap_values: np.ndarray      # (n, 68) int16 or int32 (STORAGE), FAPU integers (AU for rotations)
    viseme: np.ndarray          # (n, 4) int8/16/32: select1, select2, blend, viseme_def
    expression: np.ndarray      # (n, 6) int8/16/32: select1, intensity1, select2, intensity2, init_face, def
    bap_mask: np.ndarray        # (n, 296) bool
    bap_values: np.ndarray      # (n, 296) int32
    timestamps: np.ndarray      # (n,) float64 seconds
    object_mask: np.ndarray     # (n,) uint8: 1 face, 2 body, 3 both
    skip: np.ndarray            # (n,) int8/16/32: frames skipped after this one
    start_code: np.ndarray      # (n,) uint16 or uint32: plane start code sent before the frame, 0 if none
    bits: np.ndarray            # (n,) int16 or int32: bits the frame took in its stream (0 if not decoded)
    intra: dict[int, CodingParams] = field(default_factory=dict)
    object_start_code: int = OBJECT_START_CODE
    source_fps: float | None = None
    """Frame rate of a stream that has no intra header yet (e.g. read from a .fap file)."""
    mask_types: tuple[int, ...] | None = None
    """Intended reading of unsent FAPs per FAP group (10: 1 hold, 2 interpolate) for frames no intra
    header governs: a stream made in memory (from text, a .fap file) says here how a decoder must read
    it, so that any encoding keeps its meaning. None: hold. See :meth:`group_mask_types`."""

    # ---- construction -------------------------------------------------------------
    @classmethod
    def empty(cls, n: int, object_mask: int = FACE) -> "FapStream":
        """A stream of ``n`` frames with nothing masked and every value zero."""
        return cls(
            fap_mask=np.zeros((n, N_FAPS), dtype=bool),
            fap_values=np.zeros((n, N_FAPS), dtype=np.int32),
            viseme=np.zeros((n, 4), dtype=np.int32),
            expression=np.zeros((n, 6), dtype=np.int32),
            bap_mask=np.zeros((n, N_BAPS), dtype=bool),
            bap_values=np.zeros((n, N_BAPS), dtype=np.int32),
            timestamps=np.zeros(n, dtype=np.float64),
            object_mask=np.full(n, object_mask, dtype=np.uint8),
            skip=np.zeros(n, dtype=np.int32),
            start_code=np.zeros(n, dtype=np.uint32),
            bits=np.zeros(n, dtype=np.int32),
        )

    @classmethod
    def from_frames(cls, frames: Iterable[Frame], object_start_code: int = OBJECT_START_CODE) -> "FapStream":
        """Stack frames (e.g. from :func:`mpeg4fa.fba.iter_decode`) into one stream.

        Memory stays proportional to the stream's arrays (:mod:`mpeg4fa.fba.stacking`); when no frame
        carries body data, ``bap_mask`` and ``bap_values`` are read-only zero rows shared by every frame.
        """
        from .stacking import stack_frames  # stacking builds on this module

        return stack_frames(frames, object_start_code)

    # ---- views ---------------------------------------------------------------------
    def __len__(self) -> int:
        return int(self.fap_values.shape[0])

    @property
    def n_frames(self) -> int:
        return len(self)

    def frame(self, k: int) -> Frame:
        """Frame ``k`` as a :class:`Frame` (views into the stream's arrays)."""
        return Frame(
            index=k, timestamp=float(self.timestamps[k]), object_mask=int(self.object_mask[k]),
            fap_mask=self.fap_mask[k], fap_values=self.fap_values[k], viseme=self.viseme[k],
            expression=self.expression[k], bap_mask=self.bap_mask[k], bap_values=self.bap_values[k],
            skip=int(self.skip[k]), start_code=int(self.start_code[k]), bits=int(self.bits[k]),
            params=self.intra.get(k), stream=self,
        )

    def __iter__(self) -> Iterator[Frame]:
        return (self.frame(k) for k in range(len(self)))

    def group_mask_types(self) -> np.ndarray:
        """``(n, 10)`` mask type governing each FAP group at each frame: the latest intra header's face
        mask types; a frame no header governs reads as an encoder would send it: 0 where the frame
        sends none of the group, 3 where it sends all, else :attr:`mask_types` (hold, 1, if None)."""
        intent = np.asarray(self.mask_types if self.mask_types is not None else (1,) * N_FAP_GROUPS, dtype=np.int8)
        sent = np.add.reduceat(self.fap_mask.astype(np.int16), [a for a, _ in FAP_GROUP_SLICES], axis=1)
        size = np.array([b - a for a, b in FAP_GROUP_SLICES])
        types = np.where(sent == 0, 0, np.where(sent == size, 3, intent[None, :])).astype(np.int8)
        for start in sorted(self.intra):
            face = self.intra[start].face
            if face is not None:
                types[start:] = np.asarray(face.mask_types, dtype=np.int8)
        return types

    @property
    def nbytes(self) -> int:
        """Bytes the per-frame arrays hold: what a stream costs in memory (a row shared by every frame,
        as a stream without body data shares its zero ``bap_mask``/``bap_values`` row, counts once)."""
        return sum(a[0].nbytes if a.ndim > 1 and len(a) and a.strides[0] == 0 else a.nbytes
                   for a in (getattr(self, name) for name in ARRAY_FIELDS))

    @property
    def first_params(self) -> CodingParams | None:
        return self.intra[min(self.intra)] if self.intra else None

    @property
    def fps(self) -> float:
        """Frame rate of the first intra header that sends one, else :data:`DEFAULT_FPS`."""
        for k in sorted(self.intra):
            if self.intra[k].frame_rate is not None:
                return self.intra[k].frame_rate.fps
        return self.source_fps if self.source_fps else DEFAULT_FPS

    @property
    def duration(self) -> float:
        """Seconds from the first frame to the end of the last (including its skipped frames)."""
        if not len(self):
            return 0.0
        return float(self.timestamps[-1] - self.timestamps[0] + (int(self.skip[-1]) + 1) / self.fps)

    def widen(self) -> "FapStream":
        """Hold every integer array in its widest dtype (:data:`STORAGE`), in place, and return the stream:
        call it before writing values into a decoded stream that its narrow arrays may not hold (numpy
        would wrap them silently). Arrays already wide are kept as they are."""
        for name, ladder in STORAGE.items():
            array = getattr(self, name)
            if array.dtype != ladder[-1]:
                setattr(self, name, array.astype(ladder[-1]))
        return self

    def take(self, frames: list[int]) -> "FapStream":
        """The given frames as a new stream (intra parameters are not carried: re-plan them)."""
        arrays = {name: _take(getattr(self, name), frames) for name in ARRAY_FIELDS}
        return replace(self, intra={}, **arrays)

    def copy(self) -> "FapStream":
        """A stream with arrays of its own; read-only rows shared by every frame (no body data) stay shared."""
        arrays = {name: _take(getattr(self, name), None) for name in ARRAY_FIELDS}
        return replace(self, intra=dict(self.intra), **arrays)


def _take(array: np.ndarray, frames: list[int] | None) -> np.ndarray:
    """``array[frames]`` (all of it for None) as a new array; one row shared by every frame (stride 0,
    read-only, e.g. the body arrays of a stream without body) stays one shared row."""
    if array.ndim > 1 and array.strides[0] == 0 and not array.flags.writeable:
        n = len(array) if frames is None else len(frames)
        return np.broadcast_to(array[0] if len(array) else np.zeros(array.shape[1:], array.dtype),
                               (n, *array.shape[1:]))
    return array.copy() if frames is None else array[frames].copy()


CONTENT_FIELDS = ("fap_mask", "fap_values", "viseme", "expression", "bap_mask", "bap_values", "object_mask")
"""The per-frame arrays that say what a frame shows (not when, nor how it was coded)."""

ARRAY_FIELDS = ("fap_mask", "fap_values", "viseme", "expression", "bap_mask", "bap_values",
                "timestamps", "object_mask", "skip", "start_code", "bits")
