"""Train the bilabial closure detector of mpeg4fa.speech.listen.closures and write its weights
(mpeg4fa/speech/listen/closure_weights.py).

Data: espeak-ng speech of random pseudo-words (seeded; never the sentences tools/bench_lipsync_audio.py
scores) in English, Spanish, French, German (Latin letters), Mandarin (random characters) and Hindi
(random Devanagari syllables), in several voices and rates. The truth per 10 ms frame: inside a closure
(viseme PP) of the transcript path's track, :func:`mpeg4fa.speech.encoder.phones` of
:func:`mpeg4fa.speech.utterance.speak` (stops from their closure's silence), the very track the benchmark
compares with. Each utterance is used twice: as spoken, and filtered (a spectral tilt of +-4 dB an octave,
a low pass at 3.5-8 kHz, half the time a short room), at a random level, over noise, so that colour and
level do not decide. Model: log mel context (:func:`~mpeg4fa.speech.listen.closures.features`) -> 48 tanh
units -> logistic; Adam, cross-entropy, a little weight decay.

    .venv/bin/python tools/train_listen_closures.py [--per-language 150] [--epochs 10] [--seed 7]
"""
from __future__ import annotations

import argparse
import base64
import random
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.speech.align.recording import resample  # noqa: E402
from mpeg4fa.speech.encoder import phones  # noqa: E402
from mpeg4fa.speech.listen.closures import FIRST, HOP, RATE, features, log_mel, predict  # noqa: E402
from mpeg4fa.speech.markup import parse_markup  # noqa: E402
from mpeg4fa.speech.tts.espeak import EspeakEngine  # noqa: E402
from mpeg4fa.speech.utterance import speak  # noqa: E402

LATIN = {"en": ("p b m t d k g n f v s z l r w h sh ch th y j".split(), "a e i o u ai ee oo ay ow er".split()),
         "es": ("p b m t d k g n f s l r ll ch j v y ñ c".split(), "a e i o u ue ie".split()),
         "fr": ("p b m t d k g n f v s z l r ch j gn".split(), "a e i o u ou eau an on in é è".split()),
         "de": ("p b m t d k g n f w s z l r sch ch h pf".split(), "a e i o u ei au ie ü ö ä".split())}
DEVANAGARI = (list("पबमतदकगनफवसलरहजचटडयभथधखघ"), ["", "ा", "ि", "ी", "ु", "ू", "े", "ो", "ै"])
VOICES = {"en": ["en-us", "en-us+f3", "en-gb", "en-us+m3", "en-us+f1"], "es": ["es", "es+f3", "es+m2"],
          "fr": ["fr", "fr+f2", "fr+m3"], "de": ["de", "de+f3", "de+m1"], "cmn": ["cmn", "cmn+f3"],
          "hi": ["hi", "hi+f2"]}
RATES = (130, 150, 160, 175, 190)
HIDDEN = 48
OUT = Path(__file__).resolve().parents[1] / "mpeg4fa" / "speech" / "listen" / "closure_weights.py"


def pseudo_word(lang: str, rng: random.Random) -> str:
    """A random word-like string that espeak-ng reads in ``lang``."""
    if lang in LATIN:
        cons, vowels = LATIN[lang]
        word = "".join((rng.choice(cons) if rng.random() < 0.85 else "") + rng.choice(vowels)
                       for _ in range(rng.randint(1, 3)))
        return word + (rng.choice(cons) if rng.random() < 0.4 else "")
    if lang == "hi":
        return "".join(rng.choice(DEVANAGARI[0]) + rng.choice(DEVANAGARI[1]) for _ in range(rng.randint(1, 3)))
    return "".join(chr(rng.randint(0x4E00, 0x9000)) for _ in range(rng.randint(1, 3)))


def utterances(per_language: int, seed: int):
    """(samples float, rate, closure spans) of random pseudo-word sentences in every language."""
    rng, engine = random.Random(seed), EspeakEngine()
    for lang, voices in VOICES.items():
        for _ in range(per_language):
            text = " ".join(pseudo_word(lang, rng) for _ in range(rng.randint(4, 8)))
            text = text.capitalize() + "." if lang in LATIN else text + ("。" if lang == "cmn" else "।")
            voice = rng.choice(voices)
            ref = phones(speak(parse_markup(text), engine, lang="en" if lang == "en" else voice.split("+")[0],
                               voice=voice, rate=rng.choice(RATES)))
            spans = [(t.start, t.end) for t in ref.timings if t.viseme == "PP" and t.end > t.start]
            yield ref.speech.samples / 32768.0, ref.speech.rate, spans


