"""Semantic stream checks: what a stream that parses may still get wrong (``validate --semantic``).

A stream can be valid syntax and still ask for things no face can show, name
visemes that do not exist, or run its clock backwards. These checks look at a
decoded :class:`~mpeg4fa.fba.stream.FapStream` (from a ``.fba``, a ``.fap`` or made
in memory) and report each problem once per rule and FAP, with the first frame,
the number of frames and the worst value, so a problem that fills a stream gives
one finding, not thousands. Severity says what to do: ``error`` the stream asks
for something the standard rules out or that cannot be coded; ``warning`` a
decoder must guess or clamp; ``info`` worth knowing (interoperability, defaults).

Rules (name, severity, source; [V]/[S]/[M] as in ``spec/SYNTAX.md``):

Values (FAPs 3-68, frames that send them):

* ``unidirectional-negative`` (error): a negative value on one of the five
  unidirectional FAPs (open_jaw, thrust_jaw, lift_l/r_cheek, tongue_roll). Their
  BIFS field range is [0, +I] (facts file, BIFS FAP node, from gpac
  ``mpeg4_nodes.c``) [S]; ``unidirectional`` in ``spec/faps.csv``.
* ``beyond-face`` (warning): a value beyond what a face can show, 8192 FAPU or a
  half turn for angles (:mod:`mpeg4fa.decoded.limits`, this project's bound: the
  standard sets none) [M]; decoders clamp.
* ``beyond-default-i-range`` (info): a value outside the FAP's default intra range
  (``i_max`` x ``quant_step`` FAPU, rounded up as the decoder does: ``spec/faps.csv``,
  facts file section 5.6) [S]. Legal when the stream sends its own ranges; a
  stream that relies on the defaults cannot carry it.
* ``beyond-default-p-range`` (info): a change from one frame to the next outside
  the default P range (``p_max`` x ``quant_step``), likewise [S].

FAP 1 and FAP 2 (``spec/high_level_fields.csv``):

* ``viseme-select`` / ``expression-select`` (error): a select outside 0..14 / 0..6
  (the tables ``visemes.csv`` and ``expressions.csv``) [V].
* ``blend-range`` (error): a viseme blend or expression intensity below 0 or
  above what the stream's fap_quant can code: 63 when unquantised, else the top
  level ((63 + q//2) // q) x q, e.g. 64 at q = 2 (SYNTAX.md section 7) [V at q = 1].
* ``flag-range`` (error): viseme_def, init_face or expression_def not 0 or 1 (1-bit fields) [V].
* ``table-redefinition`` (info): viseme_def or expression_def set: the stream
  redefines a viseme or expression; decoders with fixed tables (this one) ignore it [S].

Masks (SYNTAX.md section 5; a frame governed by an intra header):

* ``mask-type-0-sent`` (error): a FAP sent in a group whose mask type is 0 (nothing sent) [V].
* ``mask-type-3-unsent`` (error): a FAP unsent in a group whose mask type is 3 (all sent) [S].
* ``mask-not-intra`` (error): a frame's FAP mask differs from its intra header's
  mask; a P frame has no mask of its own, so the bitstream cannot say this [V].
* ``interpolation-never`` (info): a FAP left out of a mask type 2 group
  (interpolate) with no counterpart sent in that frame (``FAP_PARTNERS``:
  left/right, inner/outer lip): nothing to interpolate from, so it holds [M: type 2
  semantics are recalled from the standard].
* ``unsent-value`` (warning): FAP 1/2 fields or a FAP value that is not 0 in a frame
  that does not send it: an encoder drops it, so the stream does not mean what it says.

Time (SYNTAX.md sections 3 and 4):

* ``time-backwards`` (error): a frame earlier than the one before it (e.g. a
  time code that truncates to whole seconds re-anchors the clock back) [S].
* ``time-repeated`` (warning): two frames at the same time: one is never seen.
* ``time-mismatch`` (warning): a frame's time is not the previous one plus
  (skip + 1) / fps (beyond a time code's whole-second truncation): an encoder
  rebuilds time from fps and skip, so the stream would play differently [S].
* ``skip-negative`` (error): a negative skip count (the bitstream sends counts >= 0) [V].
* ``skip-long`` (warning): a skip that leaves more than :data:`LONG_GAP_S` seconds
  with no frame (a heuristic of this project) [M].

Frame rate (SYNTAX.md section 3):

* ``fps-invalid`` (error): a rate an intra header cannot carry (0, above 255 15/16,
  not a number: :func:`mpeg4fa.fba.limits.fps_problem`) [V].
* ``fps-not-representable`` (warning): a stream without a header rate (a ``.fap``)
  whose fps would be sent rounded to sixteenths (and 1000/1001) [V].
* ``fps-1001`` (info): the 1000/1001 flag: a decoder that computes it in integers
  (visage) gets 0 fps (SYNTAX.md section 13) [S].
* ``fps-unsent`` (info): no intra header sends a rate: decoders assume 30 [S].
"""
from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Callable

