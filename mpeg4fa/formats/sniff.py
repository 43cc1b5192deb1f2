"""Open a stream file of either kind: binary FBA (.fba) or text FAP (.fap)."""
from __future__ import annotations

import os
from pathlib import Path

from ..fba import FapStream, decode
from ..fba.bits import START_CODE_PREFIX
from .errors import FormatError
from .fap_text import read_fap


def sniff(path: str | os.PathLike) -> str:
    """'fba' when the file starts with a start code prefix, else 'fap' (text).

    A missing or unreadable path (a directory) is a :class:`FormatError` naming it.
    """
    try:
        with open(path, "rb") as fh:
            head = fh.read(4)
    except OSError as exc:
        raise FormatError.from_os_error(os.fsdecode(path), exc) from None
    return "fba" if len(head) == 4 and int.from_bytes(head[:3], "big") == START_CODE_PREFIX else "fap"


def read_stream(path: str | os.PathLike) -> tuple[FapStream, str]:
    """Read a .fba or .fap file (chosen by content, not by name); return the stream and its kind."""
    kind = sniff(path)
    stream = decode(Path(path)) if kind == "fba" else read_fap(path)
    return stream, kind
