"""Audio-driven lip sync: a recording and its transcript -> the Utterance timed on the recording.

The 'recordings' are espeak-ng speech in another voice and at another rate than the aligner's reference
(en-us, 175 wpm), so the truth is known: their own phoneme events. tools/bench_align.py measures on six
sentences (see its table in the README); here two sentences and a looser bound (80 % of onsets within
30 ms, where the bench reaches >= 85 %).
"""
import difflib
import wave

import numpy as np
import pytest

from mpeg4fa.speech.align import AlignError, Recording, align_recording, choose_method, read_recording
from mpeg4fa.speech.align.dtw import dtw_path
from mpeg4fa.speech.encoder import encode_recording, encode_text
from mpeg4fa.speech.errors import MarkupError, TTSError
from mpeg4fa.speech.tts.espeak import EspeakEngine

TEXT = "Please bring the maps back before the boat leaves."
TAGGED = "(joy, 40, 0.5) Please bring the maps back (sadness, 30, 0.4) before the boat leaves."


def spoken(text, voice="en-us+f3", rate=140):
    speech = EspeakEngine().synthesize(text, voice=voice, rate=rate)
    return Recording(speech.samples, speech.rate, f"{voice}@{rate}"), speech


def onsets_within(aligned, truth, tol=0.030):
    a = [p for p in aligned.phonemes() if not p.text.startswith("_")]
    t = [p for p in truth.phonemes() if not p.text.startswith("_")]
    sm = difflib.SequenceMatcher(None, [p.text for p in a], [p.text for p in t], autojunk=False)
    err = np.array([abs(a[b.a + k].start - t[b.b + k].start) for b in sm.get_matching_blocks() for k in range(b.size)])
    return float((err <= tol).mean()), len(err) / len(t)


def write_wav(path, x, rate, channels=1, width=2):
    """``x`` float mono in [-1, 1] written as ``channels`` identical channels of ``width``-byte PCM."""
    frames = np.repeat(np.asarray(x)[:, None], channels, axis=1)
    if width == 2:
        data = np.clip(np.rint(frames * 32767), -32768, 32767).astype("<i2").tobytes()
    else:  # 24-bit
        v = np.clip(np.rint(frames * 8388607), -8388608, 8388607).astype("<i4").reshape(-1)
        data = np.stack([(v >> s) & 0xFF for s in (0, 8, 16)], axis=1).astype(np.uint8).tobytes()
    with wave.open(str(path), "wb") as w:
        w.setnchannels(channels)
        w.setsampwidth(width)
        w.setframerate(rate)
        w.writeframes(data)


@pytest.fixture(scope="module")
def recorded():
    return {case: spoken(TEXT, *case) for case in [("en-us+f3", 140), ("en-gb", 210)]}


@pytest.mark.parametrize("method", ["pocketsphinx", "dtw"])
@pytest.mark.parametrize("case", [("en-us+f3", 140), ("en-gb", 210)])
def test_aligned_onsets_land_on_the_recordings_phonemes(recorded, case, method):
    rec, truth = recorded[case]
    al = align_recording(rec, TEXT, lang="en", method=method)
    assert al.method == method
    share, paired = onsets_within(al.utterance.speech, truth)
    assert paired >= 0.85 and share >= 0.8, share  # en-gb names some phones otherwise: fewer pairs
    utt = al.utterance
    assert utt.speech.rate == rec.rate and np.array_equal(utt.speech.samples, rec.samples)
    assert [t.viseme for t in utt.timings] == [t.viseme for t in al.reference.timings]  # the same visemes
    starts = [t.start for t in utt.timings]
    assert starts == sorted(starts) and max(t.end for t in utt.timings) <= rec.duration + 1e-9


def test_auto_picks_pocketsphinx_for_english_and_dtw_for_the_rest():
    assert choose_method("auto", TEXT, "auto") == "pocketsphinx"
    assert choose_method("auto", "Buenos días", "es") == "dtw"
    assert choose_method("auto", "It costs 5 dollars", "en") == "dtw"  # digits: no dictionary words
    assert choose_method("auto", "Qwzxv said hello", "en") == "pocketsphinx"  # the word is added (below)
    with pytest.raises(AlignError, match="English only"):
        choose_method("pocketsphinx", "Buenos días", "es")


def test_words_outside_the_dictionary_are_added_as_espeak_says_them():
    from mpeg4fa.speech.align.sphinx import unknown_words

    text = "Brenwick met Zhangwei by the river."
    assert unknown_words(["brenwick", "zhangwei", "river"]) == ["brenwick", "zhangwei"]
    rec, truth = spoken(text)
    al = align_recording(rec, text, lang="en")
    assert al.method == "pocketsphinx" and not unknown_words(["brenwick", "zhangwei"])
    a = [p.start for p in al.utterance.speech.phonemes() if not p.text.startswith("_")][:15]
    t = [p.start for p in truth.phonemes() if not p.text.startswith("_")][:15]  # brenwick met zhangwei
    assert np.mean(np.abs(np.subtract(a, t)) <= 0.030) >= 0.75


def test_other_languages_align_by_dtw():
    text = "Buenos días, ¿cómo estás? Me llamo Pedro."
    speech = EspeakEngine().synthesize(text, voice="es+f3", rate=150, ipa=True)  # the reference: es, male, 175
    al = align_recording(Recording(speech.samples, speech.rate, "es+f3@150"), text, lang="es")
    assert al.method == "dtw"
    share, _ = onsets_within(al.utterance.speech, speech)
    assert share >= 0.8, share


