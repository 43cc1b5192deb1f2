"""The CLI's own errors: options that do not go together (exit status 2, like argparse's), and command-line
input that names no usable file (exit status 1, like every other bad input); and how an operating-system
error becomes one line naming its file and what to do (:func:`os_error_line`)."""
from __future__ import annotations

import contextlib
import errno
import os

from ..atomic import failed_output
from ..errors import MpegFaError


class UsageError(MpegFaError):
    """A combination of command-line options that cannot work; ``hint`` names one that does."""


class InputError(MpegFaError):
    """A command-line argument that should name a readable file and does not (``where``: the argument)."""


@contextlib.contextmanager
def located(path: str):
    """A value the FDP model rejects (a point outside the photo, a bad vertex index) named by its file."""
    from ..fdp import FdpError, FdpValueError
    try:
        yield
    except FdpValueError as exc:
        raise FdpError.no_place(path, exc.message, hint="check the feature point annotations") from None


def os_error_line(exc: OSError) -> str:
    """An OS error as one line naming its file and what to do: ``cannot write nodir/x.fap: No such file or
    directory (create the folder nodir first)``; ``cannot write`` where it was raised writing an output."""
    reason = exc.strerror or str(exc)
    path = exc.filename
    writing = failed_output(exc) is not None
    hint = _os_hint(exc.errno, None if path is None else os.fsdecode(path), writing)
    if path is None:
        text = reason
    elif writing:
        text = f"cannot write {os.fsdecode(path)}: {reason}"
    else:
        text = f"{os.fsdecode(path)}: {reason}"
    return f"{text} ({hint})" if hint else text


def _os_hint(code: int | None, path: str | None, writing: bool) -> str:
    if code == errno.ENOENT and path is not None:
        folder = os.path.dirname(path) or "."
        if not os.path.isdir(folder):
            return f"the folder {folder} does not exist: create it first"
        return "write it into an existing folder" if writing else "check the name"
    return _HINTS.get(code, "") if code is not None else ""


_HINTS = {getattr(errno, name): hint for name, hint in (
    ("EACCES", "check its permissions, or use another folder"),
    ("EPERM", "check its permissions, or use another folder"),
    ("ENOSPC", "the disk is full: free some space or write elsewhere"),
    ("EDQUOT", "the disk quota is used up: free some space or write elsewhere"),
    ("EROFS", "a read-only file system: write elsewhere"),
    ("EISDIR", "it is a folder: give a file name"),
    ("ENOTDIR", "a part of the path is a file, not a folder"),
    ("ENAMETOOLONG", "give a shorter name"),
    ("ELOOP", "too many symbolic links: give the file's real path"),
    ("EEXIST", "remove it or give another name"),
    ("EADDRINUSE", "another program uses it: give another --port"),
    ("EMFILE", "too many open files: raise the limit (ulimit -n)"),
    ("EIO", "the device failed: check the disk"),
) if hasattr(errno, name)}
"""errno -> what to do, for the errors a user can act on."""
