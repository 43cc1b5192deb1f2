"""Refusing a command line that would overwrite what it reads, or write two outputs to one file.

Why: ``decode x.fba -o x.fba`` would replace the stream with its text and ``encode ... --audio``
naming the ``-o`` file would put a WAV where the stream was; the user loses data and the
command says it succeeded. Paths are compared after resolving links and ``..`` (and by
``os.path.samefile`` where both exist, which also catches hard links).
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Mapping

from .errors import UsageError

Named = Mapping[str, "str | os.PathLike | None"]
"""Option label (``-o``, ``--audio``, ``INPUT``) -> path; None entries are left out."""


def same_file(a: str | os.PathLike, b: str | os.PathLike) -> bool:
    """Whether two paths name one file (resolved paths equal, or the same inode where both exist)."""
    if os.path.realpath(a) == os.path.realpath(b):
        return True
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return False


def refuse_overlaps(inputs: Named, outputs: Named) -> None:
    """UsageError naming both when an output is another output or one of the inputs."""
    outs = [(label, Path(path)) for label, path in outputs.items() if path is not None]
    ins = [(label, Path(path)) for label, path in inputs.items() if path is not None]
    for i, (label, path) in enumerate(outs):
        for other, other_path in outs[:i]:
            if same_file(path, other_path):
                raise UsageError(f"{label} {path} and {other} {other_path} are the same file",
                                 hint="give each output its own name")
        for source, source_path in ins:
            if same_file(path, source_path):
                raise UsageError(f"{label} {path} is the {source} {source_path}: it would be overwritten",
                                 hint="write the output to another file")
