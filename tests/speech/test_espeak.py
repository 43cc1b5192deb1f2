"""espeak-ng engine: the events must line up with the audio, because visemes are timed by them.

Each synthesis takes milliseconds, so these run with the fast suite. ``pytest -s`` prints the
English phoneme list with times (the mnemonics the viseme table has to cover).
"""
from __future__ import annotations

import pickle
import subprocess
import sys
import threading
import wave

import numpy as np
import pytest

from mpeg4fa.speech.errors import TTSError
from mpeg4fa.speech.tts.base import Engine, Event, Speech
from mpeg4fa.speech.tts import espeak
from mpeg4fa.speech.tts.espeak import EspeakEngine, list_voices

HELLO = "Hello there, how are you?"
SILENT = 2  # |sample| at or below this counts as silence
EDGE = 3  # samples at a pause's edges that may still carry the tail of a sound


@pytest.fixture(scope="module")
def engine() -> EspeakEngine:
    return EspeakEngine()


@pytest.fixture(scope="module")
def hello(engine: EspeakEngine) -> Speech:
    return engine.synthesize(HELLO)


def _span(speech: Speech, event: Event) -> np.ndarray:
    a, b = round(event.start * speech.rate), round(event.end * speech.rate)
    return speech.samples[a:b].astype(np.int64)


def test_engine_satisfies_protocol(engine: EspeakEngine) -> None:
    assert isinstance(engine, Engine)
    assert engine.name == "espeak"


def test_english_audio(hello: Speech) -> None:
    assert hello.rate == 22050
    assert hello.samples.dtype == np.int16 and hello.samples.ndim == 1
    assert hello.duration > 1.0
    assert hello.engine == "espeak" and hello.voice == "en-us"
    assert np.abs(hello.samples.astype(np.int64)).max() > 5000


def test_phonemes_ordered_and_cover_audio(hello: Speech) -> None:
    phonemes = hello.phonemes()
    print("\nespeak en-us phonemes for", repr(HELLO))
    for p in phonemes:
        print(f"  {p.start * 1000:8.1f} {p.end * 1000:8.1f} ms  {p.text!r:8} pos={p.position}")
    assert len(phonemes) >= 10
    starts = [p.start for p in phonemes]
    assert starts == sorted(starts)
    assert starts[0] < 0.05
    for a, b in zip(phonemes, phonemes[1:]):
        assert a.end == pytest.approx(b.start)
    assert phonemes[-1].end == pytest.approx(hello.duration)
    texts = {p.text for p in phonemes}
    assert {"h", "@", "l", "oU", "D", "aU", "u:"} <= texts
    assert not any(t.startswith(("'", ",")) for t in texts), "stress marks are stripped by default"
    event_starts = [e.start for e in hello.events]
    assert event_starts == sorted(event_starts)
    assert hello.events[-1].kind == "end" and hello.events[-1].start == pytest.approx(hello.duration)


def test_keep_stress_keeps_espeak_prefixes() -> None:
    speech = EspeakEngine(keep_stress=True).synthesize(HELLO)
    assert "'oU" in {p.text for p in speech.phonemes()}


def test_pauses_are_silent(hello: Speech) -> None:
    pauses = [p for p in hello.phonemes() if p.text.startswith("_") and p.duration > 0.020]
    assert len(pauses) >= 2  # after "there," and at the end
    for p in pauses:
        inner = _span(hello, p)[EDGE:-EDGE]
        assert np.abs(inner).max() <= SILENT, (p, np.abs(inner).max())


def test_words_are_loud(hello: Speech) -> None:
    for w in hello.words():
        voiced = [p for p in hello.phonemes()
                  if w.start <= p.start < w.end and not p.text.startswith("_")]
        a = round(voiced[0].start * hello.rate)
        b = round(voiced[-1].end * hello.rate)
        chunk = hello.samples[a:b].astype(np.float64)
        assert np.sqrt(np.mean(chunk**2)) > 1000, w


def test_word_positions(hello: Speech) -> None:
    words = hello.words()
    assert [w.text for w in words] == ["Hello", "there", "how", "are", "you"]
    for w in words:
        assert HELLO[w.position:w.position + len(w.text)] == w.text
    assert all(a.start < b.start for a, b in zip(words, words[1:]))
    sentences = [e for e in hello.events if e.kind == "sentence"]
    assert len(sentences) == 1 and sentences[0].text == HELLO


def test_marks(engine: EspeakEngine) -> None:
    text = "one two three four"
    i3, i4 = text.index("three"), text.index("four")
    speech = engine.synthesize(text, marks=[(i3, "smile"), (i4, 'say "hi" <&>')])
    marks = speech.marks()
    assert [m.text for m in marks] == ["smile", 'say "hi" <&>']
    assert [m.position for m in marks] == [i3, i4]
    assert all(m.end == m.start for m in marks)
    words = {w.text: w for w in speech.words()}
    assert [w.position for w in speech.words()] == [0, 4, 8, 14]  # positions of the plain text
    assert words["two"].start < marks[0].start <= words["four"].start
    assert abs(marks[0].start - words["three"].start) < 0.050
    assert words["three"].start <= marks[1].start <= words["four"].start + 0.050
    assert abs(marks[1].start - words["four"].start) < 0.050


