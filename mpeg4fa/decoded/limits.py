"""What a face can show: FAP values outside it are clamped, said once per FAP.

Streams from other systems carry values no face can mean: the visage|SDK
encoder writes negative values on unidirectional FAPs (``open_jaw`` -328,
``lift_l_cheek`` -160), Xface files likewise. Refusing them would refuse the
streams, so the decoder clamps and says so:

* a **unidirectional** FAP (3 open_jaw, 14 thrust_jaw, 41/42 lift cheeks,
  47 tongue_roll: ``unidirectional`` in ``spec/faps.csv``) is held at 0 when
  negative: the standard's BIFS range for them is [0, +I];
* any FAP beyond what a face can show is held at the bound: ``|value| <=``
  :data:`TRANSLATION_LIMIT` FAPU for translations (eight times the key distance),
  and a half turn (pi / 1e-5 AU) for rotations.

Non-finite values are not a range question: they are refused (a bitstream cannot
carry them, so they come from a caller's bug).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from mpeg4fa.decoded.errors import ClampWarning, FapValueError
from mpeg4fa.spec import ANGLE_UNIT, FAPS, N_FAPS

TRANSLATION_LIMIT = 8192
"""|value| above this many FAPU (8 times the key distance) is held at it."""


def _bounds() -> tuple[np.ndarray, np.ndarray]:
    lower = np.full(N_FAPS, -np.inf)
    upper = np.full(N_FAPS, np.inf)
    for record in FAPS[2:]:
        limit = np.pi / ANGLE_UNIT if record.fapu == "AU" else float(TRANSLATION_LIMIT)
        i = record.number - 1
        lower[i], upper[i] = (0.0 if record.unidirectional else -limit), limit
    return lower, upper


LOWER, UPPER = _bounds()
"""Per-FAP bounds of what a face shows (columns 0/1, FAP 1/2, are unbounded: their fields are checked apart)."""


@dataclass(frozen=True)
class Clamped:
    """One FAP that was clamped: in how many frames, and its value furthest outside (in FAPU)."""

    fap: int
    frames: int
    worst: float          # the value furthest outside the bounds
    negative_only: bool   # every clamped value was below 0 on a unidirectional FAP

    @property
    def name(self) -> str:
        return FAPS[self.fap - 1].name

    @property
    def bounds(self) -> tuple[float, float]:
        return float(LOWER[self.fap - 1]), float(UPPER[self.fap - 1])

    def message(self, where: str | None = "the stream") -> str:
        """What was done, for a stream (``where`` names it) or for one frame (``where=None``)."""
        low, high = self.bounds
        if self.negative_only:
            what, to = "negative on a unidirectional FAP", "clamped to 0"
        else:
            what, to = f"outside {low:g}..{high:g}", "clamped"
        if where is None:
            return f"FAP {self.fap} ({self.name}) = {self.worst:g} is {what}: {to}"
        return (f"FAP {self.fap} ({self.name}) is {what} in {self.frames} frame{'s' * (self.frames != 1)} of "
                f"{where} (as far as {self.worst:g}): {to}")


def check_finite(values: np.ndarray) -> None:
    """Refuse what no clamping can mend: a wrong shape or a non-finite value."""
    values = np.asarray(values, dtype=float)
    if values.shape[-1:] != (N_FAPS,):
        raise FapValueError(f"a frame has {N_FAPS} FAP values, got shape {values.shape}",
                        hint="pass an array of 68 values or a {fap: value} mapping")
    bad = ~np.isfinite(values)
    if bad.any():
        fap = int(np.argwhere(bad)[0][-1]) + 1
        raise FapValueError(f"FAP {fap} ({FAPS[fap - 1].name}) is {values[bad].flat[0]}", where=f"FAP {fap}",
                            hint="FAP values are finite numbers of FAPU")


def clamp(values: np.ndarray) -> tuple[np.ndarray, list[Clamped]]:
    """``values`` (68 or n x 68) held inside what a face shows, and what was changed.

    Returns a new array; the report lists each clamped FAP once with its frame count.
    """
    values = np.asarray(values, dtype=np.float64)
    check_finite(values)
    rows = values.reshape(-1, N_FAPS)
    low, high = rows < LOWER, rows > UPPER
    if not (low.any() or high.any()):
        return values.copy(), []
    report = []
    excess = np.maximum(LOWER - rows, rows - UPPER)  # > 0 where outside
    for col in np.flatnonzero(low.any(axis=0) | high.any(axis=0)):
        out = low[:, col] | high[:, col]
        worst = rows[int(np.argmax(excess[:, col])), col]
        negative_only = not high[:, col].any() and LOWER[col] == 0.0
        report.append(Clamped(int(col) + 1, int(out.sum()), float(worst), negative_only))
    return np.clip(values, LOWER, UPPER), report


def clamp_and_warn(values: np.ndarray, where: str | None = None, *, stacklevel: int = 3) -> np.ndarray:
    """:func:`clamp`, saying each clamped FAP as a :class:`ClampWarning` (``where`` as in :meth:`Clamped.message`)."""
    clamped, report = clamp(values)
    for item in report:
        warnings.warn(item.message(where), ClampWarning, stacklevel=stacklevel)
    return clamped