import numpy as np

from mpeg4fa.decoded.limits import LOWER, TRANSLATION_LIMIT, UPPER
from mpeg4fa.fba.limits import fps_problem
from mpeg4fa.fba.params import RANGE_DELTA
from mpeg4fa.fba.stream import DEFAULT_FPS, FapStream, FrameRate
from mpeg4fa.spec import FAP_GROUP, FAP_PARTNERS, FAPS, FULL_INTENSITY, HIGH_LEVEL_FIELDS, N_FAPS

__all__ = ["Finding", "Rule", "RULES", "SEVERITIES", "LONG_GAP_S", "semantic_findings", "summary"]

SEVERITIES = ("error", "warning", "info")
LONG_GAP_S = 10.0
"""A skip leaving more seconds than this without a frame is reported (``skip-long``)."""
_TIME_TOLERANCE = 1e-6
"""Seconds two times may differ by and still be the same (float sums of 1/fps)."""


@dataclass(frozen=True)
class Rule:
    """One documented check: its severity and what it says (the module docstring gives sources)."""

    severity: str
    summary: str


RULES: dict[str, Rule] = {
    "unidirectional-negative": Rule("error", "negative value on a unidirectional FAP"),
    "beyond-face": Rule("warning", "value beyond what a face can show"),
    "beyond-default-i-range": Rule("info", "value outside the FAP's default intra range"),
    "beyond-default-p-range": Rule("info", "change outside the FAP's default P range"),
    "viseme-select": Rule("error", "viseme select outside the viseme table"),
    "expression-select": Rule("error", "expression select outside the expression table"),
    "blend-range": Rule("error", "blend or intensity outside what the stream can code"),
    "flag-range": Rule("error", "a one-bit flag that is not 0 or 1"),
    "table-redefinition": Rule("info", "viseme_def or expression_def set"),
    "mask-type-0-sent": Rule("error", "FAP sent in a group of mask type 0"),
    "mask-type-3-unsent": Rule("error", "FAP unsent in a group of mask type 3"),
    "mask-not-intra": Rule("error", "frame mask differs from its intra header's"),
    "interpolation-never": Rule("info", "unsent FAP of a mask type 2 group with no counterpart sent"),
    "unsent-value": Rule("warning", "non-zero value in a frame that does not send it"),
    "time-backwards": Rule("error", "frame time earlier than the previous frame's"),
    "time-repeated": Rule("warning", "two frames at the same time"),
    "time-mismatch": Rule("warning", "frame time is not the previous one plus (skip + 1) / fps"),
    "skip-negative": Rule("error", "negative skip count"),
    "skip-long": Rule("warning", "skip leaving a long time without a frame"),
    "fps-invalid": Rule("error", "frame rate an intra header cannot carry"),
    "fps-not-representable": Rule("warning", "frame rate sent rounded"),
    "fps-1001": Rule("info", "1000/1001 frame rate (0 fps in integer decoders)"),
    "fps-unsent": Rule("info", "no frame rate sent (decoders assume 30)"),
}
"""Every rule a :class:`Finding` can name, with its severity."""
assert all(rule.severity in SEVERITIES for rule in RULES.values())


@dataclass(frozen=True)
class Finding:
    """One rule broken at one FAP (or by the stream as a whole), from ``frame`` on in ``count`` frames."""

    frame: int
    fap: int | None
    severity: str
    rule: str
    message: str
    count: int = 1
    worst: float | None = None
    """The value furthest from what the rule allows (FAPU, field value, seconds or fps)."""

    @property
    def fap_name(self) -> str | None:
        return FAPS[self.fap - 1].name if self.fap is not None else None

    def line(self, where: str) -> str:
        """``where: frame 12: FAP 3 (open_jaw): negative value -64 on a unidirectional FAP [error: rule]``."""
        fap = f"FAP {self.fap} ({self.fap_name}): " if self.fap is not None else ""
        return f"{where}: frame {self.frame}: {fap}{self.message} [{self.severity}: {self.rule}]"

    def as_dict(self) -> dict:
        return {**asdict(self), "fap_name": self.fap_name}


