"""Engines that time words, not phonemes: pyttsx3 (word boundaries) and the silent estimator, and the
estimate-then-resynchronise step that places visemes inside their words."""
import json
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mpeg4fa.fba import decode, encode
from mpeg4fa.speech.encoder import encode_text
from mpeg4fa.speech.errors import TTSError
from mpeg4fa.speech.graphemes import UNIT, english_graphemes, english_units, english_word, pinyin_units
from mpeg4fa.speech.closures import LONGEST, SHORTEST, SILENCE_DB, STOP_VISEMES
from mpeg4fa.speech.timeline import LAG, LEAD, frame_times, viseme_track
from mpeg4fa.speech.tts.base import Event, Speech
from mpeg4fa.speech.tts.espeak import EspeakEngine
from mpeg4fa.speech.tts.estimate import EstimateEngine
from mpeg4fa.speech.tts.pyttsx3_engine import Pyttsx3Engine
from mpeg4fa.speech.wordsync import PAUSE, Unit, resync

from .onsets import reached

TEXT = "Hello there, my old friend. How are you today? Please bring the maps back."
FPS = 25.0


_FRESH_ESPEAK = """
import json, sys
from mpeg4fa.speech.tts.base import Event, Speech
from mpeg4fa.speech.tts.espeak import EspeakEngine
s = EspeakEngine().synthesize(sys.argv[1], voice=sys.argv[2])
print(json.dumps({"samples": s.samples.tolist(), "words": [[w.position, w.start, w.text] for w in s.words()]}))
"""


def fresh_espeak(text: str, voice: str = "en-us") -> Speech:
    """espeak's speech (words only) in a fresh process: espeak keeps a little state between
    utterances, so in a process that has spoken other texts lengths drift by a few ms."""
    done = subprocess.run([sys.executable, "-c", _FRESH_ESPEAK, text, voice], capture_output=True, text=True,
                          check=True)
    fresh = json.loads(done.stdout)
    words = tuple(Event("word", t, t, word, pos) for pos, t, word in fresh["words"])
    return Speech(np.array(fresh["samples"], np.int16), 22050, words, "espeak", voice)


@pytest.fixture(scope="module")
def both_english():
    return Pyttsx3Engine().synthesize(TEXT), fresh_espeak(TEXT)


# -- pyttsx3 ------------------------------------------------------------------------------------

def test_pyttsx3_word_boundaries_are_espeaks(both_english):
    """pyttsx3 drives the same espeak-ng: the same samples, and each word boundary on the same sample."""
    p3, es = both_english
    assert p3.rate == es.rate and np.array_equal(p3.samples, es.samples)
    assert not p3.phonemes()  # word boundaries only
    got = {w.position: w.start for w in p3.words()}
    want = {w.position: w.start for w in es.words()}
    assert set(got) == set(want) and len(got) >= 12
    assert max(abs(got[k] - want[k]) for k in want) < 0.5 / p3.rate


def test_pyttsx3_stream_keeps_sync_at_every_word_boundary():
    """Each word's first viseme starts at the word's start in the audio (espeak's own word event: ground
    truth), or, for a stop, at the closure's silence just before it; read back from the decoded FAP 1,
    it is shown most between a frame before that onset and a frame after the onset plus LAG."""
    enc = encode_text(TEXT, engine="pyttsx3", level="high", fps=FPS)
    stream = decode(encode(enc.stream, enc.coding()))
    # The word events of this very speech: in a process that has spoken other texts espeak's lengths
    # drift by a few ms, so a fresh rendering is not the truth for this one (the test above checks
    # that pyttsx3's boundaries are espeak's).
    words = enc.speech.words()
    assert len(words) >= 12
    spans = enc.utterance.spans()
    offsets = []
    for word in words:
        k = min(range(len(spans)), key=lambda i: abs(spans[i].start - word.start))
        first = spans[k]
        moved = word.start - first.start
        if (first.set, first.viseme) in STOP_VISEMES and moved > 0:  # moved back over a closure's silence
            rate = enc.speech.rate
            gap = enc.speech.samples[int(round(first.start * rate)):int(round(word.start * rate))].astype(float)
            assert SHORTEST - 1e-9 <= moved <= LONGEST + 1e-9, word.text
            assert np.sqrt((gap * gap).mean()) < 32768 * 10 ** (SILENCE_DB / 20), word.text
        else:
            assert abs(moved) < 1e-6, word.text  # the estimate restarts at the boundary
        if first.end - first.start > 1.5 / FPS:
            t, top = reached(stream, spans, k, FPS)
            offsets.append(t - first.start)
    assert len(offsets) >= 8 and min(offsets) >= -1 / FPS - 1e-9 and max(offsets) <= LAG + 1 / FPS + 1e-9, offsets


def test_pyttsx3_speaks_a_long_text_to_its_end():
    """espeak may still be speaking when pyttsx3's loop returns: the worker waits for the end."""
    text = " ".join([TEXT] * 6)  # about 30 s of speech; the audio used to stop after ~11 s
    p3, es = Pyttsx3Engine().synthesize(text), fresh_espeak(text)
    assert np.array_equal(p3.samples, es.samples) and p3.duration > 25
    assert p3.words()[-1].text == "back" and p3.words()[-1].position == text.rindex("back")


