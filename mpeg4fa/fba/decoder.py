"""fba_object() decoding: start codes, planes, and the face and body data of each plane (the reference path).

:class:`_Decoder` yields frames; :mod:`.fastpath` builds on it (P planes compiled), and :mod:`.decoding`
chooses between the two and offers :func:`~mpeg4fa.fba.decode` / :func:`~mpeg4fa.fba.iter_decode`.
Imports go one way: decoder <- fastpath <- decoding.
"""
from __future__ import annotations

import os
from contextlib import contextmanager
from pathlib import Path
from typing import BinaryIO, Iterator

import numpy as np

from . import syntax
from .arith import decode_segment
from .bits import BitReader
from ..filetype import foreign_kind
from .errors import FbaError
from .params import BODY, FACE, FieldCoder, ValueCoder
from .stacking import ZERO_BAP_MASK, ZERO_BAP_VALUES
from .stream import (BODY as BODY_BIT, DEFAULT_FPS, END_CODE, FACE as FACE_BIT, N_BAPS, N_FAPS,
                     OBJECT_START_CODE, OBJECT_START_CODE_OLD, PLANE_START_CODE, PLANE_START_CODE_OLD,
                     CodingParams, FapStream, Frame, PartParams)

Source = bytes | bytearray | memoryview | str | os.PathLike | BinaryIO

NO_END_CODE = "stream ends without the end code 0x000001B1 (truncated?)"
OBJECT_MASK_ZERO = "fba_object_mask is 0: the plane carries neither face nor body data"


def unexpected_start_code(code: int) -> str:
    return f"unexpected start code 0x{code:08X} between planes"


def no_intra(part: str) -> str:
    return f"a predicted plane carries {part} data but no intra plane has set up the {part}"


@contextmanager
def _opened(source: Source) -> Iterator[bytes | BinaryIO]:
    if isinstance(source, (str, os.PathLike)):
        try:
            with open(source, "rb") as fh:
                yield fh
        except FileNotFoundError:
            raise FbaError(f"no such stream file: {Path(source)}") from None
        except OSError as exc:  # a directory, no permission, ...
            raise FbaError(f"cannot read stream file {Path(source)}: {exc.strerror or exc}") from None
    else:
        yield source


