"""Where the lips shut, from the signal: a small detector of bilabial closures (p, b, m) that refines what
pocketsphinx's phone loop hears.

The phone loop (:mod:`.phones`) misses about half of the p, b and m of synthetic voices: it hears a
voiced b as G, a nasal murmur or a stop's silence as SIL (tools/bench_lipsync_audio.py). The detector
looks at the spectrum around each 10 ms frame (24 log mel bands, +-100 ms, relative to the recording's
loud end) and gives the probability that the lips are shut there; a one-hidden-layer network trained by
tools/train_listen_closures.py on espeak-ng speech of random pseudo-words in six languages (never the
benchmark's sentences), with their known phone times, filtered, reverberated and noised so that a
recording's colour and level do not decide. Its weights are :mod:`.closure_weights`.

:func:`refine_closures` combines the two: a labial the recogniser heard starts where the detector's
closure starts (within :data:`SNAP`), and is not shut where the detector finds none (:data:`CONFIRM`). Which
of the detector's spans shut the lips a second small network decides (:func:`span_scores`, :data:`KEEP`): it
sees the span's probabilities, the spectrum before, in and after it (a labial's formants fall into the
closure and its burst is low) and the phones the recogniser heard at its start, end and after it; before it
(and where the weights hold none) a span was shut where a labial was heard near it or the detector was sure
of it (:data:`SURE`, at least :data:`LONGEST_UNHEARD` long), which shut the silence of t, d, k and g too
(tools/bench_lipsync_audio.py: Hindi's ʈʰ, English d after a vowel).
"""
from __future__ import annotations

import base64
from functools import lru_cache

import numpy as np

from mpeg4fa.speech.align.recording import Recording, resample

RATE = 16000
HOP = 160
WINDOW = 400
NFFT = 512
BANDS = 24
FLOOR_DB = -60.0
"""Levels below the loud end by more than this read as this: digital zero and a noise floor alike."""
CONTEXT = np.arange(-10, 11, 2)
"""Frames (10 ms) either side that the detector sees."""
FIRST = (WINDOW / 2) / RATE - HOP / RATE / 2
"""Start (s) of frame 0's 10 ms slot: frame k is centred at k * 10 ms + 12.5 ms."""
LABIALS = frozenset({"P", "B", "M"})
THRESHOLD = 0.2
"""Probability above which a frame is a closure (spans of two frames or more)."""
SNAP = 0.06
"""A recognised labial that starts this close to a detected closure takes the closure's start."""
UNSHUT = {"P": "T", "B": "D", "M": "N"}
"""With :data:`CONFIRM`, a labial the recogniser heard where the detector finds no closure starting within
:data:`SNAP` is read as the alveolar of its manner: the lips stay open (the phone loop's false p, b, m on
espeak-ng speech were heard over d, n, t, r, v and ð, tools/bench_lipsync_audio.py)."""
CONFIRM = True
OPEN = frozenset("AA AE AH AO AW AY EH ER EY IH IY OW OY UH UW HH S Z SH ZH".split())
"""Phones heard with the mouth open or the tongue making the sound: with :data:`OPEN_VETO`, a closure the
recogniser heard only as these is not shut on the detector's word alone (introduced for recordings of people,
where the detector of the time alone was right 2 times in 29, tools/bench_lipsync_audio.py --human)."""
OPEN_VETO = False
KEEP = 0.5
"""Score (:func:`span_scores`) from which a detector span is shut, chosen on held-out pseudo-word speech
(tools/train_listen_closures.py --spans --per-language 300 --seed 17: its grid, 30 sentences a language as
spoken and coloured, seed 2017) as the most onsets within 40 ms plus precision: 74.6 % at 81.4 %, where the
heard/sure rule below gave 71.1 % at 69.2 % on the same speech (0.3: 78.5 % at 76.6 %; 0.7: 68.8 % at 83.6 %).
Where the weights hold no span scorer the heard/sure rule decides."""
SURE = 0.7
LONGEST_UNHEARD = 3
"""A closure no labial was heard in is shut when its peak probability reaches :data:`SURE` over at least
this many frames. :data:`SURE`, :data:`LONGEST_UNHEARD`, :data:`OPEN_VETO` and :data:`CONFIRM` are chosen on
held-out pseudo-word speech (tools/train_listen_closures.py --grid-only --per-language 300: 30 sentences a
language, seed 2007, these weights): the most onsets within 40 ms at a precision of 75 % or more (the floor
the choice before kept): 82.4 % at 75.7 %, where the constants before (0.8, 3, veto, no confirmation) gave
73.2 % at 75.8 %. The veto cost 7-9 points of onsets at every setting there and gained no precision; it is not
measured again on recordings of people (none here). Settings with more precision and fewer onsets: 0.8 over 2
frames, 81.2 % at 79.3 %; threshold 0.3, 0.8 over 3, 77.1 % at 84.8 %."""


