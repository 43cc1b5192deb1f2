"""`mpeg4fa encode --speech REC.wav --transcript TEXT` and `mpeg4fa say --speech ...`: lip sync to a recording."""
import json
import wave

import numpy as np
import pytest

from mpeg4fa.fba import decode
from mpeg4fa.speech.tts.espeak import EspeakEngine

TEXT = "(joy, 40, 0.5) Please bring the maps back before the boat leaves."


def _write(path, samples, rate, channels=1):
    with wave.open(str(path), "wb") as w:
        w.setnchannels(channels)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes(np.repeat(samples[:, None], channels, axis=1).astype("<i2").tobytes())
    return path


@pytest.fixture(scope="module")
def rec(tmp_path_factory):
    speech = EspeakEngine().synthesize("Please bring the maps back before the boat leaves.", voice="en-us+f3",
                                       rate=150)
    return _write(tmp_path_factory.mktemp("rec") / "rec.wav", speech.samples, speech.rate, channels=2)


def _seconds(path):
    with wave.open(str(path)) as f:
        return f.getnframes() / f.getframerate(), f.getnchannels()


def test_encode_a_recording(cli, tmp_path, rec):
    out, wav, timings = tmp_path / "talk.fba", tmp_path / "talk.wav", tmp_path / "talk.json"
    code, _, err = cli("encode", "--speech", rec, "--transcript", TEXT, "-o", out, "--audio", wav, "--timings", timings)
    assert code == 0, err
    assert "aligned by pocketsphinx in" in err and "s of audio" in err
    duration, _ = _seconds(rec)
    assert abs(decode(out).duration - duration) < 0.05
    assert _seconds(wav) == pytest.approx((duration, 1), abs=1e-3)  # the recording itself, mono
    rows = json.loads(timings.read_text(encoding="utf-8"))
    assert [r["viseme"] for r in rows if r["viseme"] != "none"][0] == "PP"  # "Please"
    assert max(r["end"] for r in rows) <= duration + 1e-6


def test_transcript_from_a_file_and_another_language(cli, tmp_path):
    text = "Buenos días, ¿cómo estás?"
    speech = EspeakEngine().synthesize(text, voice="es", rate=140)
    rec = _write(tmp_path / "es.wav", speech.samples, speech.rate)
    script = tmp_path / "es.txt"
    script.write_text(text + "\n", encoding="utf-8")
    code, _, err = cli("encode", "--speech", rec, "--transcript", script, "--lang", "es", "-o", tmp_path / "es.fba",
                       "--level", "low")
    assert code == 0, err
    assert "aligned by dtw" in err and len(decode(tmp_path / "es.fba")) > 10


@pytest.mark.parametrize("argv, words", [
    (["--speech", "{missing}", "--transcript", "Hello"], "missing.wav: no such recording"),
    (["--speech", "{silent}", "--transcript", "Hello"], "silent"),
    (["--speech", "{rec}", "--transcript", "Hello"], "does not fit"),
    (["--speech", "{rec}", "--transcript", "Hello", "--lang", "xx-nowhere"], "unknown language"),
])
def test_bad_recordings_exit_1_with_one_line(cli, tmp_path, rec, argv, words):
    silent = _write(tmp_path / "silent.wav", np.zeros(16000, np.int16), 16000)
    argv = [a.format(missing=tmp_path / "missing.wav", silent=silent, rec=rec) for a in argv]
    code, _, err = cli("encode", *argv, "-o", tmp_path / "x.fba")
    assert code == 1 and words in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "x.fba").exists()


@pytest.mark.parametrize("argv, words", [
    (["--speech", "{rec}", "--transcript", "Hello", "--expression", "joy=9"], "without a transcript"),
    (["--transcript", "Hello"], "--transcript goes with --speech"),
    (["Hello", "--speech", "{rec}", "--transcript", "Hello"], "has no place beside it"),
    (["--speech", "{rec}", "--transcript", "Hello", "--engine", "estimate"], "--engine estimate with --speech"),
    ([], "INPUT missing"),
])
def test_usage_clashes_exit_2(cli, tmp_path, rec, argv, words):
    code, _, err = cli("encode", *[a.format(rec=rec) for a in argv], "-o", tmp_path / "x.fba")
    assert code == 2 and words in err, err


def test_say_a_recording(cli, tmp_path, rec, procedural_face, monkeypatch):
    from mpeg4fa.face import FaceModel
    from mpeg4fa.render.video import probe_media

    monkeypatch.setattr(FaceModel, "default", classmethod(lambda cls: procedural_face))
    out = tmp_path / "me.mp4"
    code, stdout, err = cli("say", "--speech", rec, "--transcript", TEXT, "-o", out, "--size", "64", "--aa", "0",
                            "--keep")
    assert code == 0, err
    assert "aligned by pocketsphinx" in stdout
    info = probe_media(out)
    duration, _ = _seconds(rec)
    assert abs(info.n_frames / 25 - duration) < 0.08
    assert (tmp_path / "me.fba").exists() and _seconds(tmp_path / "me.wav")[0] == pytest.approx(duration, abs=1e-3)
    code, _, err = cli("say", "-o", out)
    assert code == 2 and "TEXT missing" in err