def summary(findings: list[Finding]) -> dict[str, int]:
    """Findings per severity (every severity present, 0 where none)."""
    return {s: sum(f.severity == s for f in findings) for s in SEVERITIES}


def semantic_findings(stream: FapStream) -> list[Finding]:
    """Every semantic finding of ``stream``, sorted by first frame, then FAP, then rule."""
    context = _Context(stream)
    findings: list[Finding] = []
    for check in (_values, _high_level, _masks, _time, _frame_rate):
        findings.extend(check(stream, context))
    return sorted(findings, key=lambda f: (f.frame, f.fap or 0, f.rule))


# ---- per-frame context ---------------------------------------------------------------------------


class _Context:
    """What each frame inherits from the intra header that governs it: fps, fap_quant, face params."""

    def __init__(self, stream: FapStream) -> None:
        n = len(stream)
        self.fps = np.full(n, float(stream.source_fps or DEFAULT_FPS))
        self.quant = np.zeros(n, dtype=np.int64)
        self.governed = np.zeros(n, dtype=bool)       # a face intra header governs the frame
        self.header_mask = np.zeros((n, N_FAPS), dtype=bool)
        self.time_coded = np.zeros(n, dtype=bool)
        for k in sorted(stream.intra):
            params = stream.intra[k]
            if params.frame_rate is not None and params.frame_rate.fps > 0:
                self.fps[k:] = params.frame_rate.fps
            if params.time_code is not None:
                self.time_coded[k] = True
            if params.face is not None:
                self.quant[k:] = params.face.quant
                self.governed[k:] = True
                self.header_mask[k:] = np.asarray(params.face.mask, dtype=bool)
        self.face = (np.asarray(stream.object_mask) & 1).astype(bool)


# ---- grouping ------------------------------------------------------------------------------------


def _per_column(rule: str, hits: np.ndarray, values: np.ndarray, excess: np.ndarray,
                one: Callable[[float], str], many: Callable[[int, float, float], str],
                fap_of: Callable[[int], int | None] = lambda col: col + 1) -> list[Finding]:
    """One finding per column of ``hits`` (frames x columns) that has any: first frame, count, worst.

    ``excess`` ranks how far each hit is from what is allowed (the worst is its largest); ``one(value)``
    words a single hit, ``many(count, first, worst)`` several.
    """
    out = []
    severity = RULES[rule].severity
    for col in np.flatnonzero(hits.any(axis=0)):
        frames = np.flatnonzero(hits[:, col])
        first = int(frames[0])
        worst_frame = int(frames[np.argmax(excess[frames, col])])
        first_value, worst = float(values[first, col]), float(values[worst_frame, col])
        message = one(first_value) if len(frames) == 1 else many(len(frames), first_value, worst)
        out.append(Finding(first, fap_of(int(col)), severity, rule, message, len(frames), worst))
    return out


def _single(rule: str, hits: np.ndarray, values: np.ndarray, excess: np.ndarray,
            one: Callable[[float], str], many: Callable[[int, float, float], str]) -> list[Finding]:
    """:func:`_per_column` for a per-frame rule (no FAP)."""
    return _per_column(rule, hits[:, None], values[:, None], excess[:, None], one, many, fap_of=lambda col: None)


def _frames(count: int) -> str:
    return f"{count} frame{'s' * (count != 1)}"


# ---- values ---------------------------------------------------------------------------------------


