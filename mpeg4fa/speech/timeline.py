"""The FAP timeline: timed visemes and expression cues -> low-level FAP values per frame.

The encoder knows *when* each viseme is spoken (from the speech engine's phoneme
timings) and *when* each expression tag starts; this module turns those into
smooth (n, 68) FAP arrays sampled at arbitrary times (usually
:func:`frame_times`). Column ``i`` is FAP ``i + 1``; columns 0 and 1 (FAP 1 and
2) stay 0 because every value here is low-level. Nothing is rounded: the caller
quantises.

Model
-----
*Transitions* all use the cubic Hermite curve without an end tangent,
``f(t) = h00(t) a_s + h01(t) a_e + h10(t) g`` on normalised time ``t`` in [0, 1]
(:func:`hermite`). Its slope is ``g`` at ``t = 0`` and always 0 at ``t = 1``, so
a transition always *arrives* at rest, and the next one that starts with
``g = 0`` joins it with a continuous value and slope.

*Visemes* (:func:`viseme_track`): a viewer judges lip sync by when each
shape arrives against the sound, and notices a mouth that lags the voice by
more than ~45 ms (ITU-R BT.1359) much sooner than one that leads it. So the
mouth anticipates: every boundary between two phases (a span, or a silence
before, between or after spans) gets one move from the shape before to the
shape after, placed *across* the boundary. It starts ``lead = min(LEAD,
LEAD_SHARE x the phase before)`` before the boundary (at most 100 ms, 70 % of
that phoneme or pause) and arrives ``lag = min(LAG, LAG_SHARE x the phase
after)`` after it (at most 30 ms, 20 % of the phoneme): each shape is reached in
the first fifth of its phoneme, near its acoustic onset, not at its end. The
shares add up to 0.9, so two moves never overlap and every phase keeps a hold of
at least a tenth of its length, at its shape. *Closures* (``PP``, Chinese ``bpm``:
the lips touch) have no lag: shut at the onset itself, and held shut for
``closure_hold`` (default :data:`CLOSURE_HOLD`, one frame at 25 fps) so that a
frame always shows them; a move that the hold delays starts when it ends and
lasts at least :data:`MIN_MOVE` (a lip release is fast). Silence is the ``none``
viseme (all zero): before the first move the mouth is at rest; the move into
silence after a span is at most ``rest_time`` long (0: a step at the span's
end), and the mouth stays at rest until the move into the next span. The
tangent is ``g = tangent * (a_e - a_s)``: 0 (the default) gives
ease-in/ease-out and a C1 track, every move starting and arriving at rest;
values up to 3 leave the old shape faster and stay monotone (no overshoot) but
give up the slope continuity at the joins. :func:`viseme_fields` gives FAP 1
from the same moves, so a high-level stream shows the mouth at the same times as
the low-level one.

*Expressions* (:func:`expression_intensities`): each expression has its own
intensity track in 0..63. A cue sends its expression to its intensity and every
other expression to 0, all over the cue's ``seconds`` (``0`` is a step), so the
old expression fades out while the new one fades in. Each track starts the new
transition from where it is: its value ``a_s`` and its slope carried across.
This covers the three cases of the design: (1) an expression never shown
starts at 0 with slope 0; (2) a finished transition is at rest (slope 0); (3) a
transition still moving when the cue comes continues with ``a_s`` = its current
value and ``g`` = its current slope rescaled to the new duration,
``g_new = f'_old(t_old) * seconds_new / seconds_old``, because ``g`` is per
*normalised* time and the slope per second is ``g / seconds``; this keeps the
slope in intensity per second continuous. Re-tagging the same expression is the
same rule. Intensities are clipped to 0..63 (a carried slope can make a long
transition overshoot); where a track is clipped its slope counts as 0. The FAP
values are ``sum(profile * intensity / 63)``, as :func:`mpeg4fa.spec.expression_blend`.

*Merging* (:func:`merge_tracks`): per FAP, the largest positive value minus the
largest negative magnitude among the tracks. Where the tracks agree in sign
this is the value of larger magnitude; where they pull opposite ways they
partly cancel. Unlike "keep the value of larger magnitude" it is continuous:
that rule jumps from ``+x`` to ``-x`` when two opposite values cross in size.

*Idle* (:func:`idle_track`, off unless the encoder asks): seeded random blinks
and slow head motion, to be merged like any other track.
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from mpeg4fa.spec import AU_PER_RADIAN, FAP_BY_NAME, FAPU, FULL_INTENSITY, N_FAPS
from mpeg4fa.spec.profiles import EXPRESSION_PROFILES, VISEME_PROFILES

__all__ = [
    "VisemeSpan", "ExpressionCue", "ExpressionFields", "VisemeFields", "FULL_INTENSITY", "CLOSURES",
    "CLOSURE_HOLD", "hermite", "hermite_slope", "viseme_track", "viseme_fields", "expression_intensities",
    "expression_track", "expression_fields", "merge_tracks", "idle_track", "frame_times",
]


NEUTRAL = "neutral"
"""The expression that is no expression: a cue naming it sends every expression to 0."""

_BLINK_COLUMNS = (FAP_BY_NAME["close_t_l_eyelid"].number - 1, FAP_BY_NAME["close_t_r_eyelid"].number - 1)
_HEAD_COLUMNS = (FAP_BY_NAME["head_pitch"].number - 1, FAP_BY_NAME["head_yaw"].number - 1,
                 FAP_BY_NAME["head_roll"].number - 1)
_AU_PER_DEGREE = math.pi / 180.0 * AU_PER_RADIAN
"""Head angles are in AU (:data:`mpeg4fa.spec.ANGLE_UNIT` radians)."""
_LID_SHUT = float(FAPU["IRISD"].divisor)
"""An upper lid lowered by one IRISD0 (1024 IRISD units) covers the iris: the eye is shut."""


@dataclass(frozen=True)
class VisemeSpan:
    """A viseme held over ``[start, end)`` seconds; ``set`` names its table in ``VISEME_PROFILES``."""

    viseme: str
    start: float
    end: float
    set: str = "mpeg4"


@dataclass(frozen=True)
class ExpressionCue:
    """From ``start`` the expression moves to ``intensity`` (0..63) over ``seconds``, then holds.

    Intensity 0, or the expression ``neutral``, goes back to the neutral face.
    """

    expression: str
    intensity: int
    seconds: float
    start: float


@dataclass(frozen=True)
class ExpressionFields:
    """Per frame, the strongest and second expression with their rounded intensities (FAP 2).

    Names are ``neutral`` where the intensity rounds to 0; the encoder maps
    names to FAP 2 select codes.
    """

    select1: np.ndarray
    intensity1: np.ndarray
    select2: np.ndarray
    intensity2: np.ndarray


# ---- Hermite ---------------------------------------------------------------------------------------

def _basis(t: npt.ArrayLike, extra_dims: int) -> np.ndarray:
    """``t`` as float with trailing axes, so it broadcasts against the endpoints' shape."""
    t = np.asarray(t, dtype=np.float64)
    return t.reshape(t.shape + (1,) * extra_dims)


