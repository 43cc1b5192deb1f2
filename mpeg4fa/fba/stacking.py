"""Stacking frames into a :class:`FapStream` in memory proportional to its arrays.

:func:`~mpeg4fa.fba.decode` used to keep every decoded :class:`Frame` (a dozen small
numpy arrays each, 296-wide body rows included) and stack them at the end: about
4.7 KB a frame. :class:`StreamBuilder` copies each frame's rows into blocks of
:data:`STORE_BLOCK` frames instead, and joins the blocks field by field, freeing each
field's blocks as soon as it is joined, so a face stream costs its ~400 bytes a
frame (peak under 700 bytes while joining).

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

from .stream import FACE, N_BAPS, N_FAPS, OBJECT_START_CODE, CodingParams, FapStream, Frame

BLOCK = 1024
"""Frames per block of rows handed over at once (the compiled decoder's unit)."""
STORE_BLOCK = 16384
"""Frames per storage block of a :class:`StreamBuilder`: few mappings even for millions of frames, and
pages are committed only as rows are written, so a short stream pays for what it fills."""

_ROWS = {  # field -> (row shape, dtype): the FapStream layout of every per-frame array but the body's
    "fap_mask": ((N_FAPS,), bool), "fap_values": ((N_FAPS,), np.int32), "viseme": ((4,), np.int32),
    "expression": ((6,), np.int32), "timestamps": ((), np.float64), "object_mask": ((), np.uint8),
    "skip": ((), np.int32), "start_code": ((), np.uint32), "bits": ((), np.int32),
}
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
    """Frames in, one :class:`FapStream` out, holding only the arrays the stream will hold."""

    def __init__(self, object_start_code: int = OBJECT_START_CODE) -> None:
        self.object_start_code = object_start_code
        self.intra: dict[int, CodingParams] = {}
        self._blocks: list[dict[str, np.ndarray | None]] = []
        self._fill = STORE_BLOCK  # rows used in the last block (full: the next frame opens a block)
        self.n = 0

    def __len__(self) -> int:
        return self.n

    def _open_block(self) -> None:
        block: dict[str, np.ndarray | None] = {
            name: _fresh((STORE_BLOCK, *shape), dtype) for name, (shape, dtype) in _ROWS.items()}
        block.update(dict.fromkeys(_BODY))
        self._blocks.append(block)
        self._fill = 0

    def _row(self) -> tuple[dict[str, np.ndarray | None], int]:
        if self._fill == STORE_BLOCK:
            self._open_block()
        row = self._fill
        self._fill += 1
        self.n += 1
        return self._blocks[-1], row

    def add(self, *, fap_mask: np.ndarray, fap_values: np.ndarray, viseme: np.ndarray, expression: np.ndarray,
            timestamp: float = 0.0, object_mask: int = FACE, skip: int = 0, start_code: int = 0, bits: int = 0,
            bap_mask: np.ndarray | None = None, bap_values: np.ndarray | None = None,
            params: CodingParams | None = None) -> None:
        """Append one frame given as rows; body rows may be None (no body data)."""
        block, k = self._row()
        block["fap_mask"][k] = fap_mask  # type: ignore[index]
        block["fap_values"][k] = fap_values  # type: ignore[index]
        block["viseme"][k] = viseme  # type: ignore[index]
        block["expression"][k] = expression  # type: ignore[index]
        for name, value in (("timestamps", timestamp), ("object_mask", object_mask), ("skip", skip),
                            ("start_code", start_code), ("bits", bits)):
            block[name][k] = value  # type: ignore[index]
        has_body = (bap_mask is not None and bap_mask is not ZERO_BAP_MASK and bap_mask.any()) or \
            (bap_values is not None and bap_values is not ZERO_BAP_VALUES and bap_values.any())
        if has_body:
            for name, value in (("bap_mask", bap_mask), ("bap_values", bap_values)):
                if block[name] is None:
                    block[name] = _fresh((STORE_BLOCK, N_BAPS), _BODY[name])
                if value is not None:
                    block[name][k] = value  # type: ignore[index]
        if params is not None:
            self.intra[self.n - 1] = params

    def extend(self, rows: dict[str, np.ndarray], bap_mask: np.ndarray | None = None,
               bap_values: np.ndarray | None = None) -> None:
        """Append many frames given as arrays (the fields of ``_ROWS``, one row per frame), as :meth:`add`
        would one by one: a block gets body arrays only when one of its frames carries body data."""
        n = len(rows["timestamps"])
        body = None
        if bap_mask is not None and bap_values is not None:
            body = bap_mask.any(axis=1) | bap_values.any(axis=1)
        done = 0
        while done < n:
            if self._fill == STORE_BLOCK:
                self._open_block()
            block, start = self._blocks[-1], self._fill
            take = min(STORE_BLOCK - start, n - done)
            for name in _ROWS:
                block[name][start:start + take] = rows[name][done:done + take]  # type: ignore[index]
            if body is not None and body[done:done + take].any():
                for name, value in (("bap_mask", bap_mask), ("bap_values", bap_values)):
                    if block[name] is None:
                        block[name] = _fresh((STORE_BLOCK, N_BAPS), _BODY[name])
                    block[name][start:start + take] = value[done:done + take]  # type: ignore[index]
            self._fill += take
            self.n += take
            done += take

    def append(self, frame: Frame) -> None:
        """Append a decoded (or hand-made) :class:`Frame`."""
        self.add(fap_mask=frame.fap_mask, fap_values=frame.fap_values, viseme=frame.viseme,
                 expression=frame.expression, timestamp=frame.timestamp, object_mask=frame.object_mask,
                 skip=frame.skip, start_code=frame.start_code, bits=frame.bits, bap_mask=frame.bap_mask,
                 bap_values=frame.bap_values, params=frame.params)

    def build(self) -> FapStream:
        """The stream of every frame added so far. The builder is emptied: its blocks are freed as they are joined."""
        n, blocks = self.n, self._blocks
        sizes = [STORE_BLOCK] * (len(blocks) - 1) + ([self._fill] if blocks else [])
        arrays: dict[str, np.ndarray] = {}
        for name, (shape, dtype) in _ROWS.items():
            arrays[name] = self._join(name, (n, *shape), dtype, sizes)
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