def _default_range(attr: str) -> np.ndarray:
    """Default range magnitude per FAP in FAPU (FAP 1/2: infinite): rounded up as the decoder rounds it."""
    out = np.full(N_FAPS, np.inf)
    for record in FAPS:
        magnitude = getattr(record, attr)
        if magnitude is not None:
            out[record.number - 1] = -(-magnitude // RANGE_DELTA) * RANGE_DELTA * record.quant_step
    return out


_I_RANGE, _P_RANGE = _default_range("i_max"), _default_range("p_max")
_LOW_LEVEL = np.arange(N_FAPS) >= 2


def _values(stream: FapStream, context: _Context) -> list[Finding]:
    values = np.asarray(stream.fap_values, dtype=np.float64)
    sent = np.asarray(stream.fap_mask, dtype=bool) & _LOW_LEVEL
    unidirectional = LOWER == 0.0
    findings = []
    negative = sent & unidirectional & (values < 0)
    findings += _per_column(
        "unidirectional-negative", negative, values, -values,
        lambda v: f"negative value {v:g} on a unidirectional FAP",
        lambda n, v, w: f"negative value on a unidirectional FAP in {_frames(n)} (first {v:g}, worst {w:g})")
    outside = sent & ~negative & ((values < LOWER) | (values > UPPER))
    findings += _per_column(
        "beyond-face", outside, values, np.abs(values),
        lambda v: f"value {v:g} is beyond what a face can show (+-{TRANSLATION_LIMIT} FAPU, a half turn for "
                  "angles): decoders clamp",
        lambda n, v, w: f"value beyond what a face can show in {_frames(n)} (first {v:g}, worst {w:g})")
    beyond_i = sent & (np.abs(values) > _I_RANGE)
    findings += _per_column(
        "beyond-default-i-range", beyond_i, values, np.abs(values),
        lambda v: f"value {v:g} is outside the default intra range (legal only with ranges of its own)",
        lambda n, v, w: f"value outside the default intra range in {_frames(n)} (first {v:g}, worst {w:g})")
    if len(stream) > 1:
        step = np.zeros_like(values)
        step[1:] = values[1:] - values[:-1]
        both = np.zeros_like(sent)
        both[1:] = sent[1:] & sent[:-1]
        beyond_p = both & (np.abs(step) > _P_RANGE)
        findings += _per_column(
            "beyond-default-p-range", beyond_p, step, np.abs(step),
            lambda v: f"change {v:+g} from the previous frame is outside the default P range",
            lambda n, v, w: f"change outside the default P range in {_frames(n)} (first {v:+g}, worst {w:+g})")
    return findings


# ---- FAP 1 and FAP 2 ------------------------------------------------------------------------------

_VISEME_FIELDS = tuple(f for f in HIGH_LEVEL_FIELDS if f.fap == 1)
_EXPRESSION_FIELDS = tuple(f for f in HIGH_LEVEL_FIELDS if f.fap == 2)
_PARTS = (  # FAP, stream attribute, coded fields (array columns in order), one-bit flags (columns after them)
    (1, "viseme", _VISEME_FIELDS, ("viseme_def",)),
    (2, "expression", _EXPRESSION_FIELDS, ("init_face", "expression_def")),
)


def _blend_top(quant: np.ndarray) -> np.ndarray:
    """Highest blend/intensity each frame's fap_quant can code (params.FieldCoder's range, in field units)."""
    q = np.maximum(quant, 1)
    return np.where(quant > 0, (FULL_INTENSITY + q // 2) // q * q, FULL_INTENSITY)


def _high_level(stream: FapStream, context: _Context) -> list[Finding]:
    findings = []
    top = _blend_top(context.quant)
    for fap, attr, fields, flags in _PARTS:
        table = np.asarray(getattr(stream, attr), dtype=np.int64)
        sent = np.asarray(stream.fap_mask, dtype=bool)[:, fap - 1]
        for k, field in enumerate(fields):
            column = table[:, k].astype(np.float64)
            name = f"{attr}_{field.field}"
            if field.quantised:
                high = top.astype(np.float64)
                rule, what = "blend-range", "what the stream's fap_quant can code"
            else:
                high = np.full(len(column), float(field.i_max))
                rule, what = f"{attr}-select", f"the {attr} table"
            bad = sent & ((column < field.i_min) | (column > high))
            excess = np.maximum(field.i_min - column, column - high)
            findings += _one_fap(rule, fap, bad, column, excess,
                                 lambda v, name=name, lo=field.i_min, what=what:
                                 f"{name} = {v:g} is outside {lo}..{_high_text(high, bad)} ({what})",
                                 lambda n, v, w, name=name, what=what:
                                 f"{name} outside {what} in {_frames(n)} (first {v:g}, worst {w:g})")
        for j, flag in enumerate(flags, start=len(fields)):
            column = table[:, j].astype(np.float64)
            bad = sent & (column != 0) & (column != 1)
            findings += _one_fap("flag-range", fap, bad, column, np.abs(column),
                                 lambda v, flag=flag: f"{flag} = {v:g} is not 0 or 1",
                                 lambda n, v, w, flag=flag: f"{flag} not 0 or 1 in {_frames(n)} (first {v:g}, worst {w:g})")
            if flag.endswith("_def"):
                defined = sent & (column == 1)
                findings += _one_fap("table-redefinition", fap, defined, column, column,
                                     lambda v, flag=flag: f"{flag} = 1: the stream redefines an entry; "
                                                          "decoders with fixed tables ignore it",
                                     lambda n, v, w, flag=flag: f"{flag} = 1 in {_frames(n)}: decoders with "
                                                                "fixed tables ignore the redefinition")
        unsent = ~sent & (table != 0).any(axis=1)
        findings += _one_fap("unsent-value", fap, unsent, np.abs(table).max(axis=1).astype(float),
                             np.abs(table).max(axis=1).astype(float),
                             lambda v, attr=attr: f"{attr} fields are not 0 but FAP {fap} is not sent",
                             lambda n, v, w, attr=attr: f"{attr} fields not 0 while FAP {fap} is not sent, in "
                                                        f"{_frames(n)}")
    return findings


def _high_text(high: np.ndarray, bad: np.ndarray) -> str:
    return f"{high[bad][0]:g}" if bad.any() else f"{high.max():g}"


def _one_fap(rule: str, fap: int, hits: np.ndarray, values: np.ndarray, excess: np.ndarray,
             one: Callable[[float], str], many: Callable[[int, float, float], str]) -> list[Finding]:
    return _per_column(rule, hits[:, None], values[:, None], excess[:, None], one, many, fap_of=lambda col: fap)


# ---- masks ----------------------------------------------------------------------------------------

_GROUP_OF = np.asarray(FAP_GROUP, dtype=np.int64) - 1   # column -> group index


def _masks(stream: FapStream, context: _Context) -> list[Finding]:
    mask = np.asarray(stream.fap_mask, dtype=bool)
    types = stream.group_mask_types()[:, _GROUP_OF]        # (n, 68): the type governing each FAP
    face = context.face[:, None]
    governed = (context.governed & context.face)[:, None]
    zeros = np.zeros(mask.shape)
    findings = _per_column("mask-type-0-sent", governed & (types == 0) & mask, zeros, zeros,
                           lambda v: "sent although its group has mask type 0 (nothing sent)",
                           lambda n, v, w: f"sent although its group has mask type 0, in {_frames(n)}")
    findings += _per_column("mask-type-3-unsent", governed & (types == 3) & ~mask, zeros, zeros,
                            lambda v: "not sent although its group has mask type 3 (all sent)",
                            lambda n, v, w: f"not sent although its group has mask type 3, in {_frames(n)}")
    findings += _per_column("mask-not-intra", governed & (mask != context.header_mask), mask.astype(float), zeros,
                            lambda v: f"{'sent' if v else 'not sent'}, unlike in its intra header's mask",
                            lambda n, v, w: f"sent or not unlike its intra header's mask, in {_frames(n)}")
    # Mask type 2: an unsent FAP copies a counterpart sent in the same frame; without one it only holds.
    partner_sent = np.zeros_like(mask)
    for k in range(FAP_PARTNERS.shape[1]):
        cols = FAP_PARTNERS[:, k]
        has = cols >= 0
        partner_sent[:, has] |= mask[:, cols[has]]
    stranded = face & (types == 2) & ~mask & ~partner_sent
    findings += _per_column("interpolation-never", stranded, zeros, zeros,
                            lambda v: "left to interpolation (mask type 2) with no counterpart sent: it holds",
                            lambda n, v, w: f"left to interpolation (mask type 2) with no counterpart sent, in "
                                            f"{_frames(n)}: it holds")
    values = np.abs(np.asarray(stream.fap_values, dtype=np.float64))
    unsent = ~mask & (values != 0) & _LOW_LEVEL
    findings += _per_column("unsent-value", unsent, np.asarray(stream.fap_values, dtype=np.float64), values,
                            lambda v: f"value {v:g} in a frame that does not send it",
                            lambda n, v, w: f"value not 0 in {_frames(n)} that do not send it (first {v:g}, "
                                            f"worst {w:g})")
    return findings


# ---- time -----------------------------------------------------------------------------------------


def _time(stream: FapStream, context: _Context) -> list[Finding]:
    n = len(stream)
    t = np.asarray(stream.timestamps, dtype=np.float64)
    skip = np.asarray(stream.skip, dtype=np.int64)
    findings = _single("skip-negative", skip < 0, skip.astype(float), -skip.astype(float),
                       lambda v: f"skip count {v:g} is negative",
                       lambda c, v, w: f"negative skip count in {_frames(c)} (first {v:g}, worst {w:g})")
    gap = (skip + 1) / context.fps
    findings += _single("skip-long", gap > LONG_GAP_S, gap, gap,
                        lambda v: f"skip leaves {v:g} s without a frame (more than {LONG_GAP_S:g} s)",
                        lambda c, v, w: f"skips leave more than {LONG_GAP_S:g} s without a frame after "
                                        f"{_frames(c)} (first {v:g} s, worst {w:g} s)")
    if n < 2:
        return findings
    step = np.zeros(n)
    step[1:] = t[1:] - t[:-1]
    expected = np.zeros(n)
    expected[1:] = t[:-1] + np.maximum(gap[:-1], 0)
    later = np.zeros(n, dtype=bool)
    later[1:] = True
    backwards = later & (step < -_TIME_TOLERANCE)
    repeated = later & (np.abs(step) <= _TIME_TOLERANCE)
    # A time code sends whole seconds: it may fall up to a second before the running clock.
    off = t - expected
    allowed = np.where(context.time_coded, 1.0, _TIME_TOLERANCE)
    mismatch = later & ~backwards & ~repeated & (np.abs(off) > allowed)
    findings += _single("time-backwards", backwards, step, -step,
                        lambda v: f"frame time goes back {-v:g} s from the previous frame",
                        lambda c, v, w: f"frame time goes back in {_frames(c)} (first {-v:g} s, worst {-w:g} s)")
    findings += _single("time-repeated", repeated, t, np.zeros(n),
                        lambda v: f"frame at {v:g} s, the same time as the previous frame",
                        lambda c, v, w: f"frame at the same time as the previous frame, in {_frames(c)}")
    findings += _single("time-mismatch", mismatch, off, np.abs(off),
                        lambda v: f"frame time is {v:+g} s off the previous frame plus (skip + 1) / fps",
                        lambda c, v, w: f"frame time off the previous frame plus (skip + 1) / fps in {_frames(c)} "
                                        f"(first {v:+g} s, worst {w:+g} s)")
    return findings


# ---- frame rate -----------------------------------------------------------------------------------


def _frame_rate(stream: FapStream, context: _Context) -> list[Finding]:
    findings = []
    rates = [(k, p.frame_rate) for k, p in sorted(stream.intra.items()) if p.frame_rate is not None]
    for k, rate in rates:
        problem = fps_problem(rate.fps)
        if problem is None and FrameRate.from_fps(rate.fps).fps != rate.fps:
            problem = f"frame rate fields {rate.frame_rate} + {rate.seconds}/16 do not fit the header"
        if problem is not None:
            findings.append(Finding(k, None, "error", "fps-invalid", problem, 1, float(rate.fps)))
        elif rate.frequency_offset:
            findings.append(Finding(k, None, "info", "fps-1001",
                                    f"frame rate {rate.fps:g} uses the 1000/1001 flag: a decoder that computes "
                                    "it in integers (visage) gets 0 fps", 1, float(rate.fps)))
    if rates or not len(stream):
        return findings
    fps = stream.fps
    if stream.intra:
        findings.append(Finding(0, None, "info", "fps-unsent",
                                f"no intra header sends a frame rate: decoders assume {DEFAULT_FPS:g} fps", 1, fps))
        return findings
    problem = fps_problem(fps)
    if problem is not None:
        findings.append(Finding(0, None, "error", "fps-invalid", problem, 1, float(fps)))
    elif (sent := FrameRate.from_fps(fps).fps) != fps:
        findings.append(Finding(0, None, "warning", "fps-not-representable",
                                f"frame rate {fps:g} cannot be sent exactly: it would be {sent:.6g}", 1, float(fps)))
    return findings