def test_pyttsx3_speaks_pinyin_syllable_by_syllable():
    enc = encode_text("你好，世界！", engine="pyttsx3", level="low")
    es = fresh_espeak("ni3 hao3 , shi4 jie4 !", voice="cmn-latn-pinyin")
    zh = [t for t in enc.utterance.timings if t.viseme != "none"]
    assert [t.viseme for t in zh] == ["dtnl", "i", "gkh", "a", "o", "zhchsh", "jqx", "i", "e"]
    starts = sorted({t.start for t in zh if t.phoneme.endswith(":initial") or t.viseme == "zhchsh"})
    assert np.allclose(starts, [w.start for w in es.words()], atol=1e-6)


def test_pyttsx3_unknown_voice_fails_clearly():
    with pytest.raises(TTSError, match="no voice 'xx-nowhere'") as info:
        Pyttsx3Engine(voice="xx-nowhere").synthesize("hello")
    assert "en-us" in info.value.hint


# -- estimate-then-resynchronise ----------------------------------------------------------------

def _units(*weights):
    return [Unit("AA", w, "a") for w in weights]


def test_resync_compresses_stretches_and_pauses():
    spu = 0.1
    placed = resync([0.0, 0.25, 0.5, 2.0], [_units(1, 2), _units(1), _units(1, 1), _units(1)], 2.3, spu)
    ends = {}
    for unit, a, b in placed:
        ends.setdefault(a, b)
    # word 0: estimate 0.3 s, room 0.25: compressed to the boundary in the weights' proportion
    assert placed[0][1:] == (0.0, pytest.approx(0.25 / 3)) and placed[1][2] == 0.25
    # word 1: estimate 0.1 s, room 0.25 (gap 0.15 > PAUSE): keeps its length, then a pause
    assert PAUSE < 0.15 and placed[2][1:] == (0.25, pytest.approx(0.35))
    # word 2: estimate 0.2 s, room 1.5: pause; word 3 (last): estimate 0.1, room 0.3 -> pause
    assert placed[4][2] == pytest.approx(0.7) and placed[5][1:] == (2.0, pytest.approx(2.1))


def test_a_pause_returns_the_mouth_to_neutral():
    placed = resync([0.0, 1.5], [_units(2), _units(2)], 2.0, 0.1)
    from mpeg4fa.speech.timeline import VisemeSpan
    spans = [VisemeSpan(u.viseme, a, b) for u, a, b in placed]
    times = frame_times(2.0, FPS)
    track = viseme_track(spans, times)
    quiet = (times > 0.6) & (times < 1.5 - LEAD)  # the move into the next word starts LEAD before it
    assert np.abs(track[quiet]).max() == 0 and np.abs(track[times < 0.2]).max() > 0


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(0.01, 1.0), st.lists(st.floats(0.1, 2.0), min_size=1, max_size=5)),
                min_size=1, max_size=8),
       st.floats(0.02, 0.2))
def test_resync_keeps_each_word_inside_its_boundaries(words, spu):
    starts = np.cumsum([0.0] + [gap for gap, _ in words[:-1]]).tolist()
    end = starts[-1] + words[-1][0]
    placed = resync(starts, [_units(*w) for _, w in words], end, spu)
    assert len(placed) == sum(len(w) for _, w in words)
    k = 0
    for start, stop, (_, weights) in zip(starts, starts[1:] + [end], words):
        mine = placed[k:k + len(weights)]
        k += len(weights)
        assert mine[0][1] == start and mine[-1][2] <= stop + 1e-12
        assert all(a < b for _, a, b in mine)
        assert all(p[2] == q[1] for p, q in zip(mine, mine[1:]))  # contiguous inside the word


# -- graphemes and the silent estimator ---------------------------------------------------------

def test_grapheme_table_examples_read_their_grapheme():
    for (grapheme, _), (visemes, _) in english_graphemes().items():
        if grapheme.isalpha() and visemes:
            assert english_units(grapheme) or grapheme in ("e",), grapheme


def test_durations_follow_the_seed_rule():
    def weight(word, letter):
        return next(g.weight for g in english_word(word) if g.text == letter)
    assert weight("cat", "a") > weight("bed", "e") and weight("top", "o") > weight("tip", "i")
    assert weight("map", "m") > weight("sip", "s") > weight("sit", "t")
    assert weight("but", "u") < weight("use", "u")  # a medial u is short
    assert [u.viseme for u in english_units("thought")][0] == "TH"
    assert [g.text for g in english_word("make")] == ["m", "a", "k"]  # the final e is silent
    assert [u.viseme for u in pinyin_units("hao3")] == ["gkh", "a", "o"]


def test_estimate_engine_is_silent_and_paced_by_the_rate():
    slow = EstimateEngine().synthesize(TEXT)
    fast = EstimateEngine(rate=350).synthesize(TEXT)
    assert not slow.samples.any() and slow.duration == pytest.approx(2 * fast.duration, rel=0.02)
    words = slow.words()
    assert [w.text for w in words][:3] == ["Hello", "there", "my"]
    assert words[2].start - words[1].end == pytest.approx(0.16)  # the comma's pause
    espeak = EspeakEngine().synthesize(TEXT)
    assert 0.75 < slow.duration / espeak.duration < 1.25  # UNIT is calibrated on espeak-ng


def test_estimate_engine_encodes_without_audio():
    enc = encode_text("(joy, 40, 0.5) Hello there. 你好", engine="estimate", level="both")
    assert enc.speech.engine == "estimate" and not enc.speech.samples.any()
    visemes = [t.viseme for t in enc.utterance.timings]
    assert visemes[:4] == ["kk", "E", "nn", "oh"] and visemes[-5:] == ["dtnl", "i", "gkh", "a", "o"]
    assert len(enc.stream) == int(np.ceil(enc.speech.duration * 25)) and UNIT > 0
