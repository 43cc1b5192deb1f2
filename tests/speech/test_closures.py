"""Stops start at their closure's silence (mpeg4fa.speech.closures): synthetic audio with known
silences, then espeak-ng's own stops."""
import numpy as np
import pytest

from mpeg4fa.speech.closures import KEEP, LONGEST, stop_closures
from mpeg4fa.speech.encoder import encode_text
from mpeg4fa.speech.tts.base import Speech
from mpeg4fa.speech.utterance import Timing

RATE = 16000


def speech(loud: list[tuple[float, float]], seconds: float = 1.0) -> Speech:
    """A 200 Hz tone inside the ``loud`` intervals, digital silence elsewhere."""
    t = np.arange(int(seconds * RATE)) / RATE
    on = np.zeros(len(t), dtype=bool)
    for a, b in loud:
        on |= (t >= a) & (t < b)
    return Speech((on * 8000 * np.sin(2 * np.pi * 200 * t)).astype(np.int16), RATE, (), "test", "none")


def test_a_stop_moves_back_over_the_silence_before_it():
    s = speech([(0.0, 0.25), (0.30, 0.6)])  # the vowel's sound stops at 0.25: closure 0.25-0.30
    timings = (Timing("a", "AA", 0.0, 0.30), Timing("p", "PP", 0.30, 0.35), Timing("a", "AA", 0.35, 0.6))
    out = stop_closures(timings, s)
    assert out[0].end == out[1].start == pytest.approx(0.25, abs=0.005)
    assert out[1].end == 0.35 and out[2] == timings[2]
    assert [t.phoneme for t in out] == ["a", "p", "a"]


def test_what_does_not_move():
    s = speech([(0.0, 0.25), (0.30, 0.6)])
    nasal = (Timing("a", "AA", 0.0, 0.30), Timing("m", "nn", 0.30, 0.35))  # not a stop viseme
    assert stop_closures(nasal, s) == nasal
    pause = (Timing("_", "none", 0.25, 0.30), Timing("p", "PP", 0.30, 0.35))  # after a pause: stays
    assert stop_closures(pause, s) == pause
    gap = (Timing("a", "AA", 0.0, 0.29), Timing("p", "PP", 0.30, 0.35))  # not adjacent
    assert stop_closures(gap, s) == gap
    silent = Speech(np.zeros(RATE, dtype=np.int16), RATE, (), "estimate", "none")  # no audio at all
    timings = (Timing("a", "AA", 0.0, 0.30), Timing("p", "PP", 0.30, 0.35))
    assert stop_closures(timings, silent) == timings
    voiced = speech([(0.0, 0.6)])  # sound right up to the stop: nothing to move over
    assert stop_closures(timings, voiced) == timings


def test_longest_closure_and_what_the_phoneme_before_keeps():
    timings = (Timing("a", "AA", 0.0, 0.5), Timing("t", "DD", 0.5, 0.55))
    long_silence = speech([(0.0, 0.1), (0.5, 0.6)])  # 0.4 s of silence: a pause, not a closure
    assert stop_closures(timings, long_silence) == timings
    closure = speech([(0.0, 0.5 - LONGEST + 0.01), (0.5, 0.6)])  # just under LONGEST: a closure
    assert stop_closures(timings, closure)[1].start == pytest.approx(0.5 - LONGEST + 0.01, abs=0.005)
    short_vowel = speech([(0.0, 0.005), (0.3, 0.6)])
    out = stop_closures((Timing("a", "AA", 0.27, 0.30), Timing("k", "kk", 0.30, 0.35)), short_vowel)
    assert out[0].end - out[0].start >= KEEP - 1e-9


def test_espeak_stops_start_where_their_silence_starts():
    """espeak-ng books a voiceless stop's closure to the phoneme before: after the correction every
    moved stop starts at the first silent block, and the sound right before it is loud."""
    enc = encode_text("Peter picked a peck of pickled peppers.", level="low")
    x = enc.speech.samples.astype(np.float64)
    rate = enc.speech.rate
    raw = {round(e.start, 6) for e in enc.speech.phonemes()}
    moved = [t for t in enc.utterance.timings if t.viseme in ("PP", "DD", "kk") and round(t.start, 6) not in raw]
    assert len(moved) >= 6  # most of the p, t and k of the sentence
    block = int(0.005 * rate)
    for t in moved:
        i = int(round(t.start * rate))
        after, before = x[i:i + block], x[i - block:i]
        assert np.sqrt((after ** 2).mean()) < 32768 * 10 ** (-50 / 20), t
        assert np.sqrt((before ** 2).mean()) >= 32768 * 10 ** (-50 / 20), t


def _with_noise(s: Speech, a: float, b: float, db: float, rising_to: float | None = None) -> Speech:
    """``s`` with white noise from ``a`` to ``b`` s at ``db`` dBFS RMS (rising to ``rising_to`` dB at ``b``)."""
    x = s.samples.astype(np.float64)
    i, j = int(a * RATE), int(b * RATE)
    gain = 10 ** (np.linspace(db, db if rising_to is None else rising_to, j - i) / 20)
    x[i:j] += np.random.default_rng(0).standard_normal(j - i) * gain * 32768
    return Speech(np.clip(x, -32768, 32767).astype(np.int16), RATE, (), "test", "none")


def test_a_breathy_closure_starts_at_the_sharp_fall():
    """Breath noise in the closure (-48 dB rising to -36 before the burst, as espeak-ng's +f3): no silent block,
    yet the stop starts where the vowel's sound falls; a vowel fading out and a fricative up to the stop do not."""
    timings = (Timing("a", "AA", 0.0, 0.30), Timing("p", "PP", 0.30, 0.35), Timing("a", "AA", 0.35, 0.6))
    breathy = _with_noise(speech([(0.0, 0.25), (0.30, 0.6)]), 0.25, 0.30, -48, rising_to=-36)
    out = stop_closures(timings, breathy)
    assert out[1].start == pytest.approx(0.25, abs=0.005) and out[0].end == out[1].start
    t = np.arange(RATE) / RATE  # a vowel fading 1.5 dB a block (5 ms) to -45 dB at the stop: no closure
    fade = 8000 * np.sin(2 * np.pi * 200 * t) * 10 ** (-np.clip(t - 0.2, 0, None) / 0.005 * 1.5 / 20)
    fading = Speech(fade.astype(np.int16), RATE, (), "test", "none")
    assert stop_closures(timings, fading) == timings
    fricative = _with_noise(speech([(0.30, 0.6)]), 0.0, 0.30, -30)  # an f (its own phoneme) right up to the p
    spans = (Timing("f", "FF", 0.0, 0.30),) + timings[1:]
    assert stop_closures(spans, fricative) == spans


def test_breathy_espeak_stops_start_where_the_plain_voice_closes():
    """The same text in en-us+f3 (breath in its closures) and en-us (silent closures) has the same phone times:
    the breathy voice's stops last within 15 ms of the plain voice's in >= 80 %."""
    text = "Stop by the shop, pick up a cup of soup and keep it hot."
    plain, breathy = (encode_text(text, voice=v, level="low").utterance.timings for v in ("en-us", "en-us+f3"))
    assert [t.phoneme for t in plain] == [t.phoneme for t in breathy]
    stops = [(a.end - a.start, b.end - b.start) for a, b in zip(plain, breathy) if a.viseme in ("PP", "DD", "kk")]
    assert len(stops) >= 10  # a stop's span: its closure (moved) and release; the voices' timing drifts by ms
    near = np.mean([abs(a - b) <= 0.015 for a, b in stops])
    assert near >= 0.8, near  # 14 of 16 (7 of 16 with silence alone)
