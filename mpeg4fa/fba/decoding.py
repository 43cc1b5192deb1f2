"""decode() and iter_decode(): the decoder chosen by backend, frames stacked in bounded memory.

This module sits above both decoders (:mod:`.decoder`, the reference, and :mod:`.fastpath`, which
builds on it), so that neither imports the other back. :func:`decode` holds the stream's arrays only,
each as narrow as its values allow (:mod:`.stacking`: 228 bytes a frame for a face stream of small
values, 364 when FAP values need int32; the peak adds a few MB) and refuses a stream of more than
:data:`~mpeg4fa.fba.limits.MAX_DECODE_FRAMES` frames, which :func:`iter_decode` reads frame by frame in
constant memory.
"""
from __future__ import annotations

import os
import stat
from typing import Iterator

from .bits import BitReader
from .decoder import Source, _Decoder, _guarded, _opened
from .errors import FbaError
from .limits import MAX_DECODE_FRAMES
from .stacking import StreamBuilder
from .stream import FapStream, Frame


def _size(src) -> int | None:
    """Bytes left in ``src`` when known (bytes, a regular file), else None: what ``auto`` weighs
    (:data:`~mpeg4fa.fba.compiled.SMALL_STREAM`)."""
    if isinstance(src, (bytes, bytearray, memoryview)):
        return len(src)
    try:
        status = os.fstat(src.fileno())
        return status.st_size - src.tell() if stat.S_ISREG(status.st_mode) else None
    except (AttributeError, OSError, ValueError):  # no file number (BytesIO, a socket's file), closed...
        return None


def _decoder(reader: BitReader, backend: str, size: int | None = None) -> _Decoder:
    from .compiled import use_compiled

    if use_compiled(backend, size):
        from .fastpath import FastDecoder  # numba only when the compiled path is taken

        return FastDecoder(reader)
    return _Decoder(reader)


def iter_decode(source: Source, *, backend: str = "auto") -> Iterator[Frame]:
    """Decode frame by frame without holding the whole stream; raises :class:`FbaError` at a fault.

    ``backend``: ``"auto"`` (compiled when numba is there and the stream is not known to be under
    :data:`~mpeg4fa.fba.compiled.SMALL_STREAM` bytes, see :mod:`mpeg4fa.fba.compiled`),
    ``"compiled"`` or ``"python"`` (the reference); both give the same frames and the same errors.
    """
    with _opened(source) as src:
        for item in _guarded(_decoder(BitReader(src), backend, _size(src))):
            if isinstance(item, Frame):
                yield item
            else:
                yield from item.frames()


def decode(source: Source, *, backend: str = "auto", max_frames: int = MAX_DECODE_FRAMES) -> FapStream:
    """Decode a whole FBA stream (bytes, a path or a binary file) into a :class:`FapStream`.

    On a fault the :class:`FbaError` carries the frames decoded before it in ``.partial``.
    Memory is that of the stream's arrays (:mod:`mpeg4fa.fba.stacking`), at the peak too (plus a few
    MB): 228 bytes a frame for a face stream of small values, 364 when its FAP values need int32; a
    stream without body data shares one read-only zero row for its ``bap_mask``/``bap_values``.
    Integer arrays come back as narrow as their values allow (``fap_values`` int16 or int32, see
    :data:`~mpeg4fa.fba.stream.STORAGE`): widen before arithmetic that may overflow, and call
    :meth:`~mpeg4fa.fba.FapStream.widen` before writing larger values into the stream. More than
    ``max_frames`` frames (default :data:`~mpeg4fa.fba.limits.MAX_DECODE_FRAMES`) is an
    :class:`FbaError` at the first frame past it:
    :func:`iter_decode` reads such a stream in constant memory. ``backend`` as for :func:`iter_decode`.
    """
    with _opened(source) as src:
        decoder = _decoder(BitReader(src), backend, _size(src))
        builder = StreamBuilder()
        try:
            for item in _guarded(decoder):
                if isinstance(item, Frame):
                    builder.append(item)
                else:
                    builder.extend(item.arrays, item.bap_mask, item.bap_values)
                if len(builder) > max_frames:
                    raise FbaError(f"the stream holds more than {max_frames:,} frames, more than decode() holds "
                                   "in memory", decoder.bits.pos, frame=max_frames,
                                   hint="iter_decode() reads it frame by frame; or split the stream")
        except FbaError as exc:
            builder.object_start_code = decoder.object_start_code
            exc.partial = builder.build()
            raise
    builder.object_start_code = decoder.object_start_code
    return builder.build()
