"""Which frames show the neutral face: the calmest stretch of the first seconds, or the one the user names.

Why: every FAP is a displacement from the neutral face and every FAPU is measured on it,
so a neutral taken mid-word or mid-blink shifts the whole stream. People usually start a
recording still, but not on frame 0 (they settle, blink, take a breath). So the default
looks over the first seconds for the window of frames where the face moves least and the
mouth is closed and the eyes open (a still grin is calm, but not neutral), and takes the
median of its frames (a blink inside the window does not count).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.tracking.faps import INDEX, RIGID
from mpeg4fa.tracking.pose import fit_similarity

SEARCH_SECONDS = 3.0
"""How far into the video the default neutral is looked for."""
WINDOW_SECONDS = 0.4
"""Length of the still stretch the neutral is the median of."""


@dataclass(frozen=True)
class NeutralChoice:
    """The frames the neutral is the median of, how it was chosen, and its points (MPEG-4 axes, pixels)."""

    first: int
    last: int  # inclusive
    how: str   # "calmest" or "given"
    points: np.ndarray
    motion: float  # mean frame-to-frame motion in the window, as a fraction of the eye distance

    def describe(self, fps: float) -> str:
        span = (f"frame {self.first}" if self.first == self.last else
                f"frames {self.first}-{self.last} ({self.first / fps:.2f}-{(self.last + 1) / fps:.2f} s)")
        if self.how == "given":
            return f"neutral face: {span}, as given"
        return f"neutral face: {span}, the calmest stretch of the first {SEARCH_SECONDS:g} s (--neutral to choose)"


def _aligned(points: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """Every frame's points mapped onto ``reference`` by its rigid points (head motion out)."""
    out = np.full_like(points, np.nan)
    for k, frame in enumerate(points):
        if np.isfinite(frame).all():
            pose = fit_similarity(reference[RIGID], frame[RIGID])
            out[k] = pose.to_neutral(frame)
    return out


def _median_of(points: np.ndarray, first: int, last: int) -> np.ndarray:
    window = points[first:last + 1]
    window = window[np.isfinite(window).all(axis=(1, 2))]  # the caller's window holds at least one face
    reference = window[len(window) // 2]
    return np.median(_aligned(window, reference), axis=0)


def given_neutral(points: np.ndarray, frame: int) -> NeutralChoice:
    """The neutral at the frame the user named (points ``(n, L, 3)``, NaN where no face was found)."""
    if not np.isfinite(points[frame]).all():
        raise ValueError(f"no face was found in frame {frame}")
    return NeutralChoice(frame, frame, "given", points[frame].copy(), 0.0)


def calmest_neutral(points: np.ndarray, fps: float) -> NeutralChoice | None:
    """The calmest, mouth-closed, eyes-open window in the first :data:`SEARCH_SECONDS` (None: no face in them)."""
    n = min(len(points), max(int(round(SEARCH_SECONDS * fps)), 1))
    seen = np.flatnonzero(np.isfinite(points[:n]).all(axis=(1, 2)))
    if not len(seen):
        return None
    reference = points[seen[0]]
    aligned = _aligned(points[:n], reference)
    eyes = float(np.linalg.norm(reference[INDEX["3.5"]] - reference[INDEX["3.6"]])) or 1.0
    valid = np.isfinite(aligned).all(axis=(1, 2))  # frames with a face (lost ones cost infinity)
    step = np.full(n, np.inf)
    if n > 1:
        moved = np.sqrt(((aligned[1:] - aligned[:-1]) ** 2).sum(axis=2).mean(axis=1)) / eyes
        step[1:] = np.where(valid[1:] & valid[:-1], moved, np.inf)
        step[0] = step[1] if valid[0] else np.inf
    elif valid[0]:
        step[0] = 0.0
    gap = np.abs(aligned[:, INDEX["2.2"], 1] - aligned[:, INDEX["2.3"], 1]) / eyes
    lids = (np.abs(aligned[:, INDEX["3.1"], 1] - aligned[:, INDEX["3.3"], 1])
            + np.abs(aligned[:, INDEX["3.2"], 1] - aligned[:, INDEX["3.4"], 1])) / eyes
    gap = np.where(valid, gap - gap[valid].min(), np.inf)
    shut = np.where(valid, lids[valid].max() - lids, np.inf)  # 0 for the widest-open eyes
    cost = step + 0.5 * gap + 0.25 * shut
    width = max(1, min(n, int(round(WINDOW_SECONDS * fps))))
    sums = np.convolve(cost, np.ones(width), mode="valid") / width
    first = int(np.argmin(sums))
    if not np.isfinite(sums[first]):  # no window without a lost frame: the best single frame
        first = int(seen[np.argmin(cost[seen])])
        width = 1
    last = first + width - 1
    return NeutralChoice(first, last, "calmest", _median_of(points, first, last),
                         float(np.nanmean(step[first:last + 1])))
