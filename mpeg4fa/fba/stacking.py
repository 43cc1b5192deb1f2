"""Stacking frames into a :class:`FapStream` in memory proportional to its arrays, each held narrow.

:func:`~mpeg4fa.fba.decode` used to keep every decoded :class:`Frame` (a dozen small
numpy arrays each, 296-wide body rows included) and stack them at the end: about
4.7 KB a frame. :class:`StreamBuilder` writes each frame's rows straight into the
stream's arrays instead: one anonymous mapping per array that grows in place as frames
arrive (``mremap``: no copy, and pages are committed only as rows are written), and is
cut to its rows at the end. There is no joining step, so the peak is the stream's
arrays themselves, plus the :data:`BLOCK` frames :meth:`StreamBuilder.add` collects.

Each integer array is held in the narrowest dtype of its :data:`~mpeg4fa.fba.stream.STORAGE`
ladder that keeps every value seen so far within half the dtype's range; the first value that
does not fit widens that array, in place, to the next dtype that holds it. A face stream of
small values (one FAP of a few units, no skips) costs 228 bytes a frame: ``fap_mask`` 68,
``fap_values`` int16 136, ``viseme``/``expression`` int8 10, ``timestamps`` 8,
``object_mask`` 1, ``skip`` 1, ``start_code`` 2, ``bits`` 2; a stream whose values need int32
(head rotations at a fine quantiser) 364.

Body arrays are the exception that makes this pay: ``bap_mask`` and ``bap_values``
take ~1.5 KB a frame, and most streams send no body. They get a mapping only when
a frame with body data arrives (the frames before read as zero rows and commit no
memory); a stream none of whose frames has any gets :func:`no_body`, read-only zero
rows that take no memory per frame (assign new arrays to a stream to add BAPs to it).
"""
from __future__ import annotations

import mmap
from typing import Iterable

import numpy as np

from .stream import (FACE, N_BAPS, N_FAPS, OBJECT_START_CODE, STORAGE, CodingParams, FapStream, Frame, fits,
                     storage_dtype)

BLOCK = 1024
"""Frames per block of rows handed over at once (the compiled decoder's unit, and :meth:`StreamBuilder.add`'s)."""
STORE_BLOCK = 16384
"""Frames a :class:`StreamBuilder` array first makes room for; it doubles its room when full (address
space only: pages are committed as rows are written, so a short stream pays for what it fills)."""
WIDEN_CHUNK = 1 << 16
"""Values converted at a time when an array widens in place."""

_SHAPES = {  # field -> row shape, for every per-frame array
    "fap_mask": (N_FAPS,), "fap_values": (N_FAPS,), "viseme": (4,), "expression": (6,), "timestamps": (),
    "object_mask": (), "skip": (), "start_code": (), "bits": (), "bap_mask": (N_BAPS,), "bap_values": (N_BAPS,),
}
_LADDERS: dict[str, tuple[type, ...]] = {"fap_mask": (np.bool_,), "timestamps": (np.float64,),
                                         "object_mask": (np.uint8,), "bap_mask": (np.bool_,),
                                         "bap_values": (np.int32,), **STORAGE}
_BODY = ("bap_mask", "bap_values")
_FACE = tuple(name for name in _SHAPES if name not in _BODY)

ZERO_BAP_MASK = np.zeros(N_BAPS, dtype=bool)
ZERO_BAP_VALUES = np.zeros(N_BAPS, dtype=np.int32)
ZERO_BAP_MASK.flags.writeable = False
ZERO_BAP_VALUES.flags.writeable = False


def _mapping(size: int) -> mmap.mmap:
    """Zeroed anonymous memory of its own, private so that it can grow in place (a shared one cannot)."""
    flags = getattr(mmap, "MAP_PRIVATE", 0) | getattr(mmap, "MAP_ANONYMOUS", 0)
    return mmap.mmap(-1, max(1, size), flags=flags) if flags else mmap.mmap(-1, max(1, size))