def hermite(t: npt.ArrayLike, a_s: npt.ArrayLike, a_e: npt.ArrayLike, g: npt.ArrayLike = 0.0) -> np.ndarray:
    """``(2t^3-3t^2+1) a_s + (-2t^3+3t^2) a_e + (t^3-2t^2+t) g`` on normalised ``t``.

    The shape is ``t.shape + broadcast(a_s, a_e, g).shape``: ``t`` (n,) with
    (68,) profiles gives (n, 68), with scalars (n,). ``g`` is the start slope
    per unit of normalised time; the end slope is always 0.
    """
    a_s, a_e, g = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (a_s, a_e, g)))
    u = _basis(t, a_s.ndim)
    u2 = u * u
    u3 = u2 * u
    return (2 * u3 - 3 * u2 + 1) * a_s + (3 * u2 - 2 * u3) * a_e + (u3 - 2 * u2 + u) * g


def hermite_slope(t: npt.ArrayLike, a_s: npt.ArrayLike, a_e: npt.ArrayLike, g: npt.ArrayLike = 0.0) -> np.ndarray:
    """``d/dt`` of :func:`hermite`: ``(6t^2-6t)(a_s-a_e) + (3t^2-4t+1) g``, per normalised time."""
    a_s, a_e, g = np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (a_s, a_e, g)))
    u = _basis(t, a_s.ndim)
    return (6 * u * u - 6 * u) * (a_s - a_e) + (3 * u * u - 4 * u + 1) * g


