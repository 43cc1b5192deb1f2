"""What the fuzz campaigns of issue 26 found on the speech path, each as the smallest case that shows it.

The replays of the campaigns' own cases are in ``tests/fuzz/test_fuzz_readers.py``; these say which rule
each fix put where: the parse pass refuses what is no text, a split phoneme ends where it ends, a pinyin
syllable's phonemes are its own (a language switch is none), a float
WAV's NaN and 1e308 are silence and full scale without a numpy warning, viseme events stop at the
in-memory encoder's ceiling, and an espeak-ng voice without its dictionary is refused in one line.
"""
from __future__ import annotations

import io
import json
import struct
import warnings

import numpy as np
import pytest

from mpeg4fa.speech.chunks import parse_pieces
from mpeg4fa.speech.encoder import encode_text
from mpeg4fa.speech.errors import MarkupError, TTSError
from mpeg4fa.speech.ipa import ipa_visemes, phoneme_visemes, split_event
from mpeg4fa.speech.markup import MAX_TEXT_CHARS, parse_markup
from mpeg4fa.speech.tts.base import Event


# -- 1. a lone surrogate (and NUL) is refused by the parse pass, where it stands ---------------------------------

@pytest.mark.parametrize("text, place, said", [
    ("hello \udcff there", "<text>:1:7", "not a character: byte 0xff is not UTF-8"),
    ("one\ntwo \ud800", "<text>:2:5", "not a character: U+D800 is half of a UTF-16 surrogate pair"),
    ("hello\0there", "<text>:1:6", "a NUL character (U+0000)"),
    ("(joy, 40, 0.5) a \udfff", "<text>:1:18", "U+DFFF"),
])
def test_what_no_text_holds_is_refused_at_its_place(text, place, said):
    with pytest.raises(MarkupError) as caught:
        parse_markup(text)
    assert caught.value.where == place and said in str(caught.value)
    with pytest.raises(MarkupError):  # lenient speaks bad tags as text, never a character no engine takes
        parse_markup(text, lenient=True)