def test_marks_with_escaped_text(engine: EspeakEngine) -> None:
    text = "cats & dogs < birds, then fish"
    speech = engine.synthesize(text, marks=[(0, "begin"), (text.index("then"), "t"), (len(text), "end")])
    assert [m.text for m in speech.marks()] == ["begin", "t", "end"]
    by_text = {w.text: w for w in speech.words()}
    assert by_text["then"].position == text.index("then")
    assert by_text["fish"].position == text.index("fish")
    assert speech.marks()[0].start == 0.0


def test_mandarin_hanzi(engine: EspeakEngine) -> None:
    speech = engine.synthesize("你好，世界", voice="cmn")
    phonemes = [p for p in speech.phonemes() if not p.text.startswith("_")]
    print("\nespeak cmn phonemes for 你好，世界:",
          [(p.text, round(p.start, 3)) for p in speech.phonemes()])
    assert [p.text for p in phonemes] == ["n", "i", "X", "Au", "s.", "i.", "tS;", "iE"]
    assert speech.duration > 0.8
    assert [w.text for w in speech.words()] == ["你好", "世", "界"]


def test_mandarin_pinyin(engine: EspeakEngine) -> None:
    speech = engine.synthesize("ni3 hao3 shi4 jie4", voice="cmn-latn-pinyin")
    phonemes = [p.text for p in speech.phonemes() if not p.text.startswith("_")]
    assert phonemes == ["n", "i", "X", "Au", "s.", "i.", "tS;", "iE"]
    assert speech.duration > 0.8
    assert [w.text for w in speech.words()] == ["ni3", "hao3", "shi4", "jie4"]


def test_rate_changes_duration(engine: EspeakEngine) -> None:
    text = "The quick brown fox jumps over the lazy dog, and then it runs far away."
    fast = engine.synthesize(text, rate=250).duration
    slow = engine.synthesize(text, rate=120).duration
    assert fast < slow
    assert fast / slow == pytest.approx(120 / 250, rel=0.15)


@pytest.mark.parametrize("rate", [40, 1000])
def test_rate_out_of_range(engine: EspeakEngine, rate: int) -> None:
    with pytest.raises(TTSError, match="rate"):
        engine.synthesize("hello", rate=rate)


def test_unknown_voice(engine: EspeakEngine) -> None:
    with pytest.raises(TTSError) as info:
        engine.synthesize("hello", voice="xx-nowhere")
    err = info.value
    assert "xx-nowhere" in str(err) and err.where == "espeak"
    assert "en-us" in err.hint
    # the engine still works afterwards
    assert engine.synthesize("hello").duration > 0.2


@pytest.mark.parametrize("text", ["", "   \n"])
def test_empty_text(engine: EspeakEngine, text: str) -> None:
    with pytest.raises(TTSError, match="empty"):
        engine.synthesize(text)


def test_bad_mark_offset(engine: EspeakEngine) -> None:
    with pytest.raises(TTSError, match="outside"):
        engine.synthesize("hello", marks=[(99, "x")])


def test_list_voices() -> None:
    voices = list_voices()
    languages = {lang for _, langs in voices for lang in langs}
    assert {"en-us", "cmn", "cmn-latn-pinyin"} <= languages


def test_write_wav_round_trip(hello: Speech, tmp_path) -> None:
    path = tmp_path / "hello.wav"
    hello.write_wav(path)
    with wave.open(str(path), "rb") as f:
        assert (f.getnchannels(), f.getsampwidth(), f.getframerate()) == (1, 2, 22050)
        data = np.frombuffer(f.readframes(f.getnframes()), dtype="<i2")
    np.testing.assert_array_equal(data, hello.samples)


def test_speech_is_plain_data(hello: Speech) -> None:
    again = pickle.loads(pickle.dumps(hello))
    assert again.events == hello.events
    np.testing.assert_array_equal(again.samples, hello.samples)


def test_threads_share_the_engine(engine: EspeakEngine) -> None:
    results: dict[int, Speech] = {}

    def work(k: int) -> None:
        results[k] = engine.synthesize(["one", "two words", "three words here"][k % 3])

    threads = [threading.Thread(target=work, args=(k,)) for k in range(6)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for k, speech in results.items():
        assert len(speech.words()) == k % 3 + 1


def test_callback_error_is_raised_after(engine: EspeakEngine, monkeypatch) -> None:
    def broken(*args, **kwargs):
        raise ValueError("boom")

    monkeypatch.setattr(espeak, "RawEvent", broken)
    with pytest.raises(TTSError, match="boom"):
        engine.synthesize("hello")
    monkeypatch.undo()
    assert engine.synthesize("hello").words()[0].text == "hello"


def test_missing_library_is_a_tts_error() -> None:
    code = (
        "import sys; sys.modules['espeakng_loader'] = None\n"
        "from mpeg4fa.speech.tts.espeak import EspeakEngine\n"
        "from mpeg4fa.speech.errors import TTSError\n"
        "try:\n    EspeakEngine().synthesize('hi')\n"
        "except TTSError as e:\n    print(e.where, '|', e.hint)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.startswith("espeak |") and "espeakng-loader" in out.stdout
