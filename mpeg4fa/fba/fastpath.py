"""The decoder on the compiled path: intra planes in Python, runs of P planes in one compiled call.

Intra planes are rare and carry the headers, so :class:`FastDecoder` reads them with the
reference code it inherits; after each it lays the fresh models out as flat Fenwick tables
(:mod:`.compiled.kernels`) and hands every P plane up to the next intra plane to
:func:`.compiled.kernels.decode_planes`, which writes whole blocks of frames into arrays.
Faults are reported with the reference's words and bit offsets, so the two paths cannot be
told apart by their output or their errors (the tests decode every vector and fuzzed stream
both ways).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator

import numpy as np

from . import bits as bit_messages
from .arith import SEGMENT_ENDS, STUFFING_EXPECTED
from .bits import BitReader
from .compiled import kernels as kernel
from .compiled.tables import Bank, body_bank, coder_of, face_bank, share_face_predictions
from .decoder import NO_END_CODE, OBJECT_MASK_ZERO, _Decoder, no_intra, unexpected_start_code
from .errors import FbaError
from .stacking import BLOCK
from .stream import BODY as BODY_BIT, FACE as FACE_BIT, N_BAPS, N_FAPS, Frame

@dataclass
class Rows:
    """P frames the kernel decoded: one row per frame, in :class:`~mpeg4fa.fba.stacking.StreamBuilder` layout."""

    first: int
    arrays: dict[str, np.ndarray]
    bap_mask: np.ndarray | None
    bap_values: np.ndarray | None

    def __len__(self) -> int:
        return len(self.arrays["timestamps"])

    def frames(self) -> Iterator[Frame]:
        """The rows as :class:`Frame` objects (copies), for :func:`~mpeg4fa.fba.iter_decode`."""
        a = self.arrays
        for j in range(len(self)):
            body = self.bap_mask is not None and bool(a["object_mask"][j] & BODY_BIT)
            yield Frame(index=self.first + j, timestamp=float(a["timestamps"][j]), object_mask=int(a["object_mask"][j]),
                        fap_mask=a["fap_mask"][j].copy(), fap_values=a["fap_values"][j].copy(),
                        viseme=a["viseme"][j].copy(), expression=a["expression"][j].copy(),
                        bap_mask=self.bap_mask[j].copy() if body else np.zeros(N_BAPS, dtype=bool),
                        bap_values=self.bap_values[j].copy() if body else np.zeros(N_BAPS, dtype=np.int32),
                        skip=int(a["skip"][j]), start_code=int(a["start_code"][j]), bits=int(a["bits"][j]))


class FastDecoder(_Decoder):
    """:class:`~mpeg4fa.fba.decoder._Decoder` with P planes on the compiled path."""

    def __init__(self, reader: BitReader, block: int = BLOCK) -> None:
        super().__init__(reader)
        self.block = block
        self.fprev = share_face_predictions(self.viseme, self.expression, self.faps)
        self.fbank, self.bbank = Bank.empty(), Bank.empty()
        self.eof = reader._file is None  # noqa: SLF001 - the reader is ours
        self.res = np.zeros(kernel.RESULT_SIZE, dtype=np.int64)
        self.times = np.zeros(1, dtype=np.float64)
        self.scratch = np.zeros(max(N_BAPS, N_FAPS) + 8, dtype=np.int64)
        self._packed, self._packed_of = np.zeros(8, np.uint8), None

    def segment(self, models: list, adapt: bool) -> list[int]:
        """Intra segments (uniform models) compiled too; P segments never come here but stay correct."""
        if adapt:
            return super().segment(models, adapt)
        r = self.bits
        r.available(64 + kernel.SYMBOL_BITS * len(models))  # load the window far enough, if the stream goes on
        buf = np.frombuffer(r.buf, dtype=np.uint8)
        symbols = np.empty(len(models), dtype=np.int64)
        p, err = kernel.uniform_segment(buf, r.p, len(buf), np.asarray(models, dtype=np.int64), symbols)
        if err == kernel.BAD_STUFFING:
            raise FbaError(STUFFING_EXPECTED, r.base + p - 1)
        if err:
            raise FbaError(SEGMENT_ENDS, r.base + p)
        r.p = p
        return symbols.tolist()

    # ---- after an intra plane: the models it set up, as flat tables ----
    def _reset_face(self) -> None:
        self.fbank = face_bank(self.viseme, self.expression, self.faps, self.face.mask)

    def _reset_body(self) -> None:
        self.bbank = body_bank(self.baps)

    # ---- the loop ----
    def items(self) -> Iterator[Frame | Rows]:
        """Frames in order: intra planes as :class:`Frame`, runs of P planes as :class:`Rows`."""
        self.object_start()
        r, res = self.bits, self.res
        k = 0
        while True:
            rows = self._run(k)
            status = int(res[kernel.STATUS])
            if rows is not None:
                yield rows
                k += len(rows)
            r.p = int(res[kernel.POS])  # where to go on (ERROR: where the fault is)
            if status == kernel.FULL:
                continue
            if status == kernel.NEED_MORE:
                if not r.more():
                    self.eof = True
                continue
            if status == kernel.END:
                return
            if status == kernel.ERROR:
                raise self._fault(k)
            try:  # INTRA: the reference reads it, then its models become tables
                frame = self.framed_plane(k, int(res[kernel.CODE]))
            except FbaError as exc:
                exc.frame = k if exc.frame is None else exc.frame
                raise
            if frame.params.face is not None:
                self._reset_face()
            if frame.params.body is not None:
                self._reset_body()
            yield frame
            k += 1

    def _run(self, first: int) -> Rows | None:
        r, fb, bb = self.bits, self.fbank, self.bbank
        n = self.block
        a = {"object_mask": np.empty(n, np.uint8), "skip": np.empty(n, np.int32), "start_code": np.empty(n, np.uint32),
             "timestamps": np.empty(n, np.float64), "bits": np.empty(n, np.int32), "viseme": np.empty((n, 4), np.int32),
             "expression": np.empty((n, 6), np.int32), "fap_values": np.empty((n, N_FAPS), np.int32)}
        bap = np.empty((n if self.body is not None else 0, N_BAPS), np.int32)
        self.times[0] = self.next_pts
        buf = np.frombuffer(r.buf, dtype=np.uint8)
        if self._packed_of is not r.buf:  # the window's bits 8 to a byte, for the coder's multi-bit reads
            self._packed = np.concatenate([np.packbits(buf), np.zeros(8, np.uint8)])
            self._packed_of = r.buf
        face = self.face
        kernel.decode_planes(buf, self._packed, r.base, r.p, len(buf), self.eof,
                             fb.meta, fb.total, fb.freq, fb.tree, self.fprev, face is not None,
                             bool(face is not None and face.mask[0]), bool(face is not None and face.mask[1]),
                             bb.meta, bb.total, bb.freq, bb.tree, self.baps.prev, self.body is not None,
                             float(self.fps), self.times,
                             a["object_mask"], a["skip"], a["start_code"], a["timestamps"], a["bits"],
                             a["viseme"], a["expression"], a["fap_values"], bap, n, self.res, self.scratch)
        self.next_pts = float(self.times[0])
        m = int(self.res[kernel.ROWS])
        if m == 0:
            return None
        a = {name: value[:m] for name, value in a.items()}
        has_face = (a["object_mask"] & FACE_BIT) != 0
        a["fap_mask"] = has_face[:, None] & face.mask[None, :] if face is not None else np.zeros((m, N_FAPS), bool)
        bap_mask = bap_values = None
        if self.body is not None:
            has_body = (a["object_mask"] & BODY_BIT) != 0
            bap_mask, bap_values = has_body[:, None] & self.body.mask[None, :], bap[:m]
        return Rows(first, a, bap_mask, bap_values)

    def _fault(self, k: int) -> FbaError:
        """The kernel's fault as the reference path words it."""
        res = self.res
        fault, a0, a1, a2 = (int(res[i]) for i in (kernel.FAULT, kernel.ARG0, kernel.ARG1, kernel.ARG2))
        pos = self.bits.base + int(res[kernel.POS])
        if fault == kernel.TRUNCATED_FIELD:
            message = bit_messages.truncated(kernel.FIELD_NAMES[a0], a1, a2)
        elif fault == kernel.NO_END_CODE:
            message = NO_END_CODE
        elif fault == kernel.BAD_START_CODE:
            message = unexpected_start_code(a0)
        elif fault == kernel.BAD_STUFFING_BITS:
            message = bit_messages.bad_stuffing(a0, a1)
        elif fault == kernel.OBJECT_MASK_ZERO:
            message = OBJECT_MASK_ZERO
        elif fault == kernel.NO_FACE_INTRA:
            message = no_intra("face")
        elif fault == kernel.NO_BODY_INTRA:
            message = no_intra("body")
        elif fault == kernel.SEGMENT_TRUNCATED:
            message = SEGMENT_ENDS
        elif fault == kernel.SEGMENT_STUFFING:
            message = STUFFING_EXPECTED
        elif fault == kernel.SELECT_OUT_OF_RANGE:
            coder, j = coder_of(self.fbank.meta[a0], self.viseme, self.expression, self.faps, self.baps)
            message = coder.select_message(j, a1)
        else:  # pragma: no cover - every fault code is named above
            message = f"compiled decoder fault {fault}"
        return FbaError(message, pos, k)
