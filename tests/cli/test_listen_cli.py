"""``encode --speech REC`` and ``say --speech REC`` without a transcript (issue 28): the speech heard from
the audio alone, raw PCM from standard input, silence, bad files and the new flags' clashes."""
import io
import json
import sys
import wave

import numpy as np
import pytest

pytest.importorskip("pocketsphinx")

from mpeg4fa.fba import decode  # noqa: E402
from mpeg4fa.speech.tts.espeak import EspeakEngine  # noqa: E402

TEXT = "Please bring the maps back before the boat leaves."


def _write(path, samples, rate, channels=1):
    with wave.open(str(path), "wb") as w:
        w.setnchannels(channels)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes(np.repeat(np.asarray(samples, np.int16)[:, None], channels, axis=1).tobytes())
    return path


@pytest.fixture(scope="module")
def speech():
    s = EspeakEngine().synthesize(TEXT, voice="en-us+f3", rate=150)
    return s.samples, s.rate


@pytest.fixture(scope="module")
def rec(tmp_path_factory, speech):
    return _write(tmp_path_factory.mktemp("listen") / "rec.wav", *speech)


def _frames(path):
    """Frames on the frame grid, skipped repeats counted."""
    stream = decode(path.read_bytes())
    return int(np.sum(stream.skip + 1))


def test_encode_without_a_transcript(cli, tmp_path, rec, speech):
    out, timings = tmp_path / "x.fba", tmp_path / "x.json"
    code, _, err = cli("encode", "--speech", rec, "-o", out, "--timings", timings, "--expression", "joy=30")
    assert code == 0, err
    assert "heard by the phonetic recogniser" in err
    duration = len(speech[0]) / speech[1]
    assert abs(_frames(out) / 25 - duration) < 0.08
    items = json.loads(timings.read_text())
    assert {"PP", "AA"} <= {i["viseme"] for i in items}
    assert all(0 <= i["start"] <= i["end"] <= duration + 1e-6 for i in items)


def test_words_recogniser_writes_the_words_into_the_timings(cli, tmp_path, rec):
    out, timings = tmp_path / "x.fba", tmp_path / "x.json"
    code, _, err = cli("encode", "--speech", rec, "--recognizer", "words", "-o", out, "--timings", timings)
    assert code == 0, err
    assert "words recognised (no transcript)" in err
    words = [i.get("word") for i in json.loads(timings.read_text())]
    assert "please" in words


@pytest.mark.parametrize("rate", [8000, 44100])
def test_other_sample_rates_are_resampled(cli, tmp_path, speech, rate):
    from mpeg4fa.speech.align.recording import resample

    x = resample(speech[0] / 32768.0, speech[1], rate)
    path = _write(tmp_path / "r.wav", np.clip(np.rint(x * 32767), -32768, 32767).astype(np.int16), rate, channels=2)
    code, _, err = cli("encode", "--speech", path, "-o", tmp_path / "x.fba", "--timings", tmp_path / "t.json")
    assert code == 0, err
    assert "PP" in {i["viseme"] for i in json.loads((tmp_path / "t.json").read_text())}


def test_raw_pcm_from_standard_input(cli, tmp_path, speech, monkeypatch):
    samples, rate = speech
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(samples.astype("<i2").tobytes())))
    out = tmp_path / "x.fba"
    code, _, err = cli("encode", "--speech", "-", "--pcm-rate", rate, "-o", out)
    assert code == 0, err
    assert "<stdin>" in err and abs(_frames(out) / 25 - len(samples) / rate) < 0.08


def test_raw_pcm_from_standard_input_with_a_transcript(cli, tmp_path, speech, monkeypatch):
    """Fuzz of 2026-12-07: ``--speech - --transcript TEXT`` said ``-: no such recording`` although --help says that
    ``-`` reads raw PCM from standard input. Now it is aligned as the same samples in a WAV file are: the same stream,
    byte for byte (each in a fresh process: espeak-ng's reference audio shifts with what a process spoke before)."""
    import subprocess

    samples, rate = speech
    wav = _write(tmp_path / "s.wav", samples, rate)
    command = [sys.executable, "-m", "mpeg4fa.cli", "encode", "--transcript", TEXT, "--aligner", "dtw"]
    by_file = subprocess.run([*command, "--speech", str(wav), "-o", str(tmp_path / "f.fba")], capture_output=True,
                             text=True, timeout=300)
    by_pipe = subprocess.run([*command, "--speech", "-", "--pcm-rate", str(rate), "-o", str(tmp_path / "p.fba")],
                             input=samples.astype("<i2").tobytes(), capture_output=True, timeout=300)
    assert by_file.returncode == 0 and by_pipe.returncode == 0, (by_file.stderr, by_pipe.stderr)
    assert by_pipe.stderr.decode().startswith("<stdin>: ")
    assert (tmp_path / "p.fba").read_bytes() == (tmp_path / "f.fba").read_bytes()
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(io.BytesIO(b"")))
    code, _, err = cli("encode", "--speech", "-", "--transcript", "-", "-o", tmp_path / "q.fba")
    assert code == 2 and "both read standard input" in err and not (tmp_path / "q.fba").exists()


