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
  not a false one either;
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


def onset_score(reference, other, tolerance: float = TOLERANCE) -> OnsetScore:
    """:class:`OnsetScore` of ``other``'s closures against ``reference``'s (timings: phoneme, viseme, start,
    end): the closures to find are those that shut the lips; a closure of ``other`` is extra only where the
    reference shows none at all (see the module docstring)."""
    ref, got, shown = closure_onsets(reference, shut_only=True), closure_onsets(other), closure_onsets(reference)
    far = np.abs(shown[:, None] - got[None, :]).min(axis=0) if len(shown) else np.full(len(got), np.inf)
    extra = int((far > NEAR).sum())
    if not len(ref) or not len(got):
        return OnsetScore(len(ref), 0, (), extra)
    nearest = np.abs(ref[:, None] - got[None, :]).min(axis=1)
    hits = int((nearest <= tolerance).sum())
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