@lru_cache(maxsize=1)
def mel_bank() -> np.ndarray:
    """Triangular mel filters, 80-7600 Hz, each summing to one (BANDS x NFFT/2+1)."""
    def to_mel(f):
        return 2595 * np.log10(1 + np.asarray(f) / 700)

    edges = 700 * (10 ** (np.linspace(to_mel(80), to_mel(7600), BANDS + 2) / 2595) - 1)
    bins = np.fft.rfftfreq(NFFT, 1 / RATE)
    lo, mid, hi = edges[:-2, None], edges[1:-1, None], edges[2:, None]
    bank = np.clip(np.minimum((bins - lo) / (mid - lo), (hi - bins) / (hi - mid)), 0, None)
    return bank / bank.sum(axis=1, keepdims=True)


def log_mel(x: np.ndarray) -> np.ndarray:
    """``x`` (float, 16 kHz) -> (frames, BANDS) levels in units of 20 dB below the loud end (95th
    percentile of the frames' loudest band), floored at :data:`FLOOR_DB`: a level-free picture."""
    n = max(0, (len(x) - WINDOW) // HOP + 1)
    if n == 0:
        return np.zeros((0, BANDS))
    frames = np.lib.stride_tricks.sliding_window_view(x, WINDOW)[::HOP][:n] * np.hanning(WINDOW)
    power = np.abs(np.fft.rfft(frames, NFFT)) ** 2
    db = 10 * np.log10(power @ mel_bank().T + 1e-12)
    return np.maximum(db - np.percentile(db.max(axis=1), 95), FLOOR_DB) / 20.0


def features(levels: np.ndarray) -> np.ndarray:
    """Each frame's context (:data:`CONTEXT`), its slope (next minus previous frame) and a bias input."""
    n = len(levels)
    k = np.arange(n)
    context = levels[np.clip(k[:, None] + CONTEXT[None, :], 0, n - 1)].reshape(n, -1)
    slope = levels[np.minimum(k + 1, n - 1)] - levels[np.maximum(k - 1, 0)]
    return np.hstack([context, slope, np.ones((n, 1))])


@lru_cache(maxsize=1)
def weights() -> tuple[np.ndarray, np.ndarray]:
    """The detector's layers (:mod:`.closure_weights`, float16 in base64)."""
    from mpeg4fa.speech.listen import closure_weights as w

    hidden = np.frombuffer(base64.b64decode(w.HIDDEN), "<f2").astype(np.float64).reshape(w.SHAPE)
    out = np.frombuffer(base64.b64decode(w.OUTPUT), "<f2").astype(np.float64)
    return hidden, out


def predict(x: np.ndarray, hidden: np.ndarray, out: np.ndarray) -> np.ndarray:
    """The network: tanh hidden layer, logistic output."""
    h = np.tanh(x @ hidden)
    return 1.0 / (1.0 + np.exp(-(h @ out[:-1] + out[-1])))


def closure_probability(samples: np.ndarray, rate: int) -> np.ndarray:
    """Probability that the lips are shut, per 10 ms frame of ``samples`` (float, any rate)."""
    levels = log_mel(resample(np.asarray(samples, dtype=np.float64), rate, RATE))
    if not len(levels):
        return np.zeros(0)
    return predict(features(levels), *weights())


def closure_spans(probability: np.ndarray, threshold: float = THRESHOLD) -> list[tuple[float, float, float]]:
    """Runs of two frames or more above ``threshold``: (start s, end s, peak probability)."""
    on = np.r_[False, probability > threshold, False].astype(np.int8)
    starts, ends = np.flatnonzero(np.diff(on) == 1), np.flatnonzero(np.diff(on) == -1)
    step = HOP / RATE
    return [(FIRST + a * step, FIRST + b * step, float(probability[a:b].max()))
            for a, b in zip(starts, ends) if b - a >= 2]


VOWELS = frozenset("AA AE AH AO AW AY EH ER EY IH IY OW OY UH UW".split())
OTHER_STOPS = frozenset("T D K G CH JH".split())
SPAN_LOOKS = ((0, -3), (0, 1), (1, -1), (1, 1))
"""Frames whose spectrum a span's score sees, (0: from its first frame, 1: from the frame after its last,
frames): 30 ms before it (the vowel's formants bending into the closure), 10 ms into it, its last frame and
10 ms after it (the release burst: a labial's is low and diffuse)."""


def phone_class(name: str | None) -> int:
    """The recogniser's phone as one of five: labial, other stop or affricate, silence or filler, vowel, other."""
    if name is None or name == "SIL" or name.startswith("+"):
        return 2
    return 0 if name in LABIALS else 1 if name in OTHER_STOPS else 3 if name in VOWELS else 4


def span_features(levels: np.ndarray, probability: np.ndarray, phones: list,
                  spans: list[tuple[float, float, float]], offset: float = 0.0) -> np.ndarray:
    """Per detector span (:func:`closure_spans`): what the detector says of it (peak and mean probability,
    length), the spectrum at :data:`SPAN_LOOKS`, and what the phone loop heard (:func:`phone_class` at its
    start, its end and after it; a labial heard within :data:`SNAP` of its start; one heard inside it) and a
    bias input: the detector's frames and the recogniser's phones judged together."""
    n, step = len(levels), HOP / RATE
    rows = []
    starts = np.array([p.start - offset for p in phones])
    ends = np.array([p.end - offset for p in phones])
    names = [p.name for p in phones]

    def heard_at(t):
        k = np.flatnonzero((starts <= t) & (ends > t))
        return names[k[0]] if len(k) else None

    for a, b, peak in spans:
        i, j = int(round((a - FIRST) / step)), int(round((b - FIRST) / step))
        looks = [(j if after else i) + d for after, d in SPAN_LOOKS]
        spectra = levels[np.clip(looks, 0, n - 1)].ravel()
        classes = np.zeros(15)
        for slot, t in enumerate((a + 0.01, b - 0.01, b + 0.02)):
            classes[slot * 5 + phone_class(heard_at(t))] = 1.0
        near = any(nm in LABIALS and abs(s0 - a) <= SNAP for nm, s0 in zip(names, starts))
        inside = any(nm in LABIALS and s0 < b and e0 > a for nm, s0, e0 in zip(names, starts, ends))
        part = probability[i:max(j, i + 1)]
        rows.append(np.r_[peak, part.mean(), min(j - i, 20) / 10.0, spectra, classes, near, inside, 1.0])
    return np.array(rows).reshape(len(rows), -1)


def span_scores(levels: np.ndarray, probability: np.ndarray, phones: list,
                spans: list[tuple[float, float, float]], offset: float = 0.0) -> np.ndarray | None:
    """Probability that each span is a closure (:func:`span_features` -> :mod:`.closure_weights`' span
    layers); None where the weights have none (the heard/sure rule then decides)."""
    layers = span_weights()
    if layers is None:
        return None
    if not spans:
        return np.zeros(0)
    return predict(span_features(levels, probability, phones, spans, offset), *layers)


@lru_cache(maxsize=1)
def span_weights() -> tuple[np.ndarray, np.ndarray] | None:
    """The span scorer's layers (:mod:`.closure_weights` ``SPAN_*``), or None."""
    from mpeg4fa.speech.listen import closure_weights as w

    if not hasattr(w, "SPAN_HIDDEN"):
        return None
    hidden = np.frombuffer(base64.b64decode(w.SPAN_HIDDEN), "<f2").astype(np.float64).reshape(w.SPAN_SHAPE)
    return hidden, np.frombuffer(base64.b64decode(w.SPAN_OUTPUT), "<f2").astype(np.float64)


def refine_closures(phones: list, spans: list[tuple[float, float, float]], offset: float = 0.0, *,
                    sure: float = SURE, longest: int = LONGEST_UNHEARD, open_veto: bool = OPEN_VETO,
                    confirm: bool = CONFIRM, scores: np.ndarray | None = None, keep: float = KEEP) -> list:
    """``phones`` (:class:`~.phones.Phone`) with the detector's closures (``spans``, s from ``offset``)
    applied: a span near a recognised labial, or a sure one, becomes that labial (``B`` where none was
    heard), cutting the phones it overlaps; a recognised labial near no span is not shut (``confirm``;
    see the module docstring). With ``scores`` (:func:`span_scores`, one a span) a span is applied where its
    score reaches ``keep``, heard or not, instead. The keywords default to the chosen constants; the
    training script's grid tries others."""
    from mpeg4fa.speech.listen.phones import SILENCE, Phone

    out = list(phones)
    if confirm:
        starts = np.array([a + offset for a, _, _ in spans])
        out = [Phone(UNSHUT[p.name], p.start, p.end)
               if p.name in UNSHUT and not (np.abs(starts - p.start) <= SNAP).any() else p for p in out]
    for k, (a, b, peak) in enumerate(spans):
        a, b = a + offset, b + offset
        heard = [p for p in out if p.name in LABIALS and abs(p.start - a) <= SNAP]
        if scores is not None:
            if scores[k] < keep:
                continue
        elif not heard:
            under = {p.name for p in out if p.end > a + 0.005 and p.start < min(b, a + 0.03)}
            if peak < sure or b - a < longest * HOP / RATE - 1e-9 or not under or (open_veto and under <= OPEN):
                continue
        name = heard[0].name if heard else "B"
        if heard:  # the heard labial keeps its own end where it runs past the span
            b = max(b, max(p.end for p in heard))
        kept = []
        for p in out:
            if p.end <= a or p.start >= b:
                kept.append(p)
                continue
            if p.start < a and p in heard:  # heard early: the phone before it runs on to the closure
                if kept and abs(kept[-1].end - p.start) < 1e-9:
                    kept[-1] = Phone(kept[-1].name, kept[-1].start, a)
                else:
                    kept.append(Phone(SILENCE, p.start, a))
            elif p.start < a:
                kept.append(Phone(p.name, p.start, a))
            if p.end > b:
                kept.append(Phone(p.name, b, p.end))
        kept.append(Phone(name, a, b))
        out = sorted(kept, key=lambda p: p.start)
    return out


def refined_phones(recording: Recording, phones: list, offset: float = 0.0) -> list:
    """:func:`refine_closures` of ``phones`` heard in ``recording`` (times from ``offset``)."""
    if len(recording.samples) == 0:
        return list(phones)
    levels = log_mel(resample(np.asarray(recording.floats(), dtype=np.float64), recording.rate, RATE))
    if not len(levels):
        return list(phones)
    probability = predict(features(levels), *weights())
    spans = closure_spans(probability)
    return refine_closures(phones, spans, offset, scores=span_scores(levels, probability, phones, spans, offset))