@pytest.mark.parametrize("samples", [np.zeros(0, np.int16), np.zeros(32000, np.int16)], ids=["empty", "silent"])
def test_empty_or_silent_gives_a_closed_mouth_and_one_line(cli, tmp_path, samples):
    path = _write(tmp_path / "s.wav", samples, 16000)
    out = tmp_path / "x.fba"
    code, _, err = cli("encode", "--speech", path, "-o", out, "--level", "low")
    assert code == 0, err
    assert sum("no speech heard" in line for line in err.splitlines()) == 1
    assert _frames(out) == max(1, int(np.ceil(len(samples) / 16000 * 25)))
    values = decode(out.read_bytes()).fap_values
    assert np.abs(values.astype(np.int64)).max() == 0  # the neutral face: mouth closed


def test_not_a_wav_and_a_damaged_wav_are_one_located_error(cli, tmp_path, rec):
    bad = tmp_path / "notes.wav"
    bad.write_text("this is text, not sound\n" * 10)
    code, _, err = cli("encode", "--speech", bad, "-o", tmp_path / "x.fba")
    assert code == 1 and str(bad) in err and len(err.strip().splitlines()) == 1, err
    cut = tmp_path / "cut.wav"
    cut.write_bytes(rec.read_bytes()[:30])
    code, _, err = cli("encode", "--speech", cut, "-o", tmp_path / "x.fba")
    assert code == 1 and str(cut) in err and len(err.strip().splitlines()) == 1, err
    assert not (tmp_path / "x.fba").exists()


@pytest.mark.parametrize("argv, words", [
    (["--speech", "{rec}", "--transcript", "Hello", "--expression", "joy=30"], "is for a recording without a transcript"),
    (["--speech", "{rec}", "--transcript", "Hello", "--recognizer", "words"], "is for a recording without a transcript"),
    (["--speech", "{rec}", "--aligner", "dtw"], "--aligner goes with --transcript"),
    (["--speech", "{rec}", "--voice", "en-gb"], "--voice goes with --transcript"),
    (["--speech", "{rec}", "--pcm-rate", "8000"], "--pcm-rate is the rate of raw PCM"),
    (["--recognizer", "words", "Hello"], "--recognizer goes with --speech"),
])
def test_flag_clashes_exit_2(cli, tmp_path, rec, argv, words):
    code, _, err = cli("encode", *[a.format(rec=rec) for a in argv], "-o", tmp_path / "x.fba")
    assert code == 2 and words in err, err


@pytest.mark.parametrize("value, words", [("glee=30", "NAME one of"), ("joy=99", "0 to 63"), ("joy", "NAME=INTENSITY")])
def test_bad_expression_exit_2(cli, tmp_path, rec, capsys, value, words):
    with pytest.raises(SystemExit) as exc:
        cli("encode", "--speech", rec, "--expression", value, "-o", tmp_path / "x.fba")
    assert exc.value.code == 2 and words in capsys.readouterr().err


def test_say_a_recording_without_a_transcript(cli, tmp_path, rec, procedural_face, monkeypatch):
    from mpeg4fa.face import FaceModel
    from mpeg4fa.render.video import probe_media

    from mpeg4fa.speech.listen import stream

    monkeypatch.setattr(FaceModel, "default", classmethod(lambda cls: procedural_face))
    heard = []  # say hears the recording as encode does (stream.listened_whole: its blocks, two at once)
    monkeypatch.setattr(stream, "listened_whole", lambda *a, _hear=stream.listened_whole, **k: heard.append(1) or
                        _hear(*a, **k))
    out = tmp_path / "me.mp4"
    code, stdout, err = cli("say", "--speech", rec, "-o", out, "--size", "64", "--aa", "0")
    assert code == 0, err
    assert heard == [1]
    assert "phonetic recogniser, no transcript" in stdout
    assert probe_media(out).n_frames >= 70
