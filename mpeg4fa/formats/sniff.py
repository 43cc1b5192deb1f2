"""Open a stream file of either kind: binary FBA (.fba) or text FAP (.fap)."""
from __future__ import annotations

import os
from pathlib import Path

from ..fba import FapStream, decode
from ..fba.bits import START_CODE_PREFIX
from .fap_text import read_fap


def sniff(path: str | os.PathLike) -> str:
    """'fba' when the file starts with a start code prefix, else 'fap' (text)."""
    with open(path, "rb") as fh:
        head = fh.read(4)
    return "fba" if len(head) == 4 and int.from_bytes(head[:3], "big") == START_CODE_PREFIX else "fap"


def read_stream(path: str | os.PathLike) -> tuple[FapStream, str]:
    """Read a .fba or .fap file (chosen by content, not by name); return the stream and its kind."""
    kind = sniff(path)
    stream = decode(Path(path)) if kind == "fba" else read_fap(path)
    return stream, kind