def _hermite_rows(u: np.ndarray, a_s: np.ndarray, a_e: np.ndarray, g: np.ndarray) -> np.ndarray:
    """Hermite with one ``u`` (n,) per row of (n,) or (n, k) endpoints: the gathered form tracks need."""
    u = u.reshape(u.shape + (1,) * (a_s.ndim - 1))
    u2 = u * u
    u3 = u2 * u
    return (2 * u3 - 3 * u2 + 1) * a_s + (3 * u2 - 2 * u3) * a_e + (u3 - 2 * u2 + u) * g


def _times(times: npt.ArrayLike) -> np.ndarray:
    t = np.asarray(times, dtype=np.float64)
    if t.ndim != 1:
        raise ValueError(f"times must be one-dimensional, got shape {t.shape}")
    if not np.isfinite(t).all():
        raise ValueError("times must be finite")
    return t


def _finite(value: object, what: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)):
        raise ValueError(f"{what} {value!r} is not a number")
    if not math.isfinite(float(value)):
        raise ValueError(f"{what} {value!r} is not finite")
    return float(value)


# ---- visemes ---------------------------------------------------------------------------------------

def _profile(span: VisemeSpan, k: int) -> np.ndarray:
    if span.set not in VISEME_PROFILES:
        raise ValueError(f"span {k}: unknown viseme set {span.set!r} (known: {', '.join(VISEME_PROFILES)})")
    table = VISEME_PROFILES[span.set]
    if span.viseme not in table:
        raise ValueError(f"span {k}: {span.viseme!r} is not a viseme of set {span.set!r} "
                         f"(known: {', '.join(table)})")
    return table[span.viseme].astype(np.float64)


@dataclass(frozen=True)
class _Segment:
    """One move of the mouth: from a shape to another over [start, end]; held after ``end``."""

    start: float
    end: float
    source: tuple[str, str]   # (set, viseme) it leaves
    target: tuple[str, str]   # (set, viseme) it reaches
    a_s: np.ndarray
    a_e: np.ndarray


_REST = ("mpeg4", "none")

LEAD = 0.10
"""Longest lead (s): how far before a boundary the move into the next shape may start."""
LAG = 0.03
"""Longest lag (s): how far after the boundary the shape may still be on its way (a frame at 25 fps)."""
LEAD_SHARE = 0.7
"""Most of the phase before the boundary (phoneme or pause) a lead may take."""
LAG_SHARE = 0.2
"""Most of the phase after the boundary a lag may take: the shape is reached in its first fifth."""
CLOSURES = frozenset({("mpeg4", "PP"), ("zh", "bpm")})
"""Bilabial closures (p, b, m): shut at the onset itself, no lag."""
CLOSURE_HOLD = 0.04
"""Shortest time (s) a closure stays shut from its onset: one frame at 25 fps, so a frame sees it."""
MIN_MOVE = 0.01
"""Shortest move (s) when a closure's hold delays the next one."""


def _checked_spans(spans: Sequence[VisemeSpan]) -> list[tuple[float, float, tuple[str, str], np.ndarray]]:
    checked = []
    for k, span in enumerate(spans):
        start, end = _finite(span.start, f"span {k} start"), _finite(span.end, f"span {k} end")
        if not start < end:
            raise ValueError(f"span {k} ({span.viseme}): start {start} must be before end {end}")
        checked.append((start, end, k, span, _profile(span, k)))
    checked.sort(key=lambda item: (item[0], item[2]))
    for (s0, e0, k0, _, _), (s1, _, k1, _, _) in zip(checked, checked[1:]):
        if s1 < e0:
            raise ValueError(f"span {k1} starts at {s1}, before span {k0} ends at {e0}: spans overlap")
    return [(start, end, (span.set, span.viseme), profile) for start, end, _, span, profile in checked]