class _Decoder:
    """The state a decoder carries from plane to plane."""

    def __init__(self, reader: BitReader) -> None:
        self.bits = reader
        self.io = syntax.Reading(reader)
        self.faps = ValueCoder(FACE)
        self.baps = ValueCoder(BODY)
        self.viseme = FieldCoder(1)
        self.expression = FieldCoder(2)
        self.face: PartParams | None = None
        self.body: PartParams | None = None
        self.fps = DEFAULT_FPS
        self.next_pts = 0.0
        self.object_start_code = OBJECT_START_CODE

    def object_start(self) -> None:
        """Read the fba_object_start_code."""
        r = self.bits
        if not r.available(32):
            raise FbaError("stream is shorter than a start code: not an FBA stream", 0)
        code = r.read(32)
        if code not in (OBJECT_START_CODE, OBJECT_START_CODE_OLD):
            more = next(n for n in (96, 64, 32, 0) if r.available(n))  # enough to tell MP4 and WAV too
            kind = foreign_kind(code.to_bytes(4, "big") + (r.read(more).to_bytes(more // 8, "big") if more else b""))
            raise FbaError(f"not an FBA stream: starts with 0x{code:08X}{f' ({kind})' if kind else ''}, expected "
                           f"the fba_object_start_code 0x{OBJECT_START_CODE:08X}", 0)
        self.object_start_code = code

    def items(self) -> Iterator[Frame]:
        """Every frame, in order (the compiled path's decoder yields blocks of frames too)."""
        return self.frames()

    def frames(self) -> Iterator[Frame]:
        self.object_start()
        k = 0
        while True:
            try:
                plane_code = self.between_planes()
                if plane_code is None:
                    return
                frame = self.framed_plane(k, plane_code)
            except FbaError as exc:
                exc.frame = k if exc.frame is None else exc.frame
                raise
            yield frame
            k += 1

    def segment(self, models: list, adapt: bool) -> list[int]:
        """One arithmetic-coded segment's symbols."""
        return decode_segment(self.bits, models, adapt)

    def decoded(self, part: str, coder: FieldCoder | ValueCoder, values: np.ndarray) -> None:
        """Hook called with each segment's reconstructed values (``part``: viseme, expression, face
        or body), so that the syntax trace (:mod:`mpeg4fa.fba.trace`) can name them; a no-op here."""

    def framed_plane(self, k: int, plane_code: int) -> Frame:
        """Plane ``k`` as a frame, with the bits it took (after its start code)."""
        start = self.bits.pos
        frame = self.plane(k, plane_code)
        frame.bits = self.bits.pos - start
        return frame

    def between_planes(self) -> int | None:
        """Consume a plane start code (returned, 0 if none) or the end code (None)."""
        r = self.bits
        found = r.peek_start_code()
        if found is None:
            if not r.available(8):
                raise FbaError(NO_END_CODE, r.pos)
            return 0
        code, stuffing = found
        if code not in (END_CODE, PLANE_START_CODE, PLANE_START_CODE_OLD):
            raise FbaError(unexpected_start_code(code), r.pos + stuffing)
        r.skip_stuffing(stuffing)
        r.read(32)
        return None if code == END_CODE else code

    def plane(self, k: int, plane_code: int) -> Frame:
        io, r = self.io, self.bits
        pos = r.pos
        is_intra = io.flag(False, "is_intra")
        mask = io.u(2, 0, "fba_object_mask")
        if mask == 0:
            raise FbaError(OBJECT_MASK_ZERO, pos + 1)
        fr, tc, skip = syntax.temporal_header(io, is_intra, None, None, 0)
        params = CodingParams(frame_rate=fr, time_code=tc) if is_intra else None
        if fr is not None:
            if fr.fps <= 0:
                raise FbaError("frame rate 0 in the intra header", pos)
            self.fps = fr.fps
        frame = Frame(index=k, timestamp=0.0, object_mask=mask,
                      fap_mask=np.zeros(N_FAPS, dtype=bool), fap_values=np.zeros(N_FAPS, dtype=np.int32),
                      viseme=np.zeros(4, dtype=np.int32), expression=np.zeros(6, dtype=np.int32),
                      bap_mask=ZERO_BAP_MASK, bap_values=ZERO_BAP_VALUES,
                      skip=skip, start_code=plane_code, params=params)
        if mask & FACE_BIT:
            self.face_data(frame, is_intra)
        if mask & BODY_BIT:
            self.body_data(frame, is_intra)
        frame.timestamp = float(tc.total_seconds) if tc is not None else self.next_pts
        self.next_pts = frame.timestamp + (skip + 1) / self.fps
        return frame

    def face_data(self, frame: Frame, intra: bool) -> None:
        io, r = self.io, self.bits
        if intra:
            self.face = syntax.part_intra_header(io, None, FACE)
            frame.params.face = self.face
            self.faps.start_intra(self.face)
            self.viseme.start_intra(self.face.quant)
            self.expression.start_intra(self.face.quant)
        elif self.face is None:
            raise FbaError(no_intra("face"), r.pos)
        mask = self.face.mask
        for fap, coder, out, raw_bits in ((0, self.viseme, frame.viseme, ("viseme_def",)),
                                          (1, self.expression, frame.expression, ("init_face", "expression_def"))):
            if mask[fap]:
                pos = r.pos
                values = coder.decode(self.segment(coder.models(intra), not intra), intra)
                self.decoded(("viseme", "expression")[fap], coder, values)
                coder.check_selects(values, pos, frame.index)
                out[:len(values)] = values
                for j, name in enumerate(raw_bits):
                    out[len(values) + j] = io.u(1, 0, name)
        values = self.faps.decode(self.segment(self.faps.models(intra), not intra), intra)
        self.decoded("face", self.faps, values)
        frame.fap_values[self.faps.idx] = values
        frame.fap_mask[:] = mask

    def body_data(self, frame: Frame, intra: bool) -> None:
        r = self.bits
        frame.bap_mask, frame.bap_values = np.zeros(N_BAPS, dtype=bool), np.zeros(N_BAPS, dtype=np.int32)
        if intra:
            self.body = syntax.part_intra_header(self.io, None, BODY)
            frame.params.body = self.body
            self.baps.start_intra(self.body)
        elif self.body is None:
            raise FbaError(no_intra("body"), r.pos)
        values = self.baps.decode(self.segment(self.baps.models(intra), not intra), intra)
        self.decoded("body", self.baps, values)
        frame.bap_values[self.baps.idx] = values
        frame.bap_mask[:] = self.body.mask


def _guarded(decoder: _Decoder) -> Iterator:
    """The decoder's items, with any stray low-level exception turned into an FbaError."""
    try:
        yield from decoder.items()
    except FbaError:
        raise
    except (IndexError, ValueError, OverflowError, MemoryError) as exc:  # a guard, not an expected path
        raise FbaError(f"malformed stream ({type(exc).__name__}: {exc})", decoder.bits.pos) from exc
