"""Reading an image file (a texture, a photo) for the renderer: one RGB array or one located error.

Bounded before decoding: the header's size is checked against :data:`MAX_PIXELS` (64 Mpx, e.g.
8192 x 8192) before any pixel is decoded, so a decompression bomb (a small file that says
50,000 x 50,000) is refused at once; a truncated or damaged image, a file of another kind (a PDF, text,
a WAV: named by :mod:`mpeg4fa.filetype`) and every decoder fault of Pillow are one :class:`RenderError`
naming the file and what it was for.
"""
from __future__ import annotations

import io
import os
import struct
import warnings

import numpy as np

from mpeg4fa.filetype import HEAD_BYTES, foreign_kind, head_hex
from mpeg4fa.render.errors import RenderError

MAX_PIXELS = 1 << 26
"""Largest image read (67,108,864 pixels: 8192 x 8192); decoding it takes up to ~450 MB (~520 MB from a palette)."""
MAX_SIDE = 1 << 14
"""Longest side read (16,384 pixels): a photo or texture is never a 16 x 4,000,000 strip."""

_IMAGE_KINDS = ("a JPEG image", "a PNG image", "a GIF image", "a TIFF image", "a WebP image")


def read_image(path: str | os.PathLike | bytes, what: str, where: str | None = None, *,
               turn: bool = False) -> np.ndarray:
    """An image file (or its bytes, e.g. an FDP's texture) as (H, W, 3) uint8 RGB; RenderError naming the
    file, or ``where``, and ``what`` it was for otherwise. ``turn``: a photo, turned upright by its EXIF
    orientation (:func:`image_rgb`)."""
    from PIL import Image, UnidentifiedImageError

    if isinstance(path, (bytes, bytearray, memoryview)):
        source: str | os.PathLike | io.BytesIO = io.BytesIO(bytes(path))
        where = where or "<image bytes>"
    else:
        source, where = path, where or os.fsdecode(path)
    try:
        _check_png_chunks(source, what, where)
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            warnings.simplefilter("error", Image.DecompressionBombWarning)
            with Image.open(source) as img:
                width, height = img.size
                if width * height > MAX_PIXELS or max(width, height) > MAX_SIDE:
                    raise RenderError(f"the {what} is {width:,} x {height:,} pixels, more than the "
                                      f"{MAX_PIXELS:,} pixels or {MAX_SIDE:,} a side read", where=where, hint="scale the image down to 8192 x 8192 or less")
                if width == 0 or height == 0:
                    raise RenderError(f"the {what} has no pixels ({width} x {height})", where=where)
                kind = img.format
                pixels = image_rgb(img, turn=turn)
        _pillow_warnings(caught, kind, what, where)
        return pixels
    except FileNotFoundError:
        raise RenderError(f"no such {what}", where=where) from None
    except IsADirectoryError:
        raise RenderError(f"the {what} is a directory, not a file", where=where, hint="name an image file") from None
    except UnidentifiedImageError:
        raise RenderError(f"cannot read the {what}: {_not_an_image(source)}", where=where,
                          hint="give a PNG or JPEG image") from None
    except (Image.DecompressionBombError, Image.DecompressionBombWarning) as exc:
        raise RenderError(f"the {what} has more than the {MAX_PIXELS:,} pixels read ({exc})", where=where,
                          hint="scale the image down to 8192 x 8192 or less") from None
    except MemoryError:  # a size the header checks let through (a huge chunk or profile) that memory cannot hold
        raise RenderError(f"cannot read the {what}: too large to decode in the memory available", where=where,
                          hint="scale the image down, or save it again as PNG") from None
    except (OSError, ValueError, SyntaxError, EOFError, struct.error, IndexError, TypeError,
            ZeroDivisionError) as exc:  # Pillow's decoders fail in all of these ways on damaged files
        raise RenderError(f"cannot read the {what}: damaged or truncated image ({str(exc) or type(exc).__name__})",
                          where=where, hint="open it in an image viewer, or save it again as PNG") from None


_PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _check_png_chunks(source: str | os.PathLike | io.BytesIO, what: str, where: str) -> None:
    """A PNG whose chunk claims more bytes than the file has (a 4 GB IDAT in 800 bytes) is refused from the
    chunk headers, naming the chunk and its byte offset, before Pillow allocates what it claims. Other files
    pass untouched; reading stops at IEND or at the end of the file (a chunk at a time: linear in the file)."""
    fh = source if isinstance(source, io.BytesIO) else open(source, "rb")
    try:
        size = fh.seek(0, io.SEEK_END)
        fh.seek(0)
        if fh.read(8) != _PNG_SIGNATURE:
            return
        pos = 8
        while pos + 8 <= size:
            head = fh.read(8)
            length, name = int.from_bytes(head[:4], "big"), head[4:8]
            if pos + 12 + length > size:
                shown = name.decode("latin-1") if name.isalpha() else "0x" + name.hex().upper()
                raise RenderError(f"cannot read the {what}: damaged or truncated PNG: chunk {shown} at byte {pos:,} "
                                  f"claims {length:,} bytes, but the file has {max(size - pos - 12, 0):,} after "
                                  "its header", where=where, hint="open it in an image viewer, or save it again as PNG")
            if name == b"IEND":
                return
            pos += 12 + length
            fh.seek(pos)
    finally:
        if fh is source:
            fh.seek(0)
        else:
            fh.close()


_STRUCTURE_WARNINGS = {"TIFF": "TiffImagePlugin"}
"""Formats whose own layout Pillow reads with the module that warns: there a warning (a tag skipped, a count
wrong) means the pixels may be read wrong, so it is the file's fault."""


def _pillow_warnings(caught: list[warnings.WarningMessage], kind: str | None, what: str, where: str) -> None:
    """Pillow's warnings while reading: an error where they concern the image's own layout (a TIFF's directory);
    silenced where they concern what is not read (EXIF of a JPEG, read for its DPI; an APNG's animation
    control, whose default image is what is used). Anyone else's warnings go on as they came."""
    for w in caught:
        module = os.path.basename(str(w.filename)).removesuffix(".py")
        if "PIL" not in str(w.filename):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
        elif _STRUCTURE_WARNINGS.get(kind or "") == module:
            raise RenderError(f"cannot read the {what}: damaged {kind} image ({str(w.message).strip()})", where=where,
                              hint="open it in an image viewer, or save it again as PNG")


_ORIENTATION = 0x0112
"""The EXIF tag saying how a camera's stored pixels turn to stand upright."""


def image_rgb(img, *, turn: bool = False) -> np.ndarray:
    """An open Pillow image's pixels as (H, W, 3) uint8 RGB, 16-bit grey scaled to 8 bits; with ``turn``, a photo
    a phone stored sideways is turned upright by its EXIF orientation (a copy, only when there is a turn to make).
    Photos of faces are turned (as people see them); textures are not: their coordinates name the stored pixels,
    as an FDP's receiver, which knows no EXIF, reads them. One rule for every reader of photos and textures."""
    if turn and img.getexif().get(_ORIENTATION, 1) != 1:
        from PIL import ImageOps

        img = ImageOps.exif_transpose(img)
    return _rgb(img)


def _rgb(img) -> np.ndarray:
    """(H, W, 3) uint8; a grey image repeated into three channels without Pillow's 4-byte RGB copy. A 16-bit grey
    image (modes I;16 and I, as Pillow opens a 16-bit PNG) is scaled to 8 bits: Pillow's own conversion clips it
    to 255, so a 16-bit photo came out all but white and no face was found in it."""
    if img.mode == "L":
        grey = np.asarray(img)
    elif img.mode.startswith("I"):
        grey = np.clip(np.asarray(img, dtype=np.float64) / 257.0, 0, 255).round().astype(np.uint8)
    elif img.mode == "F":
        grey = np.clip(np.nan_to_num(np.asarray(img, dtype=np.float64)), 0, 255).round().astype(np.uint8)
    else:
        return np.asarray(img.convert("RGB"))
    return np.repeat(grey[:, :, None], 3, axis=2)


def _not_an_image(source: str | os.PathLike | io.BytesIO) -> str:
    """What the file is instead, from its first bytes."""
    try:
        if isinstance(source, io.BytesIO):
            head = source.getvalue()[:HEAD_BYTES]
        else:
            with open(source, "rb") as fh:
                head = fh.read(HEAD_BYTES)
    except OSError:
        return "not an image file"
    if not head:
        return "the file is empty"
    kind = foreign_kind(head)
    if kind in _IMAGE_KINDS:
        return f"a damaged file: it starts as {kind}"
    if kind is not None:
        return f"not an image: it starts with {head_hex(head)} ({kind})"
    if all(b in b"\t\n\r" or 32 <= b < 127 for b in head):
        return "not an image: it is text"
    return f"not an image format Pillow knows (it starts with {head_hex(head)})"
