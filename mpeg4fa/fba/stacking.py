"""Stacking frames into a :class:`FapStream` in memory proportional to its arrays, each held narrow.

:func:`~mpeg4fa.fba.decode` used to keep every decoded :class:`Frame` (a dozen small
numpy arrays each, 296-wide body rows included) and stack them at the end: about
4.7 KB a frame. :class:`StreamBuilder` copies each frame's rows into blocks of
:data:`STORE_BLOCK` frames instead, and joins the blocks field by field, freeing each
block as soon as it is copied, so a stream costs its arrays (and one block) at the peak.

Each integer array is held in the narrowest dtype of its :data:`~mpeg4fa.fba.stream.STORAGE`
ladder that keeps every value seen so far within half the dtype's range; the first value that
does not fit widens that field's blocks, all of them, to the next dtype that holds it. A face
stream of small values (one FAP of a few units, no skips) costs 228 bytes a frame: ``fap_mask``
68, ``fap_values`` int16 136, ``viseme``/``expression`` int8 10, ``timestamps`` 8,
``object_mask`` 1, ``skip`` 1, ``start_code`` 2, ``bits`` 2; a stream whose values need int32
(head rotations at a fine quantiser) 364.

Body arrays are the exception that makes this pay: ``bap_mask`` and ``bap_values``
take ~1.5 KB a frame, and most streams send no body. A block gets them only when
a frame with body data arrives; a stream none of whose frames has any gets
:func:`no_body`, read-only zero rows that take no memory per frame (assign new
arrays to a stream to add BAPs to it).
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
"""Frames per storage block of a :class:`StreamBuilder`: few mappings even for millions of frames, and
pages are committed only as rows are written, so a short stream pays for what it fills."""

_SHAPES = {  # field -> row shape, for every per-frame array but the body's
    "fap_mask": (N_FAPS,), "fap_values": (N_FAPS,), "viseme": (4,), "expression": (6,), "timestamps": (),
    "object_mask": (), "skip": (), "start_code": (), "bits": (),
}
_LADDERS: dict[str, tuple[type, ...]] = {"fap_mask": (np.bool_,), "timestamps": (np.float64,),
                                         "object_mask": (np.uint8,), **STORAGE}
_BODY = {"bap_mask": bool, "bap_values": np.int32}

ZERO_BAP_MASK = np.zeros(N_BAPS, dtype=bool)
ZERO_BAP_VALUES = np.zeros(N_BAPS, dtype=np.int32)
ZERO_BAP_MASK.flags.writeable = False
ZERO_BAP_VALUES.flags.writeable = False


def _fresh(shape: tuple[int, ...], dtype) -> np.ndarray:
    """Zeroed rows in an anonymous mapping of their own: given back to the system the moment the block is
    dropped (heap blocks of this size stay with the process), so joining blocks into the stream's arrays
    costs the arrays plus one block, not twice the stream."""
    count = int(np.prod(shape))
    buffer = mmap.mmap(-1, max(1, count * np.dtype(dtype).itemsize))
    return np.frombuffer(buffer, dtype=dtype, count=count).reshape(shape)


def no_body(n: int) -> tuple[np.ndarray, np.ndarray]:
    """``bap_mask`` and ``bap_values`` of ``n`` frames without body data: read-only views of one zero row."""
    return (np.broadcast_to(ZERO_BAP_MASK, (n, N_BAPS)), np.broadcast_to(ZERO_BAP_VALUES, (n, N_BAPS)))


class StreamBuilder:
    """Frames in, one :class:`FapStream` out, holding only the arrays the stream will hold, each as narrow
    as its values allow (module docstring)."""

    def __init__(self, object_start_code: int = OBJECT_START_CODE) -> None:
        self.object_start_code = object_start_code
        self.intra: dict[int, CodingParams] = {}
        self._blocks: list[dict[str, np.ndarray | None]] = []
        self._fill = STORE_BLOCK  # rows used in the last block (full: the next frame opens a block)
        self._dtypes = {name: ladder[0] for name, ladder in _LADDERS.items()}
        self._stage: dict[str, np.ndarray] | None = None  # rows add() collects, stored BLOCK at a time
        self._stage_body: tuple[np.ndarray, np.ndarray] | None = None
        self._staged = 0
        self.n = 0

    def __len__(self) -> int:
        return self.n

    @property
    def dtypes(self) -> dict[str, np.dtype]:
        """The dtype each per-frame array is held in now (it only ever widens)."""
        return {name: np.dtype(dtype) for name, dtype in self._dtypes.items()}

    def add(self, *, fap_mask: np.ndarray, fap_values: np.ndarray, viseme: np.ndarray, expression: np.ndarray,
            timestamp: float = 0.0, object_mask: int = FACE, skip: int = 0, start_code: int = 0, bits: int = 0,
            bap_mask: np.ndarray | None = None, bap_values: np.ndarray | None = None,
            params: CodingParams | None = None) -> None:
        """Append one frame given as rows; body rows may be None (no body data)."""
        if self._stage is None:  # rows at full width here; narrowed when a block of them is stored
            self._stage = {name: np.zeros((BLOCK, *_SHAPES[name]), dtype=ladder[-1])
                           for name, ladder in _LADDERS.items()}
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
        as :meth:`add` would one by one: a block gets body arrays only when one of its frames carries body data."""
        self._flush()
        self._store(rows, bap_mask, bap_values)
        self.n += len(rows["timestamps"])

    def _store(self, rows: dict[str, np.ndarray], bap_mask: np.ndarray | None, bap_values: np.ndarray | None) -> None:
        n = len(rows["timestamps"])
        for name in STORAGE:
            self._fit(name, rows[name])
        body = None
        if bap_mask is not None and bap_values is not None:
            body = bap_mask.any(axis=1) | bap_values.any(axis=1)
        done = 0
        while done < n:
            if self._fill == STORE_BLOCK:
                self._open_block()
            block, start = self._blocks[-1], self._fill
            take = min(STORE_BLOCK - start, n - done)
            for name in _SHAPES:
                block[name][start:start + take] = rows[name][done:done + take]  # type: ignore[index]
            if body is not None and body[done:done + take].any():
                for name, value in (("bap_mask", bap_mask), ("bap_values", bap_values)):
                    if block[name] is None:
                        block[name] = _fresh((STORE_BLOCK, N_BAPS), _BODY[name])
                    block[name][start:start + take] = value[done:done + take]  # type: ignore[index]
            self._fill += take
            done += take

    def _fit(self, name: str, values: np.ndarray) -> None:
        """Widen field ``name``, in every block, when ``values`` do not fit its dtype now."""
        current = self._dtypes[name]
        if not values.size or current is _LADDERS[name][-1]:
            return
        low, high = values.min(), values.max()
        if fits(current, low, high):
            return
        ladder = _LADDERS[name]
        wide = storage_dtype(ladder, low, high, ladder.index(current) + 1)
        self._dtypes[name] = wide
        for block in self._blocks:  # one block at a time: the peak grows by one block, not the stream
            narrow = block[name]
            block[name] = _fresh(narrow.shape, wide)  # type: ignore[union-attr]
            block[name][...] = narrow  # type: ignore[index]
            del narrow

    def _open_block(self) -> None:
        block: dict[str, np.ndarray | None] = {
            name: _fresh((STORE_BLOCK, *shape), self._dtypes[name]) for name, shape in _SHAPES.items()}
        block.update(dict.fromkeys(_BODY))
        self._blocks.append(block)
        self._fill = 0

    def append(self, frame: Frame) -> None:
        """Append a decoded (or hand-made) :class:`Frame`."""
        self.add(fap_mask=frame.fap_mask, fap_values=frame.fap_values, viseme=frame.viseme,
                 expression=frame.expression, timestamp=frame.timestamp, object_mask=frame.object_mask,
                 skip=frame.skip, start_code=frame.start_code, bits=frame.bits, bap_mask=frame.bap_mask,
                 bap_values=frame.bap_values, params=frame.params)

    def build(self) -> FapStream:
        """The stream of every frame added so far. The builder is emptied: its blocks are freed as they are joined."""
        self._flush()
        n, blocks = self.n, self._blocks
        sizes = [STORE_BLOCK] * (len(blocks) - 1) + ([self._fill] if blocks else [])
        arrays: dict[str, np.ndarray] = {}
        for name, shape in _SHAPES.items():
            arrays[name] = self._join(name, (n, *shape), self._dtypes[name], sizes)
        if any(block["bap_mask"] is not None for block in blocks):
            for name, dtype in _BODY.items():
                arrays[name] = self._join(name, (n, N_BAPS), dtype, sizes)
        else:
            arrays["bap_mask"], arrays["bap_values"] = no_body(n)
        stream = FapStream(**arrays, intra=self.intra, object_start_code=self.object_start_code)
        self.__init__(self.object_start_code)  # type: ignore[misc]
        return stream

    def _join(self, name: str, shape: tuple[int, ...], dtype, sizes: list[int]) -> np.ndarray:
        out = np.zeros(shape, dtype=dtype)
        start = 0
        for block, size in zip(self._blocks, sizes):
            part = block[name]
            if part is not None:
                out[start:start + size] = part[:size]
            block[name] = None  # freed now, before the next field is allocated
            start += size
        return out


def stack_frames(frames: Iterable[Frame], object_start_code: int = OBJECT_START_CODE) -> FapStream:
    """The frames (e.g. from :func:`~mpeg4fa.fba.iter_decode`) as one stream, built by a :class:`StreamBuilder`."""
    builder = StreamBuilder(object_start_code)
    for frame in frames:
        builder.append(frame)
    return builder.build()


__all__ = ["BLOCK", "STORE_BLOCK", "StreamBuilder", "stack_frames", "no_body", "ZERO_BAP_MASK", "ZERO_BAP_VALUES"]
