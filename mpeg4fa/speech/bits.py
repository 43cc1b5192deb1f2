"""The bits pass: frames -> one FBA stream, written block by block as the frames come.

Why blocks: the planner and the writer (:mod:`mpeg4fa.fba.encoder`) take a whole
:class:`~mpeg4fa.fba.stream.FapStream`, and a long text's frames must not be held at once. So
frames are coded in blocks of about :data:`BLOCK_SECONDS` (at most :data:`BLOCK_FRAMES`), each planned and written as a stream of
its own, starting with an intra frame behind a plane start code, and the blocks' bits are joined
into one stream: the first block keeps its object start code, every block drops its end code
and the stuffing before its plane start code (the block before ends with the same stuffing),
and the stream gets one end code. A decoder reads it as one stream that has an intra frame every
block; a text that fits in one block gets exactly the bytes it always got.

It decodes to the values one stream of all the frames would give: what a decoder holds across a
block boundary is kept by :class:`~mpeg4fa.speech.encoder.StreamBuilder`, and an intra frame,
which quantises a value on its own, could land one quantiser step away from where the
predicted frame of one stream lands (a value halfway between two steps rounds toward zero on its
own and away from the step the decoder holds when predicted). So the block's first frame sends,
for each low-level FAP, the value the one stream's prediction reconstructs there
(:class:`_Reconstruction`), which the intra frame quantises exactly.
"""
from __future__ import annotations

import struct
from collections.abc import Callable

import numpy as np

from mpeg4fa.fba import EncodeOptions
from mpeg4fa.fba.encoder import plan, write
from mpeg4fa.fba.limits import frame_limit, span_hint
from mpeg4fa.fba.params import FACE, dequantise, quantise
from mpeg4fa.fba.stream import END_CODE, PLANE_START_CODE, FapStream
from mpeg4fa.spec import N_FAPS
from mpeg4fa.speech.errors import MarkupError
from mpeg4fa.speech.frames import FrameBlock, join_blocks

BLOCK_SECONDS = 60.0
"""Seconds of frames coded as one block: each starts with an intra frame (some hundred bits)."""
BLOCK_FRAMES = 1500
"""Most frames in a block (60 s at 25 fps): the planner's search over a block (FAP 1/2 fields,
:mod:`mpeg4fa.speech.compact`) keeps some state per frame, so at high frame rates blocks are shorter."""


