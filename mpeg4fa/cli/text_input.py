"""What the TEXT/INPUT argument of ``encode`` and ``say`` stands for: text, a file, or standard input.

Why: a mistyped file name must not be spoken. ``mpeg4fa say scrpit.txt`` used to say
"scrpit dot t x t" and exit 0. So an argument that looks like a path (a path separator
or a file extension, and no spaces) must name a readable regular file; a directory or a
device (``/dev/urandom``) is refused too. ``--text`` says "this is text" whatever it looks
like, ``@FILE`` says "read this file", ``-`` reads standard input.
"""
from __future__ import annotations

import os
import re
import stat
import sys
from dataclasses import dataclass
from pathlib import Path

from ..speech.markup import MAX_TEXT_CHARS
from .errors import InputError

TEXT_MAX = MAX_TEXT_CHARS
"""Most characters of text read from a file or standard input (the speech layer's bound)."""
_EXTENSION = re.compile(r"[^./\\][^/\\]*\.[A-Za-z][A-Za-z0-9]{0,7}")
_SPEAK_IT = "use --text to speak it as text"


@dataclass(frozen=True)
class TextArgument:
    """The argument resolved: ``path`` for a file (the text file or stream to read), else the literal text."""

    argument: str
    path: Path | None = None
    stdin: bool = False


def looks_like_path(arg: str) -> bool:
    """A path separator or a file extension (``notes.txt``, ``talk.fba``), and no whitespace."""
    if not arg or any(c.isspace() for c in arg):
        return False
    return "/" in arg or os.sep in arg or _EXTENSION.fullmatch(arg) is not None


def classify(arg: str, *, as_text: bool = False) -> TextArgument:
    """Text, standard input or a file; InputError for a path-like argument naming no readable file."""
    if as_text:
        return TextArgument(arg)
    if arg == "-":
        return TextArgument(arg, stdin=True)
    if arg.startswith("@") and len(arg) > 1:
        return TextArgument(arg, path=_readable(Path(arg[1:]), "the text file named after @"))
    try:
        exists = os.path.lexists(arg)
    except (OSError, ValueError):  # a name too long for the file system is text
        exists = False
    if exists or looks_like_path(arg):
        return TextArgument(arg, path=_readable(Path(arg), _SPEAK_IT))
    return TextArgument(arg)


def _readable(path: Path, hint: str) -> Path:
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise InputError("no such file", where=str(path), hint=hint) from None
    except OSError as exc:
        raise InputError(f"cannot read it ({exc.strerror})", where=str(path), hint=hint) from None
    if stat.S_ISDIR(mode):
        raise InputError("is a directory, not a file", where=str(path), hint=hint)
    if not stat.S_ISREG(mode):
        raise InputError("is a device, pipe or socket, not a regular file", where=str(path),
                         hint=hint if hint == _SPEAK_IT else "save the text to a file, or pipe it to -")
    if not os.access(path, os.R_OK):
        raise InputError("cannot read it (permission denied)", where=str(path), hint=hint)
    return path


def read_text(source: TextArgument) -> tuple[str, str]:
    """The text and its name for messages (``<text>``, ``<stdin>`` or the file), at most TEXT_MAX characters."""
    from ..speech.errors import MarkupError

    if source.stdin:
        text = sys.stdin.read(TEXT_MAX + 1)
        name = "<stdin>"
    elif source.path is not None:
        name = str(source.path)
        with open(source.path, "rb") as handle:
            data = handle.read(4 * TEXT_MAX + 1)  # UTF-8 takes at most 4 bytes a character
        if len(data) > 4 * TEXT_MAX:
            raise InputError(f"the text is longer than {TEXT_MAX} characters", where=name,
                             hint="split it and encode the parts one after another")
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError as exc:
            before = data[:exc.start].decode("utf-8-sig", errors="replace")
            line = before.count("\n") + 1
            column = len(before) - (before.rfind("\n") + 1) + 1
            raise MarkupError(f"the text file is not UTF-8 ({exc.reason} at byte {exc.start})", line, column,
                              hint="save it as UTF-8", source=name) from None
    else:
        return source.argument, "<text>"
    if len(text) > TEXT_MAX:
        raise InputError(f"the text is longer than {TEXT_MAX} characters", where=name,
                         hint="split it and encode the parts one after another")
    return text, name