class _Moves:
    """The moves of the mouth (:func:`_viseme_segments`), made one span at a time, earliest first.

    Why incremental: long text is timed sentence by sentence, so the spans of the whole text are
    never held at once. A move needs only the phases on both sides of its boundary, so each span
    adds the moves up to its own onset; :meth:`finish` adds the close into the final silence.
    The moves are the same, bit for bit, as from all the spans at once."""

    def __init__(self, rest: float, hold: float = CLOSURE_HOLD) -> None:
        self.rest, self.hold = rest, hold
        self.last: tuple | None = None  # the last span phase added
        self.floor = -math.inf  # the previous move's end, or the end of a closure's hold
        self._rest_pose = np.zeros(N_FAPS)

    def _move(self, before: tuple, after: tuple) -> _Segment:
        at = after[0]
        lead = min(LEAD, LEAD_SHARE * (before[1] - before[0]))
        closure = after[2] in CLOSURES
        lag = 0.0 if closure else min(LAG, LAG_SHARE * (after[1] - after[0]))
        rest = self.rest
        if after[2] == _REST and lead + lag > rest:  # closing into silence: at most rest_time long
            lead, lag = (lead * rest / (lead + lag), lag * rest / (lead + lag)) if rest > 0 else (0.0, 0.0)
        start, end = at - lead, at + lag
        floor = self.floor
        if start < floor:  # a closure's hold, or a move it delayed, is still on
            start, end = floor, max(end, floor + min(MIN_MOVE, lead + lag))
        self.floor = max(end, at + self.hold) if closure else end
        return _Segment(start, end, before[2], after[2], before[3], after[3])

    def add(self, phase: tuple) -> list[_Segment]:
        """The moves up to span ``phase`` (start, end, key, profile), which must not start before the last ends."""
        rest_pose = self._rest_pose
        if self.last is None:
            moves = [self._move((-math.inf, phase[0], _REST, rest_pose), phase)]
        elif phase[0] < self.last[1]:
            raise ValueError(f"a span starts at {phase[0]}, before the span before it ends at {self.last[1]}: "
                             "spans overlap")
        elif phase[0] > self.last[1]:
            gap = (self.last[1], phase[0], _REST, rest_pose)
            moves = [self._move(self.last, gap), self._move(gap, phase)]
        else:
            moves = [self._move(self.last, phase)]
        self.last = phase
        return moves

    def finish(self) -> list[_Segment]:
        """The close into the silence after the last span (none if no span came)."""
        if self.last is None:
            return []
        last, self.last = self.last, None
        return [self._move(last, (last[1], math.inf, _REST, self._rest_pose))]

    @property
    def horizon(self) -> float:
        """Every move still to come starts at or after this time (the next move crosses the last span's end)."""
        return -math.inf if self.last is None else self.last[1] - LEAD


def _viseme_segments(spans: Sequence[VisemeSpan], rest: float, hold: float = CLOSURE_HOLD) -> list[_Segment]:
    """One move per boundary between phases (see the module docstring), earliest first."""
    moves = _Moves(rest, hold)
    segments: list[_Segment] = []
    for span in _checked_spans(spans):
        segments += moves.add(span)
    return segments + moves.finish()