def block_frames(fps: float, intra_period: int | None = None) -> int:
    """Frames per block at ``fps``: :data:`BLOCK_SECONDS` of them, at most :data:`BLOCK_FRAMES`, a whole
    number of intra periods."""
    n = max(1, min(int(round(BLOCK_SECONDS * fps)), BLOCK_FRAMES))
    if intra_period:
        n = -(-n // intra_period) * intra_period
    return n


class _Reconstruction:
    """The low-level FAP values a decoder reconstructs along one stream of all the frames (its
    closed-loop prediction), followed frame by frame so that a block's intra frame can match it."""

    def __init__(self, options: EncodeOptions) -> None:
        quant = options.fap_quant if options.fap_quant is not None else 1
        self.qstep = np.zeros(N_FAPS, dtype=np.int64)
        self.qstep[2:] = FACE.quant_step[2:] * FACE.step_multiplier(quant)
        self.period = options.intra_period or 0
        self.recon = np.zeros(N_FAPS, dtype=np.int64)
        self.frames = 0

    def follow(self, values: np.ndarray) -> None:
        """The frames ``values`` (rows) coded after those followed so far."""
        q, recon = self.qstep, self.recon
        for row in np.asarray(values, dtype=np.int64):
            if self.frames == 0 or (self.period and self.frames % self.period == 0):  # intra in one stream too
                recon = dequantise(quantise(row, q), q)
            else:
                recon = recon + dequantise(quantise(row - recon, q), q)
            self.frames += 1
        self.recon = recon

    def next_intra(self, row: np.ndarray) -> np.ndarray:
        """What the next frame, ``row``, reconstructs to in one stream: the values its intra frame sends."""
        if self.frames == 0 or (self.period and self.frames % self.period == 0):
            return np.asarray(row).copy()
        q = self.qstep
        guess = self.recon + dequantise(quantise(np.asarray(row, dtype=np.int64) - self.recon, q), q)
        return np.where(q > 0, guess, row)


class FbaBlocks:
    """Frame blocks in, one FBA stream out to ``handle`` (see the module docstring).

    ``build`` turns a :class:`~mpeg4fa.speech.frames.FrameBlock` into the block's FapStream
    (:meth:`~mpeg4fa.speech.encoder.StreamBuilder.build`); ``options`` code it. ``place`` gives the
    (source, line, column) of the text being spoken, for the error when the speech outgrows what one
    stream may span (:data:`~mpeg4fa.fba.limits.MAX_SPAN_SECONDS`).
    """

    def __init__(self, handle, build: Callable[[FrameBlock], FapStream], options: EncodeOptions, fps: float,
                 place: Callable[[], tuple[str, int, int]] = lambda: ("<text>", 1, 1)) -> None:
        self.handle, self.build, self.options, self.fps, self.place = handle, build, options, fps, place
        self.size = block_frames(fps, options.intra_period)
        self.limit = frame_limit(fps)
        self.pending: list[FrameBlock] = []
        self.buffered = 0
        self.frames = 0
        self.blocks = 0
        self.bytes = 0
        self.recon = _Reconstruction(options)

    def add(self, block: FrameBlock | None) -> None:
        """Frames that follow those added before; coded as soon as a block's worth has come."""
        if block is None or not len(block):
            return
        self.pending.append(block)
        self.buffered += len(block)
        while self.buffered >= 2 * self.size:  # keep the last block back: the text's end joins it
            self._code(self.size)

    def finish(self) -> None:
        """Code what is left and end the stream."""
        while self.buffered > 2 * self.size:
            self._code(self.size)
        if self.buffered:
            self._code(self.buffered)
        self._put(struct.pack(">I", END_CODE))

    def _take(self, n: int) -> FrameBlock:
        whole = join_blocks(self.pending)
        head, rest = _split(whole, n)
        self.pending = [rest] if len(rest) else []
        self.buffered -= n
        return head

    def _code(self, n: int) -> None:
        block = self._take(n)
        if self.frames + n > self.limit:
            source, line, column = self.place()
            raise MarkupError(f"the speech runs past {self.limit:,} frames ({self.limit / self.fps / 3600:.3g} h at "
                              f"{self.fps:g} fps) here, more than one stream may span", line, column,
                              span_hint(self.fps), source)
        stream = self.build(block)
        if self.blocks:
            first = self.recon.next_intra(stream.fap_values[0])
            stream.fap_values[0] = np.where(stream.fap_mask[0], first, stream.fap_values[0])
        self.recon.follow(block.values)
        planned = plan(stream, self.options)
        if self.blocks:
            planned.start_code[0] = PLANE_START_CODE
        data = write(planned)
        self._put(data[:-4] if not self.blocks else data[5:-4])  # see the module docstring
        self.frames += n
        self.blocks += 1

    def _put(self, data: bytes) -> None:
        self.handle.write(data)
        self.bytes += len(data)


def _split(block: FrameBlock, n: int) -> tuple[FrameBlock, FrameBlock]:
    """The first ``n`` frames of ``block`` and the rest."""
    from mpeg4fa.speech.timeline import ExpressionFields, VisemeFields

    def cut(part: slice) -> FrameBlock:
        vis = exp = None
        if block.visemes is not None:
            vis = VisemeFields(block.visemes.select1[part], block.visemes.select2[part], block.visemes.blend[part])
            e = block.expressions
            exp = ExpressionFields(e.select1[part], e.intensity1[part], e.select2[part], e.intensity2[part])
        first = block.first + (part.start or 0)
        return FrameBlock(first, block.times[part], block.values[part], vis, exp)

    return cut(slice(0, n)), cut(slice(n, None))