def no_body(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``bap_mask`` and ``bap_values`` of ``n`` frames without body data: read-only views of one zero row."""
    return (np.broadcast_to(ZERO_BAP_MASK, (n, N_BAPS)), np.broadcast_to(ZERO_BAP_VALUES, (n, N_BAPS)))


class _Column:
    """One per-frame array being filled: rows in a mapping that grows in place, in a dtype that only widens."""

    def __init__(self, shape: tuple[int, ...], dtype, rows: int = 0) -> None:
        self.shape, self.dtype = shape, np.dtype(dtype)
        self.per_row = int(np.prod(shape))
        self.rows = rows  # rows filled (those before a body column was made read as zero)
        self.room = max(STORE_BLOCK, rows)
        self.map = _mapping(self.room * self.per_row * self.dtype.itemsize)

    def _resize(self, size: int) -> None:
        try:
            self.map.resize(max(1, size))  # Linux: mremap, the pages move without a copy
        except (OSError, SystemError, ValueError):  # no mremap here: a new mapping, copied
            old, self.map = self.map, _mapping(size)
            keep = min(len(old), size)
            self.map[:keep] = old[:keep]
            old.close()

    def values(self, rows: int) -> np.ndarray:
        """The first ``rows`` rows, flat (drop the view before the column grows)."""
        return np.frombuffer(self.map, self.dtype, count=rows * self.per_row)

    def write(self, start: int, rows: np.ndarray) -> None:
        """Rows ``start ..`` (written past :attr:`rows` they extend it)."""
        stop = start + len(rows)
        if stop > self.room:
            self.room = max(stop, 2 * self.room)
            self._resize(self.room * self.per_row * self.dtype.itemsize)
        self.values(stop)[start * self.per_row:] = np.asarray(rows).reshape(-1)
        self.rows = max(self.rows, stop)

    def widen(self, dtype) -> None:
        """Hold the values in ``dtype`` (wider), in place: converted from the end, so that a wider value never
        lands on a narrower one not yet read."""
        wide = np.dtype(dtype)
        self._resize(self.room * self.per_row * wide.itemsize)
        count = self.rows * self.per_row
        old, new = self.values(self.rows), np.frombuffer(self.map, wide, count=count)
        for stop in range(count, 0, -WIDEN_CHUNK):
            start = max(0, stop - WIDEN_CHUNK)
            new[start:stop] = old[start:stop].copy()
        del old, new
        self.dtype = wide

    def array(self, n: int) -> np.ndarray:
        """The column as an ``(n, *shape)`` array over its own mapping, cut to its rows; the column is spent."""
        if n == 0:
            return np.zeros((0, *self.shape), self.dtype)
        self._resize(n * self.per_row * self.dtype.itemsize)
        return self.values(n).reshape(n, *self.shape)


class StreamBuilder:
    """Frames in, one :class:`FapStream` out, holding only the arrays the stream will hold, each as narrow
    as its values allow (module docstring)."""

    def __init__(self, object_start_code: int = OBJECT_START_CODE) -> None:
        self.object_start_code = object_start_code
        self.intra: dict[int, CodingParams] = {}
        self._columns: dict[str, _Column] = {}  # made on the first rows (the body's on the first body rows)
        self._stage: dict[str, np.ndarray] | None = None  # rows add() collects, stored BLOCK at a time
        self._stage_body: tuple[np.ndarray, np.ndarray] | None = None
        self._staged = 0
        self._stored = 0
        self.n = 0

    def __len__(self) -> int:
        return self.n

    @property
    def dtypes(self) -> dict[str, np.dtype]:
        """The dtype each per-frame array is held in now (it only ever widens)."""
        return {name: (self._columns[name].dtype if name in self._columns else np.dtype(_LADDERS[name][0]))
                for name in _SHAPES}

    def add(self, *, fap_mask: np.ndarray, fap_values: np.ndarray, viseme: np.ndarray, expression: np.ndarray,
            timestamp: float = 0.0, object_mask: int = FACE, skip: int = 0, start_code: int = 0, bits: int = 0,
            bap_mask: np.ndarray | None = None, bap_values: np.ndarray | None = None,
            params: CodingParams | None = None) -> None:
        """Append one frame given as rows; body rows may be None (no body data)."""
        if self._stage is None:  # rows at full width here; narrowed when a block of them is stored
            self._stage = {name: np.zeros((BLOCK, *_SHAPES[name]), dtype=_LADDERS[name][-1]) for name in _FACE}
        stage, k = self._stage, self._staged
        stage["fap_mask"][k] = fap_mask
        stage["fap_values"][k] = fap_values
        stage["viseme"][k] = viseme
        stage["expression"][k] = expression
        for name, value in (("timestamps", timestamp), ("object_mask", object_mask), ("skip", skip),
                            ("start_code", start_code), ("bits", bits)):
            stage[name][k] = value
        has_body = (bap_mask is not None and bap_mask is not ZERO_BAP_MASK and bap_mask.any()) or \
            (bap_values is not None and bap_values is not ZERO_BAP_VALUES and bap_values.any())
        if has_body:
            if self._stage_body is None:
                self._stage_body = (np.zeros((BLOCK, N_BAPS), bool), np.zeros((BLOCK, N_BAPS), np.int32))
            for rows, value in zip(self._stage_body, (bap_mask, bap_values)):
                if value is not None:
                    rows[k] = value
        self._staged += 1
        self.n += 1
        if params is not None:
            self.intra[self.n - 1] = params
        if self._staged == len(stage["timestamps"]):
            self._flush()

    def _flush(self) -> None:
        """Store the rows :meth:`add` collected."""
        m, self._staged = self._staged, 0
        if not m:
            return
        body, self._stage_body = self._stage_body, None
        rows = {name: value[:m] for name, value in self._stage.items()}  # type: ignore[union-attr]
        self._store(rows, *((body[0][:m], body[1][:m]) if body is not None else (None, None)))

    def extend(self, rows: dict[str, np.ndarray], bap_mask: np.ndarray | None = None,
               bap_values: np.ndarray | None = None) -> None:
        """Append many frames given as arrays (the fields of ``FapStream`` but the body's, one row per frame),
        as :meth:`add` would one by one: the body arrays are made when a frame first carries body data."""
        self._flush()
        self._store(rows, bap_mask, bap_values)
        self.n += len(rows["timestamps"])

    def _store(self, rows: dict[str, np.ndarray], bap_mask: np.ndarray | None, bap_values: np.ndarray | None) -> None:
        n, start = len(rows["timestamps"]), self._stored
        body = {}
        if bap_mask is not None and bap_values is not None and (bap_mask.any() or bap_values.any()):
            body = {"bap_mask": bap_mask, "bap_values": bap_values}
        for name, values in (*((name, rows[name]) for name in _FACE), *body.items()):
            column = self._columns.get(name)
            if column is None:
                column = self._columns[name] = _Column(_SHAPES[name], _LADDERS[name][0], start)
            self._fit(column, _LADDERS[name], values)
            column.write(start, values)
        self._stored += n

    @staticmethod
    def _fit(column: _Column, ladder: tuple[type, ...], values: np.ndarray) -> None:
        """Widen ``column`` when ``values`` do not fit its dtype now."""
        if len(ladder) == 1 or column.dtype == ladder[-1] or not values.size:
            return
        low, high = values.min(), values.max()
        if not fits(column.dtype, low, high):
            at = [np.dtype(d) for d in ladder].index(column.dtype) + 1
            column.widen(storage_dtype(ladder, low, high, at))

    def append(self, frame: Frame) -> None:
        """Append a decoded (or hand-made) :class:`Frame`."""
        self.add(fap_mask=frame.fap_mask, fap_values=frame.fap_values, viseme=frame.viseme,
                 expression=frame.expression, timestamp=frame.timestamp, object_mask=frame.object_mask,
                 skip=frame.skip, start_code=frame.start_code, bits=frame.bits, bap_mask=frame.bap_mask,
                 bap_values=frame.bap_values, params=frame.params)

    def build(self) -> FapStream:
        """The stream of every frame added so far; its arrays are the builder's, cut to their rows. The
        builder is emptied."""
        self._flush()
        n = self.n
        arrays = {}
        for name in _SHAPES:
            column = self._columns.pop(name, None)
            if name in _BODY:
                if column is not None:
                    arrays[name] = column.array(n)
                continue
            arrays[name] = column.array(n) if column is not None else np.zeros((n, *_SHAPES[name]), _LADDERS[name][0])
        if "bap_mask" not in arrays:
            arrays["bap_mask"], arrays["bap_values"] = no_body(n)
        stream = FapStream(**arrays, intra=self.intra, object_start_code=self.object_start_code)
        self.__init__(self.object_start_code)  # type: ignore[misc]
        return stream


def stack_frames(frames: Iterable[Frame], object_start_code: int = OBJECT_START_CODE) -> FapStream:
    """The frames (e.g. from :func:`~mpeg4fa.fba.iter_decode`) as one stream, built by a :class:`StreamBuilder`."""
    builder = StreamBuilder(object_start_code)
    for frame in frames:
        builder.append(frame)
    return builder.build()


__all__ = ["BLOCK", "STORE_BLOCK", "StreamBuilder", "stack_frames", "no_body", "ZERO_BAP_MASK", "ZERO_BAP_VALUES"]
