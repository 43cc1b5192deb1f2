"""Dynamic time warping of two recordings on spectral features: the aligner for any language.

Features: 25 ms Hann frames every 10 ms at 16 kHz, 40 mel bands (80-7600 Hz), log, DCT-II to
cepstral coefficients 1-12 plus the frame's log energy, each normalised to zero mean and unit
variance over its recording (so that two voices' spectral tilt and loudness cancel), with their
deltas. Distance: Euclidean. Path: the symmetric step pattern (diagonal steps weigh twice),
inside a Sakoe-Chiba band around the straight line from start to end. Each row of the cost
matrix is done at once: a horizontal run is a prefix minimum over the row's cumulative cost
(``D[j] = S[j] + min_{k<=j}(A[k] - S[k])``), so the only Python loop is over rows.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

from mpeg4fa.speech.align.recording import HOP

RATE = 16000
WINDOW = 0.025
MEL_BANDS = 40
CEPSTRA = 12


@lru_cache(maxsize=4)
def _mel_bank(n_fft: int, rate: int, n_mels: int, alpha: float = 1.0, low: float = 80.0,
              high: float = 7600.0) -> np.ndarray:
    mel = lambda f: 2595.0 * np.log10(1.0 + f / 700.0)  # noqa: E731
    hz = lambda m: 700.0 * (10 ** (m / 2595.0) - 1.0)  # noqa: E731
    edges = hz(np.linspace(mel(low), mel(high), n_mels + 2))
    freqs = np.fft.rfftfreq(n_fft, 1.0 / rate) / alpha  # alpha > 1: a shorter vocal tract's formants moved down
    bank = np.zeros((n_mels, len(freqs)))
    for k in range(n_mels):
        a, c, b = edges[k], edges[k + 1], edges[k + 2]
        bank[k] = np.clip(np.minimum((freqs - a) / (c - a), (b - freqs) / (b - c)), 0.0, None)
    return bank


def features(x: np.ndarray, rate: int = RATE, alpha: float = 1.0) -> np.ndarray:
    """(frames, 26) normalised cepstra + log energy and their deltas of ``x`` (float mono at ``rate``);
    ``alpha`` scales the frequency axis (vocal tract length normalisation)."""
    hop, win = int(round(HOP * rate)), int(round(WINDOW * rate))
    n_fft = 1 << (win - 1).bit_length()
    frames = max(1, (len(x) - win) // hop + 1) if len(x) >= win else 1
    padded = np.pad(np.asarray(x, dtype=np.float64), (win // 2, win + hop))
    idx = np.arange(frames)[:, None] * hop + np.arange(win)[None, :]
    seg = padded[idx] * np.hanning(win)[None, :]
    power = np.abs(np.fft.rfft(seg, n_fft, axis=1)) ** 2
    logmel = np.log(power @ _mel_bank(n_fft, rate, MEL_BANDS, round(alpha, 4)).T + 1e-8)
    k = np.arange(MEL_BANDS)
    dct = np.cos(np.pi / MEL_BANDS * (k[None, :] + 0.5) * np.arange(1, CEPSTRA + 1)[:, None])
    ceps = logmel @ dct.T
    energy = np.log((seg ** 2).sum(axis=1) + 1e-8)[:, None]
    f = np.hstack([ceps, energy])
    f = (f - f.mean(axis=0)) / (f.std(axis=0) + 1e-8)
    delta = np.gradient(f, axis=0) if len(f) > 1 else np.zeros_like(f)
    return np.hstack([f, delta])


MAX_RADIUS = 1500
"""The band's half-width is at most 15 s: the path's memory is one byte a cell, 3000 cells a frame."""


def band_radius(n: int, m: int) -> int:
    """Half-width of the band around the line from start to end, frames: a fifth of the longer
    recording, at least 0.4 s, at most :data:`MAX_RADIUS`."""
    return int(max(40, min(0.2 * max(n, m), MAX_RADIUS)))


def dtw_path(a: np.ndarray, b: np.ndarray, radius: int | None = None) -> np.ndarray:
    """The warping path between feature rows ``a`` (n, d) and ``b`` (m, d): (k, 2) index pairs, from
    (0, 0) to (n-1, m-1), each step one of (1,1), (1,0), (0,1)."""
    n, m = len(a), len(b)
    r = band_radius(n, m) if radius is None else int(radius)
    centre = np.arange(n) * ((m - 1) / max(n - 1, 1))
    lo = np.clip(np.floor(centre - r).astype(int), 0, m - 1)
    hi = np.clip(np.ceil(centre + r).astype(int) + 1, 1, m)
    lo[0], hi[-1] = 0, m
    lo = np.minimum.accumulate(lo[::-1])[::-1]  # keep the band's edges monotone
    hi = np.maximum.accumulate(hi)
    width = int((hi - lo).max())
    move = np.zeros((n, width), dtype=np.int8)  # 0 diagonal, 1 from below (i-1), 2 from the left (j-1)
    prev = None  # the previous row's cumulative costs (only the moves are kept for the way back)
    for i in range(n):
        j0, j1 = lo[i], hi[i]
        cost = np.sqrt(((b[j0:j1] - a[i]) ** 2).sum(axis=1))
        if prev is None:
            row = np.cumsum(cost)
            step = np.full(j1 - j0, 2, dtype=np.int8)
            step[0] = 0
        else:
            p0, p1, pd = lo[i - 1], hi[i - 1], prev
            up = np.full(j1 - j0, np.inf)  # D[i-1, j]
            diag = np.full(j1 - j0, np.inf)  # D[i-1, j-1]
            js = np.arange(j0, j1)
            ok = (js >= p0) & (js < p1)
            up[ok] = pd[js[ok] - p0]
            ok = (js - 1 >= p0) & (js - 1 < p1)
            diag[ok] = pd[js[ok] - 1 - p0]
            a_diag, a_up = diag + 2 * cost, up + cost
            first = np.where(a_diag <= a_up, a_diag, a_up)
            first_step = np.where(a_diag <= a_up, 0, 1).astype(np.int8)
            s = np.cumsum(cost)
            best = np.minimum.accumulate(first - s)
            row = s + best
            step = np.where(row < first - 1e-9, 2, first_step).astype(np.int8)
        move[i, :j1 - j0] = step
        prev = row
    path = []
    i, j = n - 1, m - 1
    while True:
        path.append((i, j))
        if i == 0 and j == 0:
            break
        s = move[i, j - lo[i]]
        if i == 0:
            j -= 1
        elif s == 0:
            i, j = i - 1, j - 1
        elif s == 1:
            i -= 1
        else:
            j -= 1
    return np.array(path[::-1])


def warp_anchors(path: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(reference times, recording times), seconds: for each reference frame the mean recording frame
    it was matched with, from the path (``path[:, 0]`` reference, ``path[:, 1]`` recording)."""
    ref = path[:, 0]
    counts = np.bincount(ref)
    sums = np.bincount(ref, weights=path[:, 1])
    keep = counts > 0
    return np.flatnonzero(keep) * HOP, sums[keep] / counts[keep] * HOP


