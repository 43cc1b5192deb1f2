"""The codec's compiled path: the arithmetic coder and the P-plane syntax under numba.

The pure-Python modules of :mod:`mpeg4fa.fba` stay the reference: they are what the syntax
description (``spec/SYNTAX.md``) is checked against, and what runs where numba cannot. This
package does the same work on flat arrays, compiled to machine code on first use and cached on
disk (``numba`` ``cache=True``), and the tests decode every vector both ways and compare.

``MPEG4FA_CODEC=python`` in the environment forces the reference path; ``available()`` says
whether the compiled one can run here, and ``why_not()`` why not.
"""
from __future__ import annotations

import os

try:  # numba installs from wheels; a platform without them still decodes, on the reference path
    import numba as _numba
except ImportError as exc:  # pragma: no cover - depends on the platform
    _numba = None
    _IMPORT_ERROR = f"numba is not installed ({exc})"
else:
    _IMPORT_ERROR = ""

ENV = "MPEG4FA_CODEC"
"""Environment variable: ``python`` forces the reference path, ``compiled`` requires the compiled one."""


def why_not() -> str:
    """Why the compiled path is off ('' when it is on)."""
    if os.environ.get(ENV, "").strip().lower() == "python":
        return f"{ENV}=python"
    return _IMPORT_ERROR


def available() -> bool:
    """Whether decode/encode use the compiled path."""
    return not why_not()


BACKENDS = ("auto", "compiled", "python")


def use_compiled(backend: str = "auto") -> bool:
    """Whether to take the compiled path for ``backend`` (auto: when available); ``compiled`` where it
    cannot run is an error that says why."""
    if backend not in BACKENDS:
        raise ValueError(f"backend {backend!r} is not one of {', '.join(BACKENDS)}")
    if backend == "python":
        return False
    if backend == "compiled" and not available():
        from mpeg4fa.fba.errors import FbaError

        raise FbaError(f"the compiled codec cannot run here: {why_not()}",
                       hint="install numba (pip install numba), or use backend='python'")
    return available()


def jit(fn):
    """Compile ``fn`` with numba in nopython mode, cached on disk; the plain function without numba."""
    if _numba is None:  # pragma: no cover
        return fn
    return _numba.njit(cache=True, nogil=True)(fn)
