"""Outputs that appear whole or not at all: write beside the target under a temporary name, rename when done.

Why: a command that fails or is interrupted half-way must leave neither a truncated
file (a 0-byte MP4, half a stream, a WAV without its header) nor half a folder of
frames under the name asked for, and must not have replaced a good file with a
broken one. The temporary lies in the target's own folder, so the final rename
stays on one file system and is atomic.

Any layer may use :func:`atomic_output` (one file or folder) and :func:`atomic_outputs` (several files that
belong together); the module depends on nothing else in the package.

Signals: Ctrl-C raises KeyboardInterrupt, which unwinds every ``atomic_output`` and removes its
temporary. SIGTERM and SIGHUP (what ``timeout``, ``kill`` and a closed terminal send) kill a Python
process at once by default, leaving ``.NAME.partial-XXXX`` files behind. :func:`clean_up_on_signals`
makes them raise :class:`Terminated` instead, a KeyboardInterrupt, so they clean up as Ctrl-C does.
The ``mpeg4fa`` command installs it for every subcommand; a program that calls the library and
wants the same wraps its work in ``with clean_up_on_signals(): ...``.
"""
from __future__ import annotations

import contextlib
import errno
import os
import secrets
import shutil
import signal
import stat
import threading
from pathlib import Path
from typing import Any, Callable, Iterator

PARTIAL_MARK = ".partial-"
"""What every temporary's name holds: ``.NAME.partial-XXXXXXXX`` (+ the target's suffix)."""
_STEM_MAX = 100  # keeps the temporary's name under the file system's name limit
_ERROR_TEXT = ("where", "message", "hint", "filename", "filename2", "source", "path", "problem")


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
        try:
            yield target
        except OSError as exc:  # /dev/full: the error still says which output
            _name_output(exc, str(path))
            raise
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
        if isinstance(exc, OSError):
            _name_output(exc, str(path))
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


_OUTPUT_ATTR = "_mpeg4fa_output"


def _name_output(exc: OSError, target: str) -> None:
    """Mark an OS error raised while writing ``target``; one that names no file (a ``write()`` on a full
    disk: ENOSPC, EIO, EDQUOT) is given the target's name, so that the message says which file."""
    if exc.filename is None:
        exc.filename = target
    setattr(exc, _OUTPUT_ATTR, target)


def failed_output(exc: BaseException) -> str | None:
    """The output an OS error was raised while writing (in an :func:`atomic_output` block), else None."""
    return getattr(exc, _OUTPUT_ATTR, None)


@contextlib.contextmanager
def atomic_outputs(*paths: str | os.PathLike | None) -> Iterator[list[Path | None]]:
    """:func:`atomic_output` for several files at once: all are put in place when the block succeeds, none if not.

    None entries stay None (an output not asked for).
    """
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(atomic_output(p)) if p is not None else None for p in paths]


TERMINATING = tuple(getattr(signal, name) for name in ("SIGTERM", "SIGHUP") if hasattr(signal, name))
"""The signals that :func:`clean_up_on_signals` turns into :class:`Terminated` (those the platform has)."""


class Terminated(KeyboardInterrupt):
    """SIGTERM or SIGHUP arrived: raised in the main thread, it unwinds like Ctrl-C's KeyboardInterrupt.

    A KeyboardInterrupt so that every ``except KeyboardInterrupt`` and ``except BaseException``
    clean-up (ours and the libraries') runs for it too; ``signum`` says which signal.
    """

    def __init__(self, signum: int) -> None:
        self.signum = int(signum)
        super().__init__(f"terminated ({self.signal_name})")

    @property
    def signal_name(self) -> str:
        try:
            return signal.Signals(self.signum).name
        except ValueError:
            return f"signal {self.signum}"

    def __reduce__(self):
        return (type(self), (self.signum,))


def _raise_terminated(signum: int, frame: Any) -> None:
    raise Terminated(signum)


@contextlib.contextmanager
def clean_up_on_signals(signals: tuple[int, ...] = TERMINATING) -> Iterator[None]:
    """While the block runs, SIGTERM and SIGHUP raise :class:`Terminated` in the main thread (as Ctrl-C raises
    KeyboardInterrupt), so partial outputs are removed; the handlers before are put back after it.

    Only a signal left at its default action is taken over: one the process ignores (``nohup``
    ignores SIGHUP) stays ignored, and one another handler owns keeps it. Outside the main thread
    (where Python runs no signal handler) it does nothing. Servers that install their own handlers
    while they run (uvicorn) put these back when they stop.
    """
    replaced: dict[int, Any] = {}
    if threading.current_thread() is threading.main_thread():
        for signum in signals:
            if signal.getsignal(signum) is signal.SIG_DFL:
                replaced[signum] = signal.signal(signum, _raise_terminated)
    try:
        yield
    finally:
        for signum, before in replaced.items():
            if signal.getsignal(signum) is _raise_terminated:
                signal.signal(signum, before)


@contextlib.contextmanager
def signals_deferred(signals: tuple[int, ...] = (signal.SIGINT, *TERMINATING)) -> Iterator[Callable[[], bool]]:
    """Hold Ctrl-C, SIGTERM and SIGHUP while C code that calls back into Python runs; deliver them after.

    Why: an exception raised in a ctypes callback cannot cross into C; ctypes prints it and
    drops it, so a KeyboardInterrupt (or :class:`Terminated`) raised there is lost and the work
    goes on. In the block a signal is only noted; the yielded ``stopped()`` says whether one came
    (the callback then asks the C code to stop), and when the block ends the handler it had
    before is called, where an exception can be raised. Only signals with a Python handler are
    held, and only in the main thread (where Python runs its handlers).
    """
    came: list[int] = []
    held: dict[int, Any] = {}
    if threading.current_thread() is threading.main_thread():
        for signum in signals:
            before = signal.getsignal(signum)
            if callable(before):
                held[signum] = signal.signal(signum, lambda number, frame: came.append(number))
    try:
        yield lambda: bool(came)
    finally:
        for signum, before in held.items():
            signal.signal(signum, before)
        if came and came[0] in held:
            held[came[0]](came[0], None)