ALPHAS = (0.9, 1.0, 1.1, 1.2, 1.3)
"""Frequency scales tried on the recording (a deep voice 0.9, espeak-ng's male voices 1.0, women ~1.2,
children ~1.3); the one whose path costs least wins. On espeak-ng's female en-us+f3 voice against the
male reference this lifts onsets within 30 ms from 82 % to 97 % (tools/bench_align.py)."""


def align(reference: np.ndarray, recording: np.ndarray, rate: int = RATE,
          alphas: tuple[float, ...] = ALPHAS, coarse: int = 3) -> tuple[np.ndarray, float, float]:
    """DTW of ``reference`` to ``recording`` (float mono at ``rate``), the recording's frequency axis
    scaled by the one of ``alphas`` whose path costs least, chosen on every ``coarse``-th frame (a ninth
    of the work each): (path, the alpha chosen, its mean distance along the full path)."""
    a = features(reference, rate)
    best: tuple[float, float] | None = None
    for alpha in alphas if len(alphas) > 1 else ():
        b = features(recording, rate, alpha)
        path = dtw_path(a[::coarse], b[::coarse])
        cost = float(np.sqrt(((a[::coarse][path[:, 0]] - b[::coarse][path[:, 1]]) ** 2).sum(axis=1)).mean())
        if best is None or cost < best[0]:
            best = (cost, alpha)
    alpha = best[1] if best is not None else alphas[0]
    b = features(recording, rate, alpha)
    path = dtw_path(a, b)
    return path, alpha, float(np.sqrt(((a[path[:, 0]] - b[path[:, 1]]) ** 2).sum(axis=1)).mean())