def test_a_surrogate_far_into_a_long_source_is_located_in_the_whole_source():
    source = "Say this. " * (MAX_TEXT_CHARS // 10 + 5) + "\n  x\udcc3"
    with pytest.raises(MarkupError) as caught:
        list(parse_pieces(source))
    assert (caught.value.line, caught.value.column) == (2, 4)


@pytest.mark.parametrize("engine", ["estimate", "espeak"])
def test_no_engine_sees_a_surrogate(engine):
    """Fuzz text:364@0 and text:8@2: the text reached espeak-ng and ended in a UnicodeEncodeError."""
    with pytest.raises(MarkupError, match="not a character"):
        encode_text("Hello \ud800 there", engine=engine)
    from mpeg4fa.speech.pipeline import stream_text
    with pytest.raises(MarkupError, match="1:7: not a character"):
        stream_text("Hello \udfff there", io.BytesIO(), engine=engine)


def test_a_voice_name_no_utf8_can_spell_is_an_unknown_voice():
    from mpeg4fa.speech.tts.espeak import EspeakEngine

    with pytest.raises(TTSError, match="unknown voice"):
        EspeakEngine().synthesize("Hello", voice="en\udcff")


def test_a_voice_variant_too_long_for_espeak_is_refused_not_a_crash():
    """Fuzz of 2026-12-07: ``--voice en+`` and 40 letters aborted the whole process inside espeak-ng ("buffer overflow
    detected", exit 134) for every engine on it. Run in a child, so that a crash fails this test, not the suite."""
    import subprocess
    import sys

    from mpeg4fa.speech.tts.espeak import MAX_VARIANT_BYTES, EspeakEngine
    from mpeg4fa.speech.tts.pyttsx3_engine import Pyttsx3Engine

    child = ("from mpeg4fa.speech.tts.espeak import EspeakEngine\n"
             "try:\n    EspeakEngine().synthesize('Hi', voice='en+' + 'y' * 40)\n"
             "except Exception as exc:\n    print(type(exc).__name__, exc)\n")
    run = subprocess.run([sys.executable, "-c", child], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0 and run.stdout.startswith("TTSError") and "at most 32" in run.stdout, run
    with pytest.raises(TTSError, match="at most 32"):
        Pyttsx3Engine().synthesize("Hi", voice="en+" + "y" * 40)
    assert EspeakEngine().synthesize("Hi", voice="en+" + "y" * MAX_VARIANT_BYTES).duration > 0  # taken (unknown: ignored)


# -- 2. the parts of a split phoneme end exactly where the phoneme does ------------------------------------------

def test_a_split_phoneme_ends_where_it_ends():
    """Fuzz text:134@1: the offglide of eɪ ended at 18.262086167800458, the next phoneme started at ...454
    (the shares 0.7 + 0.30000000000000004 of the phoneme's time, added, overshoot its end by an ulp)."""
    event = Event("phoneme", 49.54349206349206, 49.64439909297052, "eɪ", 0)
    parts = split_event(event, phoneme_visemes("eɪ")[0])
    assert [p[1] for p in parts] == ["E", "ih"]
    assert parts[0][2] == event.start and parts[-1][3] == event.end
    assert all(a[3] == b[2] for a, b in zip(parts, parts[1:]))


def test_split_phonemes_never_overlap_the_next():
    rng = np.random.default_rng(7)
    bounds = np.cumsum(rng.uniform(0.01, 0.2, 400)) + 70.3
    names = ["eɪ", "s", "tʃ", "ə", "aɪ", "ɒ", "dʒ", "oʊ"]
    events = [Event("phoneme", float(a), float(b), names[k % len(names)], k)
              for k, (a, b) in enumerate(zip(bounds, bounds[1:]))]
    placed = ipa_visemes(events)
    assert all(b[2] >= a[3] for a, b in zip(placed, placed[1:]))


def test_an_affricate_split_at_the_stdin_case_times_ends_where_the_next_phoneme_starts():
    """Fuzz stdin:2495@0 (``gigantes`` said over and over by the ca-nw voice): the d of dʒ took 0.3 of its
    508 samples and the ʒ 0.7; added, they ended at 4.366938775510205, an ulp into the next i."""
    end = 96291 / 22050
    events = [Event("phoneme", (96291 - 508) / 22050, end, "dʒ", 0), Event("phoneme", end, 4.43, "i", 1)]
    placed = ipa_visemes(events)
    assert [p[1] for p in placed] == ["DD", "CH", "ih"]
    assert placed[1][3] == end == placed[2][2]


# -- 2b. a pinyin syllable's phonemes are its own ----------------------------------------------------------------

def test_a_phoneme_near_a_syllable_boundary_belongs_to_one_syllable():
    """Fuzz text:22873@0: espeak-ng's pinyin voice spells qiong2 out in English between the switches (en) and
    (cmn); the (cmn) event, 7 ms before the next syllable's word, was the last phoneme of qiong and the
    initial of cun too, so cun started inside qiong ('spans overlap'). A language switch is no phoneme."""
    from mpeg4fa.speech.encoder import make_engine
    from mpeg4fa.speech.markup import parse_markup
    from mpeg4fa.speech.utterance import speak

    utterance = speak(parse_markup("穹村"), make_engine("espeak"), lang="zh")
    spans = utterance.spans()
    assert all(b.start >= a.end for a, b in zip(spans, spans[1:]))
    assert not any(t.phoneme.startswith("(") for t in utterance.timings)
    initials = [t for t in utterance.timings if t.phoneme == "tsh"]
    assert [t.viseme for t in initials] == ["zcs"]  # cun's initial is its own tsh, not the switch before it
    assert encode_text("穹村", engine="espeak").stream.n_frames > 0


# -- 4. a float WAV's NaN, inf and 1e308 -------------------------------------------------------------------------

def _float_wav(path, samples, channels: int, bits: int = 64):
    data = np.asarray(samples, "<f8" if bits == 64 else "<f4").tobytes()
    fmt = struct.pack("<HHIIHH", 3, channels, 8000, 8000 * channels * bits // 8, channels * bits // 8, bits)
    path.write_bytes(b"RIFF" + struct.pack("<I", 36 + len(data)) + b"WAVEfmt " + struct.pack("<I", 16) + fmt
                     + b"data" + struct.pack("<I", len(data)) + data)
    return path


@pytest.mark.parametrize("samples, channels, bits, expected", [
    ([np.nan, 0.5] * 4, 1, 32, [0, 16384]),
    ([np.inf, -np.inf] * 4, 2, 64, [0, 0]),
    ([1e308, 1e308] * 4, 2, 64, [32767, 32767]),
    ([1e308, -1e308, -1e308, -1e308] * 2, 2, 64, [0, -32768]),
    ([np.nan, np.inf] * 4, 2, 32, [16384, 16384]),
])
def test_float_samples_beyond_full_scale_read_without_a_numpy_warning(tmp_path, samples, channels, bits, expected):
    from mpeg4fa.wavread import read_wav

    path = _float_wav(tmp_path / "f.wav", samples, channels, bits)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        out, rate = read_wav(path)
    assert rate == 8000 and out[:2].tolist() == expected


# -- 3. viseme events stop where the in-memory encoder does ------------------------------------------------------

def test_viseme_events_stop_at_the_recordings_ceiling():
    from mpeg4fa.formats.errors import FormatError
    from mpeg4fa.speech import viseme_events as ve
    from mpeg4fa.wavread import MAX_SECONDS, MAX_SPEECH_SECONDS

    assert ve.MAX_SECONDS == MAX_SECONDS == MAX_SPEECH_SECONDS == 1800
    late = int(MAX_SPEECH_SECONDS * ve.TICKS_PER_SECOND)
    _, events = ve.parse_viseme_events(f'[{{"AudioOffset": 0, "VisemeId": 21}}, {{"AudioOffset": {late}, '
                                       f'"VisemeId": 4}}]', "ok.json")
    assert events[-1].time == MAX_SPEECH_SECONDS
    with pytest.raises(FormatError, match=r"event 1: AudioOffset 35990000000 is not a time \(ticks 0..1800 s\)"):
        ve.parse_viseme_events('[{"AudioOffset": 0, "VisemeId": 21}, {"AudioOffset": 35990000000, "VisemeId": 4}]',
                               "late.json")


# -- 5. a voice whose dictionary is not installed ----------------------------------------------------------------

def test_a_voice_without_its_dictionary_is_refused_in_one_line_with_nothing_on_stderr(capfd):
    from mpeg4fa.speech.tts import espeak

    mute = {v.identifier for v in espeak.voices() if not v.speaks}
    assert mute == {"gmq/fo", "trk/kaa", "art/xex"}  # the espeakng-loader wheel's 1.52 data
    assert not mute & {v.identifier for v in espeak.voices(speaking=True)}
    assert espeak.missing_dictionary("fo") == "fo" and espeak.missing_dictionary("Faroese+m1") == "fo"
    assert espeak.missing_dictionary("en-us") is None and espeak.missing_dictionary("no-such") is None
    capfd.readouterr()
    for voice in ("fo", "kaa", "xextan-test"):
        with pytest.raises(TTSError, match=f"espeak-ng has no dictionary for {voice} in this installation"):
            espeak.EspeakEngine().synthesize("Hello there", voice=voice)
    assert "dictionary" not in capfd.readouterr().err
    assert espeak.EspeakEngine().synthesize("Hello", voice="en-us").samples.size > 0


def test_encode_visemes_streams_the_same_stream(tmp_path, cli):
    """``encode --visemes`` codes block by block (:func:`~mpeg4fa.speech.pipeline.stream_utterance`): a short
    file gets the bytes the in-memory encoder gives; a long one decodes to the frames it gives."""
    from mpeg4fa.decoded import resolve
    from mpeg4fa.fba import decode, encode
    from mpeg4fa.speech import viseme_events as ve

    def grid(stream) -> np.ndarray:
        return np.repeat(resolve(stream), stream.skip.astype(int) + 1, axis=0)

    events = [{"AudioOffset": k * 900_000, "VisemeId": (k * 7) % 22} for k in range(60)]
    late = events + [{"AudioOffset": 250 * ve.TICKS_PER_SECOND, "VisemeId": 4}]
    for name, listed, level in (("short", events, "high"), ("long", late, "low")):
        path, out = tmp_path / f"{name}.json", tmp_path / f"{name}.fba"
        path.write_text(json.dumps(listed), encoding="utf-8")
        code, _, err = cli("encode", "--visemes", path, "-o", out, "--level", level)
        assert code == 0, err
        kind, parsed = ve.read_viseme_events(path)
        memory = ve.encode_viseme_events(parsed, engine=kind, name=str(path), level=level)
        whole = encode(memory.stream, memory.coding())
        if name == "short":
            assert out.read_bytes() == whole
        else:
            streamed, held = grid(decode(out.read_bytes())), grid(decode(whole))
            assert streamed.shape == held.shape and len(held) > 6000 and np.abs(held).max() > 0
            assert np.array_equal(streamed, held)


def test_a_long_run_of_dotted_letters_is_spoken_in_pieces_not_crashing_espeak(tmp_path):
    """Fuzz finding (stdin:12268@0, a worker killed by SIGSEGV): espeak-ng 1.52 overruns a buffer on about 200
    single letters run together with dots ('stack smashing detected', SIGABRT/SIGSEGV/SIGBUS). Runs without
    white space longer than chunks.MAX_RUN are cut into chunks of their own. In a child process: the old code
    killed the process that spoke it."""
    import subprocess
    import sys

    from mpeg4fa.speech.chunks import MAX_RUN, sentence_chunks
    from mpeg4fa.speech.markup import parse_markup

    text = "Hello. " + ".a" * 250 + " there."
    pieces = [m.text for m in sentence_chunks(parse_markup(text))]
    assert max(len(p) for p in pieces) <= MAX_RUN and "".join(pieces).replace(" ", "") == text.replace(" ", "")
    out = tmp_path / "dots.fba"
    done = subprocess.run([sys.executable, "-m", "mpeg4fa.cli", "encode", "--text", text, "-o", str(out)],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr[-500:]
    assert out.stat().st_size > 0


def test_the_engine_refuses_a_run_it_cannot_speak_whole():
    """Callers that do not chunk (the aligner speaks a transcript whole) get one error, not espeak-ng's overrun."""
    from mpeg4fa.speech.errors import TTSError
    from mpeg4fa.speech.tts.espeak import EspeakEngine

    with pytest.raises(TTSError, match="500 characters without a space at character 7"):
        EspeakEngine().synthesize("Hello " + ".a" * 250)


def test_emoji_joiners_never_reach_espeak_whose_gaelic_voice_crashes_on_them():
    """Fuzz finding (text:88775@0, a worker killed by SIGSEGV): espeak-ng 1.52's Scottish Gaelic voice
    corrupts memory on '#' + VS16 + keycap + 'ý' + a flag. The joiners of emoji sequences become spaces
    before espeak-ng sees the text (offsets kept). In a child process: the old code killed the process."""
    import subprocess
    import sys

    from mpeg4fa.speech.tts.espeak import _without_emoji_joiners

    text = "#\ufe0f\u20e3\u00fd\U0001F1EB\U0001F1F7"
    assert _without_emoji_joiners(text) == "#  \u00fd  " and len(_without_emoji_joiners("a\u200db")) == 3
    code = ("from mpeg4fa.speech.tts.espeak import EspeakEngine; "
            f"EspeakEngine().synthesize({text!r}, voice='gd', ipa=True); print('spoke')")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0 and "spoke" in done.stdout, (done.returncode, done.stderr[-300:])
