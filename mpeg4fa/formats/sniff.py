"""Open a stream file of any kind: binary FBA (.fba), text FAP (.fap) or text BAP (.bap)."""
from __future__ import annotations

import os
from pathlib import Path

from ..fba import FapStream, decode
from ..filetype import refuse_foreign
from ..fba.bits import START_CODE_PREFIX
from .bap_text import SUPPORTED_VERSIONS as BAP_VERSIONS
from .bap_text import read_bap
from .errors import FormatError
from .fap_text import read_fap

_TEXT_PEEK = 1 << 16
"""Bytes of a text file looked at for its header line (comments before it included)."""


def sniff(path: str | os.PathLike) -> str:
    """'fba' when the file starts with a start code prefix; for text, 'bap' when the header line's version
    is a .bap one (3.1, 3.2), else 'fap' (whose reader then says what is wrong).

    The one place a stream file's kind is told (every command reads streams through it): a file that
    starts with another format's signature (JPEG, PNG, WAV, MP4, ZIP/GLB, gzip, PDF...,
    :mod:`mpeg4fa.filetype`) is a :class:`FormatError` that names the format and the bytes, as the
    decoder does. A missing or unreadable path (a directory) is a :class:`FormatError` naming it.
    """
    try:
        with open(path, "rb") as fh:
            head = fh.read(_TEXT_PEEK)
    except OSError as exc:
        raise FormatError.from_os_error(os.fsdecode(path), exc) from None
    if len(head) >= 4 and int.from_bytes(head[:3], "big") == START_CODE_PREFIX:
        return "fba"
    name = os.fsdecode(path)
    refuse_foreign(head, "an FBA stream or a .fap/.bap text file",
                   lambda problem, hint: FormatError.no_place(name, problem, hint), allowed=("UTF-16 text",))
    return "bap" if _text_version(head) in BAP_VERSIONS else "fap"


def _text_version(head: bytes) -> str | None:
    """First field of the first line that is neither blank nor a ``#`` comment (None when there is none)."""
    for raw in head.removeprefix(b"\xef\xbb\xbf").splitlines():
        fields = raw.split()
        if fields and not fields[0].startswith(b"#"):
            return fields[0].decode("ascii", "replace")
    return None


def read_stream(path: str | os.PathLike) -> tuple[FapStream, str]:
    """Read a .fba, .fap or .bap file (chosen by content, not by name); return the stream and its kind."""
    kind = sniff(path)
    readers = {"fba": lambda: decode(Path(path)), "bap": lambda: read_bap(path), "fap": lambda: read_fap(path)}
    return readers[kind](), kind
