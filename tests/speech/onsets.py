"""Reading viseme timing back out of a decoded high-level stream (FAP 1), without the face engine."""
import numpy as np

from mpeg4fa.spec import VISEMES

NAMES = [v.name for v in VISEMES]
TOLERANCE = 0.03
"""A weight this close to the top counts as at the top (FAP 1 blend is quantised in steps of 1/63 or more)."""


def fap1_weight(stream, viseme: str) -> np.ndarray:
    """Per frame on the frame grid: how much of ``viseme`` FAP 1 shows (select1 x blend/63 +
    select2 x (1 - blend/63)), skipped repeats put back."""
    fields = np.repeat(stream.viseme, stream.skip + 1, axis=0)
    code = NAMES.index(viseme)
    w = np.clip(fields[:, 2], 0, 63) / 63.0
    return np.where(fields[:, 0] == code, w, 0.0) + np.where(fields[:, 1] == code, 1.0 - w, 0.0)


def reached(stream, spans, k: int, fps: float) -> tuple[float, float]:
    """When FAP 1 shows span ``k``'s viseme most, and how much: the first frame within TOLERANCE of
    the top weight, from the middle of the span before to the span's end."""
    span = spans[k]
    lo = (spans[k - 1].start + spans[k - 1].end) / 2 if k > 0 else -np.inf
    w = fap1_weight(stream, span.viseme)
    t = np.arange(len(w)) / fps
    inside = np.flatnonzero((t >= lo) & (t < span.end))
    top = w[inside].max()
    first = inside[np.flatnonzero(w[inside] >= top - TOLERANCE)[0]]
    return float(t[first]), float(top)
