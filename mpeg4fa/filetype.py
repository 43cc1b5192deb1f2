"""What a file is, from its first bytes: the one table of magic numbers every reader consults.

A reader that is handed the wrong kind of file (a JPEG renamed ``talk.fba``, a PNG given as
points JSON, an MP4 given as a WAV) should say what the file is, not what its own parser tripped
on. :func:`foreign_kind` names the common formats by their signature; readers call
:func:`refuse_foreign` with the kind they expect. The module sits at the bottom of the package
(it imports nothing of it), so every layer, the codec included, can use it.
"""
from __future__ import annotations

from typing import Callable

__all__ = ["SIGNATURES", "foreign_kind", "head_hex", "refuse_foreign", "HEAD_BYTES"]

HEAD_BYTES = 16
"""Bytes of a file's start that are enough to tell every kind below."""

SIGNATURES: tuple[tuple[int, bytes, str], ...] = (
    (0, b"\xff\xd8\xff", "a JPEG image"),
    (0, b"\x89PNG\r\n\x1a\n", "a PNG image"),
    (0, b"\x89FDP\r\n\x1a\n", "a binary FDP"),
    (0, b"GIF87a", "a GIF image"),
    (0, b"GIF89a", "a GIF image"),
    (0, b"II*\x00", "a TIFF image"),
    (0, b"MM\x00*", "a TIFF image"),
    (0, b"glTF", "a GLB (binary glTF) model"),
    (0, b"PK\x03\x04", "a ZIP archive"),
    (0, b"PK\x05\x06", "a ZIP archive (empty)"),
    (0, b"\x1f\x8b", "a gzip-compressed file"),
    (0, b"\xfd7zXZ\x00", "an xz-compressed file"),
    (0, b"7z\xbc\xaf\x27\x1c", "a 7-Zip archive"),
    (0, b"%PDF", "a PDF document"),
    (0, b"\x7fELF", "an executable (ELF)"),
    (0, b"OggS", "an Ogg audio file"),
    (0, b"fLaC", "a FLAC audio file"),
    (0, b"ID3", "an MP3 audio file"),
    (0, b"\x1aE\xdf\xa3", "a Matroska/WebM video"),
    (4, b"ftyp", "an MP4/QuickTime file"),
    (0, b"\xff\xfe", "UTF-16 text"),
    (0, b"\xfe\xff", "UTF-16 text"),
    (0, b"\x00\x00\x01\xba", "an FBA stream"),
    (0, b"\x00\x00\x01\x01", "an FBA stream"),
)
"""(offset, bytes, what it is). RIFF files are told apart by their form type, and MPEG audio without an
ID3 tag by its frame sync (:func:`foreign_kind`)."""

_RIFF_FORMS = {b"WAVE": "a WAV audio file", b"AVI ": "an AVI video", b"WEBP": "a WebP image"}


def foreign_kind(head: bytes) -> str | None:
    """What ``head`` (a file's first :data:`HEAD_BYTES` or more) says the file is, e.g. ``"a JPEG image"``;
    None when no signature matches (text, or a format not listed)."""
    if head[:4] in (b"RIFF", b"RIFX", b"RF64"):
        return _RIFF_FORMS.get(head[8:12], "a RIFF file")
    for offset, magic, kind in SIGNATURES:
        if head[offset:offset + len(magic)] == magic:
            return kind
    if len(head) >= 2 and head[0] == 0xFF and head[1] & 0xF6 == 0xF0:  # MPEG audio frame sync, layer bits 00
        return "an AAC (ADTS) audio file"
    if len(head) >= 2 and head[0] == 0xFF and head[1] & 0xE0 == 0xE0 and head[1] & 0x06:
        return "an MP3 audio file"
    return None


def head_hex(head: bytes, n: int = 4) -> str:
    """The first ``n`` bytes as ``0xFFD8FFE0``, the form the messages quote."""
    return "0x" + head[:n].hex().upper()


def refuse_foreign(head: bytes, expected: str, fail: Callable[[str, str], Exception],
                   allowed: tuple[str, ...] = ()) -> None:
    """Raise ``fail(problem, hint)`` when ``head`` is a known kind other than ``expected`` (and not in ``allowed``).

    ``problem`` reads ``"not EXPECTED: starts with 0xFFD8FFE0 (a JPEG image)"``, as the decoder's message does.
    """
    kind = foreign_kind(head)
    if kind is None or kind in allowed:
        return
    raise fail(f"not {expected}: starts with {head_hex(head)} ({kind})",
               "a file's content, not its name, says what it is")
