"""`mpeg4fa play` and `mpeg4fa snapshot` on the generic head (skips when it is not built)."""
import json
import wave

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.cli import main
from mpeg4fa.fba import demo_stream, encode
from mpeg4fa.render.video import probe_media

pytestmark = pytest.mark.usefixtures("generic_head_installed")



@pytest.fixture
def talk(tmp_path):
    """A short demo stream, and a WAV of the same name beside it."""
    stream = demo_stream()
    path = tmp_path / "talk.fba"
    path.write_bytes(encode(stream))
    _wav(tmp_path / "talk.wav", stream.duration)
    return path, stream


def _wav(path, seconds, rate=16000):
    t = np.arange(int(seconds * rate)) / rate
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes((8000 * np.sin(2 * np.pi * 200 * t)).astype("<i2").tobytes())


def test_play_mp4_finds_the_wav_beside_the_stream(cli, talk, tmp_path):
    path, stream = talk
    code, out, err = cli("play", path, "-o", tmp_path / "talk.mp4", "--size", "64", "--json")
    assert code == 0, err
    assert "talk.wav (found beside the stream" in err
    summary = json.loads(out)
    info = probe_media(tmp_path / "talk.mp4")
    assert info.n_frames == summary["frames"] == len(stream) and info.width == 64
    assert summary["audio"].endswith("talk.wav") and abs(info.av_offset) <= 0.001


def test_play_png_frames_without_audio(cli, talk, tmp_path):
    path, stream = talk
    code, out, err = cli("play", path, "-o", tmp_path / "frames", "--size", "40x32", "--no-audio")
    assert code == 0, err
    pngs = sorted((tmp_path / "frames").glob("*.png"))
    assert len(pngs) == len(stream) and Image.open(pngs[0]).size == (40, 32)
    assert not (tmp_path / "frames" / "audio.wav").exists() and "frames at" in out


def test_play_says_what_it_padded(cli, talk, tmp_path):
    path, stream = talk
    _wav(tmp_path / "long.wav", stream.duration + 1.0)
    code, _, err = cli("play", path, "-o", tmp_path / "x.mp4", "--size", "32", "--audio", tmp_path / "long.wav")
    assert code == 0 and "warning: audio is" in err and "video padded with 25 frames" in err


def test_play_errors_are_one_line(cli, talk, tmp_path):
    path, _ = talk
    code, _, err = cli("play", path)
    assert code == 2 and "say where the frames go" in err  # a usage clash: exit 2 like argparse
    bad = tmp_path / "bad.wav"
    bad.write_text("not audio")
    code, _, err = cli("play", path, "-o", tmp_path / "x.mp4", "--audio", bad)
    assert code == 1 and "bad.wav" in err and err.count("\n") == 1
    code, _, err = cli("play", tmp_path / "missing.fba", "-o", tmp_path / "x.mp4")
    assert code == 1 and "missing.fba" in err
    with pytest.raises(SystemExit):
        main(["play", str(path), "-o", "x.mp4", "--size", "big"])


def test_snapshot(cli, talk, tmp_path):
    path, stream = talk
    code, out, err = cli("snapshot", path, "--frame", "3", "-o", tmp_path / "f3.png", "--size", "96", "--aa", "4")
    assert code == 0, err
    assert Image.open(tmp_path / "f3.png").size == (96, 96)
    code, _, err = cli("snapshot", path, "--frame", str(len(stream)), "-o", tmp_path / "f.png")
    assert code == 1 and "outside the stream" in err
