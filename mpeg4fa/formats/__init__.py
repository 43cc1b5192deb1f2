"""File formats around the codec: readers and writers that turn files into
:class:`~mpeg4fa.fba.stream.FapStream` objects and back.

Every reader reports bad input as a :class:`FormatError` carrying the path, line
and column to fix; nothing else (no bare ``ValueError``/``IndexError``, no
``OSError`` for a missing file or a directory) escapes for malformed content.
The limits a ``.fap`` file is read within are listed in :mod:`mpeg4fa.formats.fap_text`.

* :func:`read_fap`, :func:`iter_fap`, :func:`write_fap`: plain-text ``.fap`` files
  (Xface, Greta, VREng, visage).
* :func:`read_stream`, :func:`sniff`: open a ``.fba`` or ``.fap`` file by its content.
"""
from mpeg4fa.formats.errors import FormatError, FormatWarning
from mpeg4fa.formats.fap_text import iter_fap, read_fap, write_fap
from mpeg4fa.formats.sniff import read_stream, sniff

__all__ = ["FormatError", "FormatWarning", "iter_fap", "read_fap", "write_fap", "read_stream", "sniff"]