def test_tags_wav_formats_and_the_encoder(tmp_path, recorded):
    """A 44.1 kHz stereo 24-bit WAV; tags become cues on the recording's time; the stream covers it."""
    from scipy.signal import resample_poly

    rec, _ = recorded[("en-us+f3", 140)]
    x = resample_poly(rec.floats(), 2, 1)  # 22050 -> 44100
    path = tmp_path / "rec.wav"
    write_wav(path, x, 44100, channels=2, width=3)
    got = read_recording(path)
    assert got.rate == 44100 and abs(got.duration - rec.duration) < 1e-3
    enc = encode_recording(path, TAGGED, level="high", fps=25)
    assert enc.speech.rate == 44100 and enc.speech.duration == pytest.approx(got.duration)
    assert len(enc.stream) == int(np.ceil(got.duration * 25))
    assert [c.expression for c in enc.utterance.cues] == ["joy", "sadness"]
    words = {w.text: w.start for w in enc.speech.words()}
    assert enc.utterance.cues[1].start == pytest.approx(words["before"], abs=0.03)
    assert enc.stream.viseme[:, 0].any() and enc.stream.expression[:, 0].any()
    # one timeline path: the same utterance through encode_text's code gives the same stream
    plain = encode_text(TAGGED, level="high")
    assert plain.stream.fap_mask.shape[1] == enc.stream.fap_mask.shape[1]


def test_clear_errors(tmp_path, recorded):
    rec, _ = recorded[("en-us+f3", 140)]
    with pytest.raises(AlignError, match="no such recording") as exc:
        align_recording(tmp_path / "missing.wav", TEXT)
    assert "missing.wav" in str(exc.value)
    bad = tmp_path / "bad.wav"
    bad.write_bytes(b"RIFF not really a wave file")
    with pytest.raises(AlignError, match="cannot read") as exc:
        read_recording(bad)
    assert "bad.wav" in str(exc.value)
    quiet = tmp_path / "quiet.wav"
    write_wav(quiet, np.random.default_rng(0).standard_normal(22050) * 1e-4, 22050)
    with pytest.raises(AlignError, match="silent"):
        align_recording(quiet, TEXT)
    long_text = " ".join([TEXT] * 5)
    for method in ("pocketsphinx", "dtw"):
        with pytest.raises(AlignError, match="does not fit"):
            align_recording(rec, long_text, lang="en", method=method)
        with pytest.raises(AlignError, match="does not fit"):
            align_recording(rec, "Please.", lang="en", method=method)
    with pytest.raises(TTSError, match="unknown language"):
        align_recording(rec, TEXT, lang="xx-nowhere")
    with pytest.raises(MarkupError):
        align_recording(rec, "(joy, 99, 1) Please bring the maps")
    # a run no word is as long as: refused at its place in the transcript (espeak-ng is never handed it; encode
    # and say cut such a run in text they speak without a recording, a transcript must be the words said)
    with pytest.raises(MarkupError, match="300 characters without a space") as err:
        align_recording(rec, "Please bring\nthe " + "ab" * 150, name="words.txt")
    assert err.value.where == "words.txt:2:5" and "put spaces" in err.value.hint


def test_dtw_path_follows_a_known_warp():
    rng = np.random.default_rng(1)
    a = rng.standard_normal((200, 3))
    idx = np.rint(199 * np.linspace(0, 1, 260) ** 1.2).astype(int)  # a slow start, then faster: steps 0 or 1
    path = dtw_path(a, a[idx])
    assert tuple(path[0]) == (0, 0) and tuple(path[-1]) == (199, 259)
    assert (np.diff(path, axis=0) >= 0).all() and (np.diff(path, axis=0).sum(axis=1) >= 1).all()
    assert all(i == idx[j] for i, j in path)  # every frame on its own copy: the zero-cost path


def test_wav_sample_formats(tmp_path):
    """8-bit and 32-bit integer PCM through the stdlib, 32-bit float (WAVE_FORMAT_IEEE_FLOAT) through PyAV."""
    import struct

    x = 0.5 * np.sin(2 * np.pi * 440 * np.arange(8000) / 8000)
    for width, data in ((1, np.clip(np.rint(x * 127 + 128), 0, 255).astype(np.uint8).tobytes()),
                        (4, np.rint(x * 2**31 * 0.999).astype("<i4").tobytes())):
        path = tmp_path / f"w{width}.wav"
        with wave.open(str(path), "wb") as w:
            w.setnchannels(1)
            w.setsampwidth(width)
            w.setframerate(8000)
            w.writeframes(data)
        got = read_recording(path)
        assert got.rate == 8000 and np.abs(got.floats() - x).max() < 0.01
    data = x.astype("<f4").tobytes()
    fmt = struct.pack("<HHIIHH", 3, 1, 8000, 8000 * 4, 4, 32)
    path = tmp_path / "float.wav"
    path.write_bytes(b"RIFF" + struct.pack("<I", 4 + 8 + len(fmt) + 8 + len(data)) + b"WAVE" + b"fmt "
                     + struct.pack("<I", len(fmt)) + fmt + b"data" + struct.pack("<I", len(data)) + data)
    got = read_recording(path)
    assert got.rate == 8000 and np.abs(got.floats()[:len(x)] - x).max() < 0.01
