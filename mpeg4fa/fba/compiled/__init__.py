"""The codec's compiled path: the arithmetic coder and the P-plane syntax under numba.

The pure-Python modules of :mod:`mpeg4fa.fba` stay the reference: they are what the syntax
description (``spec/SYNTAX.md``) is checked against, and what runs where numba cannot. This
package does the same work on flat arrays, compiled to machine code on first use and cached on
disk (``numba`` ``cache=True``), and the tests decode every vector both ways and compare.

``MPEG4FA_CODEC=python`` in the environment forces the reference path; ``available()`` says
whether the compiled one can run here, and ``why_not()`` why not.

numba is imported the first time the compiled path is asked for, not with this package: loading it and
the cached kernels takes ~0.5 s and ~70 MB, more than the reference needs for a stream under
:data:`SMALL_STREAM` bytes, which ``auto`` therefore decodes on the reference path.
"""
from __future__ import annotations

import os
from types import ModuleType

_numba: ModuleType | None = None
_IMPORT_ERROR: str | None = None  # None: numba not tried yet

ENV = "MPEG4FA_CODEC"
"""Environment variable: ``python`` forces the reference path, ``compiled`` requires the compiled one."""

SMALL_STREAM = 16_384
"""Bytes below which ``auto`` decodes on the reference path: it reads 10-30 us a byte, so such a stream
takes under ~0.4 s, less than importing numba and loading its kernels (``mpeg4fa info`` of a small
stream in ~0.2 s and ~40 MB instead of ~1 s and ~170 MB)."""


def _load() -> ModuleType | None:
    """numba, imported once on first need (a platform without its wheels decodes on the reference path)."""
    global _numba, _IMPORT_ERROR
    if _IMPORT_ERROR is None:
        try:
            import numba
        except ImportError as exc:  # pragma: no cover - depends on the platform
            _IMPORT_ERROR = f"numba is not installed ({exc})"
        else:
            _numba, _IMPORT_ERROR = numba, ""
    return _numba


def why_not() -> str:
    """Why the compiled path is off ('' when it is on)."""
    if os.environ.get(ENV, "").strip().lower() == "python":
        return f"{ENV}=python"
    _load()
    return _IMPORT_ERROR or ""


def available() -> bool:
    """Whether decode/encode use the compiled path."""
    return not why_not()


BACKENDS = ("auto", "compiled", "python")


def use_compiled(backend: str = "auto", size: int | None = None) -> bool:
    """Whether to take the compiled path for ``backend`` (auto: when available, and for ``size`` bytes of
    input, when known, of at least :data:`SMALL_STREAM`); ``compiled`` where it cannot run is an error
    that says why."""
    if backend not in BACKENDS:
        raise ValueError(f"backend {backend!r} is not one of {', '.join(BACKENDS)}")
    if backend == "python" or (backend == "auto" and size is not None and size < SMALL_STREAM):
        return False
    if backend == "compiled" and not available():
        from mpeg4fa.fba.errors import FbaError

        raise FbaError(f"the compiled codec cannot run here: {why_not()}",
                       hint="install numba (pip install numba), or use backend='python'")
    if available():
        announce_compiling()
        return True
    return False


def jit(fn):
    """Compile ``fn`` with numba in nopython mode, cached on disk; the plain function without numba."""
    numba = _load()
    if numba is None:  # pragma: no cover
        return fn
    return numba.njit(cache=True, nogil=True)(fn)


def cached() -> bool:
    """Whether numba's disk cache holds machine code for the kernels (False: the first call compiles, ~10-20 s).

    All kernels live in one file, so an install or an upgrade leaves none cached: one cached kernel means
    the big compile is done (a command that then runs kernels no earlier one ran, such as the first long
    decode after a few encodes, still compiles those few, for a second or two, and :func:`warm_up` compiles
    them all). Reads numba's cache index through its internals; where they have moved, says True (nothing
    is announced rather than something wrong)."""
    if _load() is None:
        return True
    from . import kernels

    try:
        dispatchers = [v for v in vars(kernels).values() if hasattr(v, "_cache") and hasattr(v, "py_func")]
        return any(d._cache._cache_file._load_index() for d in dispatchers)
    except Exception:  # pragma: no cover - another numba's internals
        return True


def announce_compiling() -> None:
    """Tell the user (:func:`mpeg4fa.notices.note`) that the kernels compile now, when they are not cached:
    the first command after an install or an upgrade would otherwise sit silent for 10-20 s."""
    global _announced
    if _announced:
        return
    _announced = True
    from ...notices import note

    if available() and not cached():
        note("compiling the codec's numba kernels (first run only; they are cached on disk)...")


_announced = False


def warm_up() -> None:
    """Compile the kernels that encoding and decoding run (or load them from the disk cache): what
    ``tools/dev.sh`` runs after installing, so that no command waits for it."""
    from ..decoding import decode
    from ..encoder import EncodeOptions, encode
    from ..samples import demo_stream

    if not available():
        return
    stream = demo_stream()
    for options in (EncodeOptions(fap_quant=1), EncodeOptions(optimize=True, fap_quant=3)):
        decode(encode(stream, options, backend="compiled"), backend="compiled")
