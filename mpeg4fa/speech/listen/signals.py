"""Sounds that are not speech, made here so that the benchmark and the tests can check that a mouth stays at
rest through them: white noise at a given level, and a short piece of music (a melody of plucked notes over
held chords, with a hi-hat), both seeded."""
from __future__ import annotations

import numpy as np


def white_noise(seconds: float, rate: int = 16000, dbfs: float = -30.0, seed: int = 0) -> np.ndarray:
    """Gaussian white noise whose RMS is ``dbfs`` (float samples)."""
    n = int(round(seconds * rate))
    return np.random.default_rng(seed).standard_normal(n) * 10 ** (dbfs / 20)


def _note(f0: float, seconds: float, rate: int, decay: float, harmonics: int = 8) -> np.ndarray:
    t = np.arange(int(round(seconds * rate))) / rate
    tone = sum(np.sin(2 * np.pi * f0 * k * t) / k ** 1.2 for k in range(1, harmonics + 1) if f0 * k < rate / 2)
    return tone * np.exp(-t / decay) * np.minimum(1.0, t / 0.005)


def music(seconds: float, rate: int = 16000, dbfs: float = -18.0, seed: int = 0) -> np.ndarray:
    """A piece in C major at 120 bpm: a melody of plucked notes (eighths and quarters) over chords held a bar
    each, and a hi-hat on the off-beats; RMS ``dbfs`` (float samples)."""
    rng = np.random.default_rng(seed)
    n = int(round(seconds * rate))
    out = np.zeros(n + rate)
    scale = [261.63, 293.66, 329.63, 349.23, 392.00, 440.00, 493.88, 523.25]
    chords = [(130.81, 164.81, 196.00), (110.00, 130.81, 164.81), (87.31, 110.00, 130.81), (98.00, 123.47, 146.83)]
    t, bar = 0.0, 0
    while t < seconds:
        for f in chords[bar % 4]:
            a = int(t * rate)
            note = _note(f, 2.0, rate, 1.5, 6) * 0.25
            out[a:a + len(note)] += note[:len(out) - a]
        beat = 0.0
        while beat < 2.0 - 1e-9:
            length = 0.25 if rng.random() < 0.5 else 0.5
            a = int((t + beat) * rate)
            note = _note(scale[rng.integers(len(scale))], length, rate, 0.3) * 0.5
            out[a:a + len(note)] += note[:len(out) - a]
            hat = rng.standard_normal(int(0.03 * rate)) * np.exp(-np.arange(int(0.03 * rate)) / (0.008 * rate)) * 0.2
            h = int((t + beat + 0.25) * rate)
            out[h:h + len(hat)] += hat[:max(0, len(out) - h)]
            beat += length
        t += 2.0
        bar += 1
    out = out[:n]
    rms = np.sqrt(np.mean(out ** 2)) if n else 1.0
    return out / max(rms, 1e-12) * 10 ** (dbfs / 20)
