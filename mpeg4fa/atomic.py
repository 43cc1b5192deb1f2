"""Outputs that appear whole or not at all: write beside the target under a temporary name, rename when done.

Why: a command that fails or is interrupted half-way must leave neither a truncated
file (a 0-byte MP4, half a stream, a WAV without its header) nor half a folder of
frames under the name asked for, and must not have replaced a good file with a
broken one. The temporary lies in the target's own folder, so the final rename
stays on one file system and is atomic.

Any layer may use :func:`atomic_output` (one file or folder) and :func:`atomic_outputs` (several files that
belong together); the module depends on nothing else in the package.
"""
from __future__ import annotations

import contextlib
import errno
import os
import secrets
import shutil
import stat
from pathlib import Path
from typing import Iterator

PARTIAL_MARK = ".partial-"
"""What every temporary's name holds: ``.NAME.partial-XXXXXXXX`` (+ the target's suffix)."""
_STEM_MAX = 100  # keeps the temporary's name under the file system's name limit
_ERROR_TEXT = ("where", "message", "hint", "filename", "filename2", "source")


def partial_path(target: Path) -> Path:
    """A fresh hidden name beside ``target``, keeping its suffix (writers that pick a format by suffix see it)."""
    name = target.name or "output"
    suffix = Path(name).suffix
    stem = name[: len(name) - len(suffix)][:_STEM_MAX]
    while True:
        candidate = target.parent / f".{stem}{PARTIAL_MARK}{secrets.token_hex(4)}{suffix}"
        if not os.path.lexists(candidate):
            return candidate


@contextlib.contextmanager
def atomic_output(path: str | os.PathLike, *, directory: bool = False) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it becomes ``path``, on any exception it is removed.

    The block creates the file (or, with ``directory=True``, the folder) at the yielded
    path; nothing is created before. A folder replaces a missing target; into an existing
    folder its files are moved one by one (other files there are left alone). A symbolic
    link keeps pointing at its file, which is replaced. A target that is a device or a
    pipe (``/dev/stdout``) cannot be replaced and is written directly. Errors raised in the
    block name ``path``, not the temporary. KeyboardInterrupt removes the temporary too.
    """
    target = Path(path)
    if os.path.islink(target):
        target = Path(os.path.realpath(target))
    kind = _kind(target)
    if kind == "other":  # a device, pipe or socket: nothing to rename onto
        yield target
        return
    if kind == "dir" and not directory:
        raise IsADirectoryError(errno.EISDIR, os.strerror(errno.EISDIR), str(path))
    if kind == "file" and directory:
        raise NotADirectoryError(errno.ENOTDIR, "exists and is not a directory", str(path))
    partial = partial_path(target)
    try:
        yield partial
        _finish(partial, target)
    except BaseException as exc:
        _remove(partial)
        _rename_in_error(exc, str(partial), str(path))
        raise


def _kind(path: Path) -> str | None:
    try:
        mode = os.stat(path).st_mode
    except OSError:  # missing (or unreadable: the write will say so)
        return None
    if stat.S_ISDIR(mode):
        return "dir"
    return "file" if stat.S_ISREG(mode) else "other"


def _finish(partial: Path, target: Path) -> None:
    """Put the finished temporary in place (nothing to do when the block wrote nothing)."""
    if not os.path.lexists(partial):
        return
    if partial.is_dir() and target.is_dir():
        for entry in sorted(partial.iterdir()):
            os.replace(entry, target / entry.name)
        partial.rmdir()
    else:
        os.replace(partial, target)


def _remove(partial: Path) -> None:
    """Remove what the block left at the temporary name; a failure here must not hide the first error."""
    try:
        if partial.is_dir() and not partial.is_symlink():
            shutil.rmtree(partial, ignore_errors=True)
        elif os.path.lexists(partial):
            partial.unlink()
    except OSError:
        pass


def _rename_in_error(exc: BaseException, partial: str, target: str) -> None:
    """Errors name the file the caller asked for: the temporary's name is replaced in their text fields."""
    for attr in _ERROR_TEXT:
        value = getattr(exc, attr, None)
        if isinstance(value, str) and partial in value:
            try:
                setattr(exc, attr, value.replace(partial, target))
            except (AttributeError, TypeError):  # a computed property: leave it
                pass
    if exc.args and isinstance(exc.args[0], str) and partial in exc.args[0]:
        exc.args = (exc.args[0].replace(partial, target), *exc.args[1:])


@contextlib.contextmanager
def atomic_outputs(*paths: str | os.PathLike | None) -> Iterator[list[Path | None]]:
    """:func:`atomic_output` for several files at once: all are put in place when the block succeeds, none if not.

    None entries stay None (an output not asked for).
    """
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(atomic_output(p)) if p is not None else None for p in paths]
