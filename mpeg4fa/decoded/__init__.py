"""What a decoder shows: decoded frames -> the 68 FAP values a face takes at every frame.

The one home of the standard's rules for reading a stream beyond its bits, used
by the face, the encoder (to prove what it leaves out decodes the same), the
renderer, the CLI and the conformance suite alike:

* :mod:`.resolve`: FAPs a frame does not send are held or interpolated (mask type
  per FAP group, :meth:`~mpeg4fa.fba.stream.FapStream.group_mask_types`), FAP 1
  (visemes) and FAP 2 (expressions) expand through the ``spec/`` profiles, and a
  sent low-level FAP overrides the high-level value;
* :mod:`.limits`: values no face can show are clamped, said once per FAP.

>>> values = resolve(stream)             # (n, 68) float, what frame k shows in row k
>>> shown_frame(stream.frame(40))        # row 40 alone (resolved with the frames before it)
"""
from __future__ import annotations

from .errors import ClampWarning, FapValueError
from .limits import LOWER, UPPER, Clamped, check_finite, clamp, clamp_and_warn
from .resolve import FrameResolver, ResolveState, explicit, held_high_level, resolve, shown_frame, shown_values

__all__ = ["resolve", "explicit", "held_high_level", "shown_frame", "shown_values", "FrameResolver", "ResolveState", "clamp", "clamp_and_warn",
           "check_finite", "Clamped", "LOWER", "UPPER", "ClampWarning", "FapValueError"]