def coloured(x: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """``x`` (16 kHz) tilted, low-passed, maybe in a small room, at a random level over noise."""
    f = np.fft.rfftfreq(len(x), 1 / RATE)
    tilt = rng.uniform(-4, 4) * np.log2(np.maximum(f, 100) / 1000)
    db = tilt - 40 * np.clip((f - rng.uniform(3500, 8000)) / 1000, 0, None)
    y = np.fft.irfft(np.fft.rfft(x) * 10 ** (db / 20), len(x))
    if rng.random() < 0.5:
        n = int(0.03 * RATE)
        room = rng.standard_normal(n) * np.exp(-np.arange(n) / (rng.uniform(0.003, 0.012) * RATE))
        room[0] = 1.0 / rng.uniform(0.2, 0.6)
        y = np.convolve(y, room / np.abs(room).sum() * 3)[:len(y)]
    y = y / (np.sqrt(np.mean(y ** 2)) + 1e-9) * 10 ** (rng.uniform(-30, -15) / 20)
    return y + rng.standard_normal(len(y)) * 10 ** (rng.uniform(-80, -50) / 20)


def dataset(per_language: int, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Features and truth (1 inside a closure) of every frame, each utterance plain and coloured."""
    rng = np.random.default_rng(seed)
    xs, ys = [], []
    for samples, rate, spans in utterances(per_language, seed):
        x = resample(samples, rate, RATE)
        for version in (x, coloured(x, rng)):
            levels = log_mel(version)
            centre = FIRST + (np.arange(len(levels)) + 0.5) * HOP / RATE
            y = np.zeros(len(levels))
            for a, b in spans:
                y[(centre >= a) & (centre < b)] = 1.0
            xs.append(features(levels))
            ys.append(y)
    return np.vstack(xs), np.concatenate(ys)


def train(x: np.ndarray, y: np.ndarray, epochs: int, seed: int, rate: float = 3e-3,
          batch: int = 512, decay: float = 1e-4) -> tuple[np.ndarray, np.ndarray]:
    """One tanh layer and a logistic output, Adam on cross-entropy."""
    rng = np.random.default_rng(seed)
    hidden = rng.standard_normal((x.shape[1], HIDDEN)) / np.sqrt(x.shape[1])
    out = rng.standard_normal(HIDDEN + 1) / np.sqrt(HIDDEN)
    params = [hidden, out]
    m1, m2 = [np.zeros_like(p) for p in params], [np.zeros_like(p) for p in params]
    step = 0
    for _ in range(epochs):
        order = rng.permutation(len(x))
        for k in range(0, len(x), batch):
            i = order[k:k + batch]
            h = np.tanh(x[i] @ hidden)
            p = 1.0 / (1.0 + np.exp(-(h @ out[:-1] + out[-1])))
            g = (p - y[i]) / len(i)
            grads = [x[i].T @ (np.outer(g, out[:-1]) * (1 - h * h)) + decay * hidden, np.r_[h.T @ g, g.sum()]]
            step += 1
            for j, (param, grad) in enumerate(zip(params, grads)):
                m1[j] = 0.9 * m1[j] + 0.1 * grad
                m2[j] = 0.999 * m2[j] + 0.001 * grad * grad
                param -= rate * (m1[j] / (1 - 0.9 ** step)) / (np.sqrt(m2[j] / (1 - 0.999 ** step)) + 1e-8)
    return hidden, out


def write(hidden: np.ndarray, out: np.ndarray, note: str) -> None:
    def b64(a):
        text = base64.b64encode(a.astype("<f2").tobytes()).decode()
        return "\n".join(f'    "{text[k:k + 100]}"' for k in range(0, len(text), 100))

    OUT.write_text(f'"""Weights of the closure detector (:mod:`.closures`), float16 little-endian in base64.\n\n'
                   f"Written by tools/train_listen_closures.py: {note}.\n\"\"\"\n"
                   f"SHAPE = {hidden.shape}\nHIDDEN = (\n{b64(hidden)}\n)\nOUTPUT = (\n{b64(out)}\n)\n", encoding="utf-8")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--per-language", type=int, default=150)
    ap.add_argument("--epochs", type=int, default=10)
    ap.add_argument("--seed", type=int, default=7)
    args = ap.parse_args()
    started = time.perf_counter()
    x, y = dataset(args.per_language, args.seed)
    print(f"{len(x)} frames, {y.mean():.1%} inside a closure ({time.perf_counter() - started:.0f} s)")
    hidden, out = train(x, y, args.epochs, args.seed)
    vx, vy = dataset(max(10, args.per_language // 5), args.seed + 1000)
    p = predict(vx, hidden, out) > 0.5
    recall, precision = (p & (vy > 0)).sum() / max(1, (vy > 0).sum()), (p & (vy > 0)).sum() / max(1, p.sum())
    note = (f"{args.per_language} sentences a language, seed {args.seed}, {args.epochs} epochs; held-out frames "
            f"(seed {args.seed + 1000}) at 0.5: recall {recall:.2f}, precision {precision:.2f}")
    write(hidden, out, note)
    print(f"{note} ({time.perf_counter() - started:.0f} s); wrote {OUT.relative_to(OUT.parents[3])}")


if __name__ == "__main__":
    main()
