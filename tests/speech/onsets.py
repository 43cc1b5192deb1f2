"""Reading viseme onsets back out of a decoded high-level stream (FAP 1)."""
import numpy as np

from mpeg4fa.spec import VISEMES

NAMES = [v.name for v in VISEMES]


def _inverse_ease(w: np.ndarray) -> np.ndarray:
    """u for which the eased blend 3u^2 - 2u^3 equals w (0..1)."""
    grid = np.linspace(0, 1, 20001)
    return np.interp(w, 3 * grid**2 - 2 * grid**3, grid)


def recovered_onset(stream, start: float, end: float, viseme: str, fps: float) -> float | None:
    """When the viseme spanning [start, end] began, as the decoded FAP 1 says: the first frame inside
    the span names it, and its eased blend says how far into the span that frame is (None: not named)."""
    fields = np.repeat(stream.viseme, stream.skip + 1, axis=0)  # skipped repeats back on the frame grid
    k = int(np.ceil(start * fps - 1e-9))
    t = k / fps
    if t >= end or k >= len(fields) or NAMES[fields[k, 0]] != viseme:
        return None
    u = _inverse_ease(min(fields[k, 2], 63) / 63.0)
    return float(t - u * (end - start))
