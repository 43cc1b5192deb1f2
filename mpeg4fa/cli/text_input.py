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

from .errors import InputError


def text_max() -> int:
    """Most characters of text read from a file or standard input: the speech layer's bound (imported when
    text is read, so that commands that read none do not load the speech layer)."""
    from ..speech.chunks import MAX_SOURCE_CHARS

    return MAX_SOURCE_CHARS

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
    """The text and its name for messages (``<text>``, ``<stdin>`` or the file), at most :func:`text_max`
    characters."""
    TEXT_MAX = text_max()
    if source.stdin:
        name = "<stdin>"
        binary = getattr(sys.stdin, "buffer", None)
        if binary is None:  # a text stream put in place of stdin (an embedding program): already decoded
            text = sys.stdin.read(TEXT_MAX + 1)
        else:  # bytes, whatever the locale says: decoded (or refused) by one rule, as a file's
            text = _decoded(binary.read(4 * TEXT_MAX + 1), name)
    elif source.path is not None:
        name = str(source.path)
        with open(source.path, "rb") as handle:
            text = _decoded(handle.read(4 * TEXT_MAX + 1), name)
    else:
        return _argv_text(source.argument), "<text>"
    if len(text) > TEXT_MAX:
        raise InputError(f"the text is longer than {TEXT_MAX} characters", where=name,
                         hint="split it and encode the parts one after another")
    return text, name


def _argv_text(text: str) -> str:
    """Text from the command line, its bytes held to standard input's rule.

    Python decodes the command line with ``surrogateescape``: a byte that is not UTF-8 arrives as a
    lone surrogate, which no engine can take. The bytes are recovered and decoded by :func:`_decoded`,
    so ``--text $'hello \\xff'`` and the same bytes on standard input get the same located message.
    (Under a locale whose encoding is not UTF-8 the text is left as it came; the parse pass refuses any
    surrogate left, :func:`mpeg4fa.speech.markup.check_characters`.)
    """
    if text.isascii() or not any("\udc80" <= c <= "\udcff" for c in text):
        return text
    try:
        data = os.fsencode(text)
    except UnicodeEncodeError:  # a surrogate no byte stands for: the parse pass names it
        return text
    if sys.getfilesystemencoding().lower().replace("-", "") != "utf8":
        return text
    return _decoded(data, "<text>", hint="give the text as UTF-8; check the terminal's encoding")


def _decoded(data: bytes, name: str, hint: str | None = None) -> str:
    """UTF-8 text (a byte-order mark dropped); a MarkupError at line:column and byte offset where it is not.

    Standard input is read as bytes, not through the locale's codec: under a strict UTF-8 locale
    a stray byte ended in a UnicodeDecodeError, under the C locale it became a lone surrogate.
    The rule is the package's one (:func:`mpeg4fa.jsonio.decode_utf8`).
    """
    from ..jsonio import decode_utf8
    from ..speech.errors import MarkupError

    TEXT_MAX = text_max()
    if len(data) > 4 * TEXT_MAX:  # UTF-8 takes at most 4 bytes a character
        raise InputError(f"the text is longer than {TEXT_MAX} characters", where=name,
                         hint="split it and encode the parts one after another")
    return decode_utf8(data, name, lambda path, line, column, problem, said: MarkupError(
        problem, line or 1, column or 1, hint=hint or said, source=path), what="text")