def _locate(segments: list[_Segment], t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """For each time: its segment index (-1 before the first), whether it is live, and u in [0, 1]."""
    starts = np.array([seg.start for seg in segments])
    ends = np.array([seg.end for seg in segments])
    idx = np.searchsorted(starts, t, side="right") - 1
    live = idx >= 0
    i = np.maximum(idx, 0)
    length = ends[i] - starts[i]  # 0 only for a closing move with rest_time 0: a step
    u = np.where(t < ends[i], (t - starts[i]) / np.where(length > 0, length, 1.0), 1.0)
    return idx, live, np.clip(u, 0.0, 1.0)


def _non_negative(value: float, what: str) -> float:
    x = _finite(value, what)
    if x < 0:
        raise ValueError(f"{what} {value!r} must be >= 0")
    return x


def viseme_track(spans: Sequence[VisemeSpan], times: npt.ArrayLike, tangent: float = 0.0,
                 rest_time: float = 0.15, closure_hold: float = CLOSURE_HOLD) -> np.ndarray:
    """Low-level FAPs (n, 68) of the mouth speaking ``spans``, sampled at ``times`` (seconds).

    Each move into a span's shape crosses the span's onset: it starts up to
    :data:`LEAD` before it and arrives up to :data:`LAG` after it (closures at
    the onset, then shut for ``closure_hold``); see the module docstring.
    Silence closes to ``none`` by a move at most ``rest_time`` long (0 = a step
    at the span's end). ``tangent`` scales the start slope, ``g = tangent *
    (a_e - a_s)``: 0 keeps value and slope continuous at every join; anything in
    [0, 3] keeps every value between the two profiles. Spans may come in any
    order; they must have ``start < end`` and must not overlap (``ValueError``).
    """
    t = _times(times)
    k_tan = _finite(tangent, "tangent")
    if not 0.0 <= k_tan <= 3.0:
        raise ValueError(f"tangent {tangent!r} must be in [0, 3]: outside it the mouth overshoots")
    segments = _viseme_segments(spans, _non_negative(rest_time, "rest_time"),
                                _non_negative(closure_hold, "closure_hold"))
    return _viseme_rows(segments, t, k_tan)


def _viseme_rows(segments: Sequence[_Segment], t: np.ndarray, k_tan: float = 0.0) -> np.ndarray:
    """:func:`viseme_track` at ``t`` from its moves: all of them, or (streaming) those from the last one
    started at ``t[0]`` on, which give the same rows."""
    out = np.zeros((len(t), N_FAPS))
    if not segments:
        return out
    idx, live, u = _locate(segments, t)
    a_s, a_e = np.stack([seg.a_s for seg in segments]), np.stack([seg.a_e for seg in segments])
    i = idx[live]
    out[live] = _hermite_rows(u[live], a_s[i], a_e[i], k_tan * (a_e[i] - a_s[i]))
    return out


@dataclass(frozen=True)
class VisemeFields:
    """Per frame, FAP 1 as a decoder blends it: ``select1 x blend/63 + select2 x (1 - blend/63)``.

    ``select1``/``select2`` are (set, viseme) names: the shape being reached and
    the one being left; ``blend`` is the eased progress (Hermite, tangent 0) in 0..63,
    so the blend of the two profiles is the :func:`viseme_track` curve up to rounding.
    """

    select1: list[tuple[str, str]]
    select2: list[tuple[str, str]]
    blend: np.ndarray


def viseme_fields(spans: Sequence[VisemeSpan], times: npt.ArrayLike, rest_time: float = 0.15,
                  closure_hold: float = CLOSURE_HOLD) -> VisemeFields:
    """FAP 1 fields (which two visemes, how far between them) for every time: the same moves as
    :func:`viseme_track`, so the high-level and the low-level stream show the mouth at one time."""
    t = _times(times)
    segments = _viseme_segments(spans, _non_negative(rest_time, "rest_time"),
                                _non_negative(closure_hold, "closure_hold"))
    return _viseme_field_rows(segments, t)


def _viseme_field_rows(segments: Sequence[_Segment], t: np.ndarray) -> VisemeFields:
    """:func:`viseme_fields` at ``t`` from its moves (all, or those from the last one started at ``t[0]``)."""
    if not segments:
        return VisemeFields([_REST] * len(t), [_REST] * len(t), np.zeros(len(t), np.int64))
    idx, live, u = _locate(segments, t)
    weight = np.where(live, hermite(u, 0.0, 1.0), 1.0)
    select1 = [segments[i].target if ok else _REST for i, ok in zip(idx, live)]
    select2 = [segments[i].source if ok else _REST for i, ok in zip(idx, live)]
    return VisemeFields(select1, select2, np.rint(FULL_INTENSITY * weight).astype(np.int64))


# ---- expressions -----------------------------------------------------------------------------------

_EXPRESSION_NAMES = tuple(name for name in EXPRESSION_PROFILES if name != NEUTRAL)
_EXPRESSION_STACK = np.stack([EXPRESSION_PROFILES[n] for n in _EXPRESSION_NAMES]).astype(np.float64)


def _checked_cues(cues: Sequence[ExpressionCue]) -> list[tuple[float, float, str, int]]:
    result = []
    for k, cue in enumerate(cues):
        if cue.expression not in EXPRESSION_PROFILES:
            raise ValueError(f"cue {k}: unknown expression {cue.expression!r} "
                             f"(known: {', '.join(EXPRESSION_PROFILES)})")
        level = cue.intensity
        if isinstance(level, bool) or not isinstance(level, (int, np.integer)) \
                or not 0 <= level <= FULL_INTENSITY:
            raise ValueError(f"cue {k}: intensity {level!r} is not an integer in 0..{FULL_INTENSITY}")
        seconds = _finite(cue.seconds, f"cue {k} seconds")
        if seconds < 0:
            raise ValueError(f"cue {k}: seconds {seconds} must be >= 0")
        result.append((_finite(cue.start, f"cue {k} start"), seconds, cue.expression, int(level)))
    result.sort(key=lambda c: c[0])  # stable: cues at one instant apply in the order given
    return result


def _state(seg: tuple[float, float, float, float, float], at: float) -> tuple[float, float]:
    """Value and slope per second of one track's last segment at time ``at`` (>= its start)."""
    start, seconds, a_s, a_e, g = seg
    if seconds == 0 or at >= start + seconds:
        return a_e, 0.0
    u = (at - start) / seconds
    value = float(hermite(u, a_s, a_e, g))
    if not 0.0 <= value <= FULL_INTENSITY:  # clipped here, so flat
        return min(max(value, 0.0), float(FULL_INTENSITY)), 0.0
    return value, float(hermite_slope(u, a_s, a_e, g)) / seconds


class _ExpressionTracks:
    """Each expression's transitions (start, seconds, a_s, a_e, g), added cue by cue in time order.

    Why a class: a long text's cues come sentence by sentence; a new transition starts from where
    its track is (value and slope, :func:`_state`), which needs only each track's last transition.
    :meth:`levels` reads the tracks at times not before those read last; :meth:`forget` drops the
    transitions no later time can reach, so memory stays flat."""

    def __init__(self) -> None:
        self.tracks: list[list[tuple[float, float, float, float, float]]] = [[] for _ in _EXPRESSION_NAMES]
        self.latest = -math.inf

    def add(self, checked: Sequence[tuple[float, float, str, int]]) -> None:
        """Cues as :func:`_checked_cues` gives them, none before a cue added earlier."""
        for start, seconds, name, level in checked:
            if start < self.latest:
                raise ValueError(f"a cue at {start} s comes after one at {self.latest} s: cues go in time order")
            self.latest = start
            for e, track in enumerate(self.tracks):
                target = float(level) if _EXPRESSION_NAMES[e] == name else 0.0
                value, slope = _state(track[-1], start) if track else (0.0, 0.0)
                if not track and target == 0.0:
                    continue  # never shown and not asked for: stays at 0
                track.append((start, seconds, value, target, slope * seconds))

    def levels(self, t: np.ndarray) -> np.ndarray:
        """(n, k) intensities at ``t``."""
        out = np.zeros((len(t), len(_EXPRESSION_NAMES)))
        for e, track in enumerate(self.tracks):
            if not track:
                continue
            starts, seconds, a_s, a_e, g = (np.array(col) for col in zip(*track))
            idx = np.searchsorted(starts, t, side="right") - 1
            live = idx >= 0
            i, tt = idx[live], t[live]
            moving = (seconds[i] > 0) & (tt < starts[i] + seconds[i])
            u = np.where(moving, (tt - starts[i]) / np.where(seconds[i] > 0, seconds[i], 1.0), 1.0)
            curve = _hermite_rows(np.clip(u, 0.0, 1.0), a_s[i], a_e[i], g[i])
            out[live, e] = np.clip(curve, 0.0, FULL_INTENSITY)
        return out

    def forget(self, before: float) -> None:
        """Drop transitions that times from ``before`` on cannot read (each track keeps the one in force)."""
        for e, track in enumerate(self.tracks):
            k = 0
            while k + 1 < len(track) and track[k + 1][0] <= before:
                k += 1
            if k:
                del track[:k]


def expression_intensities(cues: Sequence[ExpressionCue],
                           times: npt.ArrayLike) -> tuple[tuple[str, ...], np.ndarray]:
    """Each expression's intensity (n, k float, 0..63) at ``times``, with the k names (no ``neutral``).

    The intensities stay fractional so the FAP track moves smoothly; see the
    module docstring for the fade rule and how a moving transition continues.
    """
    t = _times(times)
    tracks = _ExpressionTracks()
    tracks.add(_checked_cues(cues))
    return _EXPRESSION_NAMES, tracks.levels(t)


def expression_track(cues: Sequence[ExpressionCue], times: npt.ArrayLike) -> np.ndarray:
    """Low-level FAPs (n, 68) of the expressions: ``sum(profile * intensity / 63)``."""
    _, levels = expression_intensities(cues, times)
    return _expression_rows(levels)


def _expression_rows(levels: np.ndarray) -> np.ndarray:
    """(n, 68) FAPs of (n, k) intensities: ``sum(profile * intensity / 63)``, row by row alike."""
    return levels @ _EXPRESSION_STACK / FULL_INTENSITY


def expression_fields(cues: Sequence[ExpressionCue], times: npt.ArrayLike) -> ExpressionFields:
    """FAP 2's select1/intensity1/select2/intensity2 per frame: the two strongest expressions.

    Ties go to the earlier expression in ``EXPRESSION_PROFILES`` order, so the
    choice is stable from frame to frame; a rounded intensity of 0 reads ``neutral``.
    """
    names, levels = expression_intensities(cues, times)
    return _expression_field_rows(levels)


def _expression_field_rows(levels: np.ndarray) -> ExpressionFields:
    """:func:`expression_fields` from the (n, k) intensities."""
    names = _EXPRESSION_NAMES
    padded = np.concatenate([levels, np.zeros((len(levels), 2))], axis=1)  # always a first and second
    label = np.array(names + (NEUTRAL, NEUTRAL))
    order = np.argsort(-padded, axis=1, kind="stable")[:, :2]
    level = np.rint(np.take_along_axis(padded, order, axis=1)).astype(np.int64)
    select = np.where(level > 0, label[order], NEUTRAL)
    s1, s2, i1, i2 = select[:, 0], select[:, 1], level[:, 0], level[:, 1]
    return ExpressionFields(select1=s1, intensity1=i1, select2=s2, intensity2=i2)


# ---- merging ---------------------------------------------------------------------------------------

def merge_tracks(viseme: npt.ArrayLike, expression: npt.ArrayLike, *more: npt.ArrayLike) -> np.ndarray:
    """Merge (n, 68) tracks per FAP: largest positive value minus largest negative magnitude.

    Same sign: the larger magnitude wins, so a viseme and an expression moving
    the same point do not add up past either. Opposite signs: they partly
    cancel. The result is continuous in its inputs, which "larger magnitude
    keeps its sign" is not (it flips from +x to -x where two opposite values
    cross); it is symmetric and does not depend on the order of the tracks.
    """
    stack = np.stack(np.broadcast_arrays(*(np.asarray(x, dtype=np.float64) for x in (viseme, expression, *more))))
    return np.maximum(stack, 0.0).max(axis=0) - np.maximum(-stack, 0.0).max(axis=0)


# ---- idle behaviour --------------------------------------------------------------------------------

def _smoothstep(x: np.ndarray) -> np.ndarray:
    return hermite(np.clip(x, 0.0, 1.0), 0.0, 1.0)


def _blink_block(rng: np.random.Generator, last: float, lo: float, hi: float) -> np.ndarray:
    """The next 64 blink onsets after ``last``: blinks are drawn in fixed blocks, so a longer time
    only adds blinks, and a stream made piece by piece blinks as one made at once."""
    return last + np.cumsum(rng.uniform(lo, hi, size=64))


class IdleMotion:
    """Idle blinks and head motion as a function of time: :func:`idle_track` for times read piece by
    piece (non-decreasing), drawing blinks only as far as asked and forgetting those passed."""

    def __init__(self, seed: int, blinks: bool = True, head: bool = True, *,
                 blink_every: tuple[float, float] = (2.0, 6.0), blink_seconds: float = 0.15,
                 blink_amplitude: float = _LID_SHUT, head_degrees: tuple[float, float, float] = (1.5, 2.5, 1.0),
                 fade_in: float = 1.0) -> None:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
            raise ValueError(f"seed {seed!r} must be an integer")
        lo, hi = (_finite(x, "blink_every") for x in blink_every)
        length = _finite(blink_seconds, "blink_seconds")
        if not 0 < length < lo <= hi:
            raise ValueError(f"need 0 < blink_seconds < blink_every[0] <= blink_every[1], "
                             f"got {blink_seconds} and {blink_every}")
        self.blinks, self.head = blinks, head
        self.lo, self.hi, self.length, self.amplitude = lo, hi, length, float(blink_amplitude)
        self._rng, head_rng = (np.random.default_rng(s) for s in np.random.SeedSequence(int(seed)).spawn(2))
        self._onsets = np.zeros(0)
        self._last = 0.0
        self.fade = _finite(fade_in, "fade_in") if head else 0.0
        self._sway = []
        if head:
            for col, degrees in zip(_HEAD_COLUMNS, head_degrees):
                freq = head_rng.uniform(0.05, 0.3, size=3)
                phase = head_rng.uniform(0.0, 2 * math.pi, size=3)
                weight = head_rng.uniform(0.5, 1.0, size=3)
                weight /= weight.sum()
                self._sway.append((col, freq, phase, weight, _finite(degrees, "head_degrees")))

    def __call__(self, t: np.ndarray) -> np.ndarray:
        """(n, 68) idle FAPs at ``t`` (seconds from 0)."""
        out = np.zeros((len(t), N_FAPS))
        if self.blinks and len(t):
            until = float(t.max())
            blocks = [self._onsets]
            while self._last <= until:
                block = _blink_block(self._rng, self._last, self.lo, self.hi)
                blocks.append(block)
                self._last = float(block[-1])
            onsets = self._onsets = np.concatenate(blocks) if len(blocks) > 1 else self._onsets
            idx = np.searchsorted(onsets, t, side="right") - 1
            u = np.where(idx >= 0, (t - onsets[np.maximum(idx, 0)]) / self.length, np.inf)
            shut = np.where(u < 0.5, _smoothstep(3 * u), _smoothstep(3 * (1 - u)))
            shut = np.where((u >= 0) & (u < 1), shut, 0.0)
            for col in _BLINK_COLUMNS:
                out[:, col] = self.amplitude * shut
        if self.head:
            fade = self.fade
            envelope = _smoothstep(t / fade) if fade > 0 else (t >= 0).astype(np.float64)
            for col, freq, phase, weight, degrees in self._sway:
                sway = np.sin(2 * math.pi * freq * t[:, None] + phase) @ weight
                out[:, col] = degrees * _AU_PER_DEGREE * envelope * sway
        return out

    def forget(self, before: float) -> None:
        """Drop blink onsets that times from ``before`` on cannot read."""
        k = int(np.searchsorted(self._onsets, before, side="right")) - 1
        if k > 0:
            self._onsets = self._onsets[k:]


def idle_track(times: npt.ArrayLike, seed: int, blinks: bool = True, head: bool = True, *,
               blink_every: tuple[float, float] = (2.0, 6.0), blink_seconds: float = 0.15,
               blink_amplitude: float = _LID_SHUT, head_degrees: tuple[float, float, float] = (1.5, 2.5, 1.0),
               fade_in: float = 1.0) -> np.ndarray:
    """Idle blinks and head motion (n, 68) for ``times`` (seconds from 0), the same for the same seed.

    Blinks close both upper lids (FAP 19, 20) to ``blink_amplitude`` IRISD
    units (1024 = one iris diameter: shut) with gaps drawn uniformly from
    ``blink_every``; each closes, holds and opens in thirds of
    ``blink_seconds``, so at 25 fps a frame always sees the lid shut. The head
    (FAP 48-50, AU = 1e-5 rad) sways by three slow sines per axis (0.05-0.3 Hz)
    whose sum never exceeds ``head_degrees`` (pitch, yaw, roll), eased in over
    ``fade_in`` seconds so the stream starts at the neutral pose. Blinks and
    head use independent random streams: turning one off leaves the other as is.
    """
    t = _times(times)
    return IdleMotion(seed, blinks, head, blink_every=blink_every, blink_seconds=blink_seconds,
                      blink_amplitude=blink_amplitude, head_degrees=head_degrees, fade_in=fade_in)(t)


# ---- frames ----------------------------------------------------------------------------------------

def frame_times(duration: float, fps: float = 25.0) -> np.ndarray:
    """Times ``k / fps`` of the ``ceil(duration * fps)`` frames (at least 1) that cover ``duration``.

    Frame ``k`` is shown over ``[k/fps, (k+1)/fps)``, so the frames last
    ``n / fps >= duration``; the product is rounded to 9 digits first so that
    e.g. 0.28 s at 25 fps gives 7 frames, not 8.
    """
    d, rate = _finite(duration, "duration"), _finite(fps, "fps")
    if d < 0 or rate <= 0:
        raise ValueError(f"need duration >= 0 and fps > 0, got {duration} and {fps}")
    n = max(1, math.ceil(round(d * rate, 9)))
    return np.arange(n, dtype=np.float64) / rate
