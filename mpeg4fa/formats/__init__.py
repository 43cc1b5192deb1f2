"""File formats around the codec: readers and writers that turn files into
:class:`~mpeg4fa.fba.stream.FapStream` objects and back.

Every reader reports bad input as a :class:`FormatError` carrying the path, line
and column to fix; nothing else (no bare ``ValueError``/``IndexError``, no
``OSError`` for a missing file or a directory) escapes for malformed content.
The limits a ``.fap`` file is read within are listed in :mod:`mpeg4fa.formats.fap_text`;
a ``.bap`` file is read within the same ones (:mod:`mpeg4fa.formats.bap_text`).

* :func:`read_fap`, :func:`iter_fap`, :func:`write_fap`: plain-text ``.fap`` files
  (Xface, Greta, VREng, visage).
* :func:`read_bap`, :func:`iter_bap`, :func:`write_bap`: plain-text ``.bap`` body files (VREng's
  dialect); :func:`split_face_body` and :func:`merge_face_body` turn a face+body stream into a
  ``.fap`` + ``.bap`` pair and back.
* :func:`read_stream`, :func:`sniff`: open a ``.fba``, ``.fap`` or ``.bap`` file by its content.
"""
from mpeg4fa.formats.errors import FormatError, FormatWarning
from mpeg4fa.formats.fap_text import iter_fap, read_fap, write_fap
from mpeg4fa.formats.bap_text import (
    has_body, has_face, iter_bap, merge_face_body, read_bap, read_bap_header, split_face_body, write_bap,
)
from mpeg4fa.formats.sniff import read_stream, sniff

__all__ = ["FormatError", "FormatWarning", "iter_fap", "read_fap", "write_fap", "iter_bap", "read_bap",
           "read_bap_header", "write_bap", "split_face_body", "merge_face_body", "has_face", "has_body",
           "read_stream", "sniff"]
