"""Record types for the rows of the standard's tables (see ``spec/README.md``).

They are frozen so that the module-level tables built from them cannot be
changed by accident: every part of the codec shares the same objects.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Fap:
    """One facial animation parameter (a row of ``faps.csv``).

    FAP 1 (viseme) and FAP 2 (expression) are high-level: they have no FAPU,
    direction, feature point or default range, so those fields are ``None`` or
    empty; their fields are described by :class:`HighLevelField`.
    """

    number: int
    name: str
    description: str
    fapu: str | None
    """Key of :data:`mpeg4fa.spec.FAPU` the value is measured in."""
    direction: str | None
    """Direction a positive value moves the point, in the face's own frame."""
    unidirectional: bool | None
    """True for the five FAPs whose BIFS range starts at 0."""
    group: int
    """FAP group 1..10; the bitstream masks FAPs group by group."""
    feature_point: tuple[str, ...]
    """Label(s) of the feature point(s) the FAP moves (two for tongue_roll)."""
    quant_step: int
    """Per-FAP quantiser step; the coded step is this times fap_quant."""
    i_max: int | None
    """Default intra range magnitude, in quantised units (min = -max)."""
    p_max: int | None
    """Default predicted (P) range magnitude, in quantised units."""
    lr_partner: int | None = None
    """The FAP that does the same on the other side of the face (left <-> right), if any."""
    io_partner: int | None = None
    """The outer-lip FAP of an inner-lip one and back (FAPs 4-13 <-> 51-60), if any."""
    notes: str = ""


@dataclass(frozen=True)
class HighLevelField:
    """One coded field of FAP 1 or FAP 2, in bitstream order.

    The selects are not quantised; blend and intensities are quantised by
    fap_quant and their ranges are divided by it (``quantised``).
    """

    fap: int
    field: str
    i_min: int
    i_max: int
    p_min: int
    p_max: int
    quantised: bool


@dataclass(frozen=True)
class FeaturePoint:
    """One of the 84 facial feature points, labelled ``group.index``."""

    label: str
    group: int
    description: str
    moved_by_faps: tuple[int, ...]
    """FAPs that displace the point; empty for calibration-only points."""
    fapu_role: tuple[str, ...]
    """FAPU distances (e.g. ``"MNS0"``) measured at this point."""
    side: str | None = None
    """``"left"`` or ``"right"``: the face's side the point lies on (+x is the face's left); None on the midline."""
    mirror: str | None = None
    """Label of the point's left/right twin (3.5 <-> 3.6); None on the midline."""


@dataclass(frozen=True)
class Fapu:
    """A facial animation parameter unit.

    Distance units are ``(point_a.axis - point_b.axis) / divisor`` on the
    neutral face; AU is a fixed angle of ``radians`` and has no points.
    """

    symbol: str
    name: str
    distance: str | None
    """Name of the neutral-face distance the unit divides (``"IRISD0"``); None for AU."""
    definition: str
    point_a: str | None
    axis: str | None
    point_b: str | None
    divisor: int | None
    unit: str
    radians: float | None


@dataclass(frozen=True)
class Viseme:
    """A viseme that ``viseme_select1``/``viseme_select2`` can name (0 = none)."""

    number: int
    name: str
    phonemes: str
    examples: str


@dataclass(frozen=True)
class Expression:
    """A facial expression that ``expression_select1/2`` can name (0 = neutral)."""

    number: int
    name: str
    description: str
