"""How close an audio-only viseme track comes to a reference one (the transcript path's): what the
benchmark (tools/bench_lipsync_audio.py) and the tests measure.

* per-frame viseme agreement: :func:`mpeg4fa.speech.ipa.frame_agreement` (frames where both show a
  pause left out);
* closure onsets: where the lips shut (viseme ``PP``: p, b, m) in the reference, and whether the
  audio-only track shuts them within a tolerance (40 ms); the mean error of those found within
  :data:`NEAR`; and the closures the audio-only track adds where the reference has none (false
  closures: what a recogniser that shut the lips everywhere would score badly on). A ``PP`` of a
  bilabial fricative or approximant alone (Spanish intervocalic b/v, [β]: the lips near, not shut,
  and no silence in the sound) is no closure to find (:func:`shuts`), though a closure shown there is
  not a false one either. With ``from_rest``, a closure the reference begins from rest (at the start of the
  recording or straight after a pause: the neutral face's lips are already in contact, ISO/IEC 14496-2's
  neutral face, so the reference's onset there is no movement and the sound has none to hear, only silence
  before the release) counts as found where the other track also shows the lips shut or at rest at that
  onset (tools/bench_lipsync_audio.py: e.g. "Bill..." whose b starts the file, and Mandarin's p after
  espeak-ng's pause event, whose digital silence is the stop's closure yet lies outside the reference's PP);
* rest: the share of frames with the mouth closed or at rest (no viseme shown).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.speech.ipa import frame_agreement, parse
from mpeg4fa.speech.visemes import PAUSE

CLOSURE = "PP"
"""The viseme of p, b, m: the lips shut."""
TOLERANCE = 0.040
NEAR = 0.100
"""Onsets farther than this from any in the other track are a miss, not a large error."""


SHUT = frozenset({"stop", "nasal"})
"""Manners of a bilabial that shuts the lips (p, b, m); a fricative or approximant ([ɸ], [β]) only narrows them."""


def shuts(phoneme: str) -> bool:
    """Whether a ``PP`` timing's phoneme shuts the lips: not a bilabial fricative or approximant alone (its
    IPA, the part after ``:`` where the label names the event and the segment, read by
    :func:`mpeg4fa.speech.ipa.parse`; labels the tables do not read count as shut)."""
    segments, _ = parse(phoneme.split(":")[-1])
    bilabial = [s.manner for s in segments if s.place == "bilabial"]
    return not bilabial or any(m in SHUT for m in bilabial)


def closure_onsets(timings, shut_only: bool = False) -> np.ndarray:
    """Start times of the closures (runs of ``PP`` timings, joined where one follows another); with
    ``shut_only``, runs where no timing :func:`shuts` the lips left out."""
    runs: list[tuple[float, bool]] = []  # (start, whether any timing of the run shuts the lips)
    last_end = -1.0
    for t in sorted((t for t in timings if t.viseme == CLOSURE and t.end > t.start), key=lambda t: t.start):
        shut = not shut_only or shuts(t.phoneme)
        if runs and abs(t.start - last_end) <= 1e-6:
            runs[-1] = (runs[-1][0], runs[-1][1] or shut)
        else:
            runs.append((t.start, shut))
        last_end = t.end
    return np.array([start for start, shut in runs if shut])


def _shows(timings, at: np.ndarray, visemes: frozenset) -> np.ndarray:
    """Whether every timing of ``timings`` covering each time of ``at`` shows one of ``visemes`` (none: rest)."""
    ok = np.ones(len(at), dtype=bool)
    for t in timings:
        if t.viseme not in visemes and t.end > t.start:
            ok &= ~((at >= t.start) & (at < t.end))
    return ok


REST_BEFORE = 0.005
"""How far before a closure onset the reference must show rest for the onset to begin from rest."""


@dataclass(frozen=True)
class OnsetScore:
    """Closures of the reference (``reference``), found within the tolerance (``hits``), the mean
    error (s) of those within :data:`NEAR`, and closures of the other track near none (``extra``)."""

    reference: int
    hits: int
    errors: tuple[float, ...]
    extra: int

    @property
    def share(self) -> float:
        return self.hits / self.reference if self.reference else float("nan")

    @property
    def mean_error(self) -> float:
        return float(np.mean(self.errors)) if self.errors else float("nan")


def onset_score(reference, other, tolerance: float = TOLERANCE, from_rest: bool = False) -> OnsetScore:
    """:class:`OnsetScore` of ``other``'s closures against ``reference``'s (timings: phoneme, viseme, start,
    end): the closures to find are those that shut the lips; a closure of ``other`` is extra only where the
    reference shows none at all; ``from_rest``: see the module docstring (the errors stay those of onsets
    matched in time)."""
    ref, got, shown = closure_onsets(reference, shut_only=True), closure_onsets(other), closure_onsets(reference)
    far = np.abs(shown[:, None] - got[None, :]).min(axis=0) if len(shown) else np.full(len(got), np.inf)
    extra = int((far > NEAR).sum())
    if not len(ref):
        return OnsetScore(0, 0, (), extra)
    if not len(got):
        got = np.array([np.inf])
    nearest = np.abs(ref[:, None] - got[None, :]).min(axis=1)
    hit = nearest <= tolerance
    if from_rest:
        rested = _shows(reference, ref - REST_BEFORE, frozenset({PAUSE}))
        hit |= rested & _shows(other, ref, frozenset({PAUSE, CLOSURE}))
    hits = int(hit.sum())
    return OnsetScore(len(ref), hits, tuple(float(e) for e in nearest[nearest <= NEAR]), extra)


def agreement(reference, other, duration: float, fps: float = 25.0) -> tuple[float, int]:
    """Per-frame viseme agreement (:func:`~mpeg4fa.speech.ipa.frame_agreement`)."""
    return frame_agreement(reference, other, duration, fps)


def rest_share(timings, duration: float, fps: float = 25.0) -> float:
    """Share of frames (centres at ``fps``) where no viseme is shown: the mouth closed or at rest."""
    n = max(1, int(np.floor(duration * fps)))
    times = (np.arange(n) + 0.5) / fps
    moving = np.zeros(n, dtype=bool)
    for t in timings:
        if t.viseme != PAUSE:
            moving |= (times >= t.start) & (times < t.end)
    return float(1.0 - moving.mean())
