"""Every real stream other systems wrote plays: the non-speech .fba vectors (face+body and body
only), the Xface .fap files, and (in test_player) the English ones with their speech.

Those streams carry values a face cannot mean (negative ``open_jaw`` and cheek lifts); the
decoder clamps them and says so once per FAP, with the frame count and the worst value.
"""
from __future__ import annotations

import math
import re
import warnings
from pathlib import Path

import pytest

from mpeg4fa.face import FaceWarning
from mpeg4fa.decoded.limits import LOWER, UPPER
from mpeg4fa.decoded import resolve
from mpeg4fa.formats import read_stream
from mpeg4fa.render import RenderWarning, play
from mpeg4fa.render.timing import schedule
from mpeg4fa.render.video import probe_media

SHARED = Path(__file__).resolve().parents[2] / ".." / "shared" / "vectors"
LONG = 250  # long streams play their first 250 frames (the whole stream is resolved and clamped)
SIZE = {"width": 48, "height": 48}


def _streams() -> list[Path]:
    if not SHARED.is_dir():
        return []
    found = [p for p in (SHARED / "fba").iterdir() if p.is_file() and p.suffix.lower() == ".fba"]
    found += [p for p in (SHARED / "fap").iterdir() if p.is_file()]
    return sorted(found)


needs_vectors = pytest.mark.skipif(not SHARED.is_dir(), reason="../shared/vectors not present: real streams not played")


@needs_vectors
def test_the_vectors_are_all_here():
    names = {p.name for p in _streams()}
    assert {"angry_0.fba", "headmotion_long.fba", "basicMotion.FBA", "xface-joy.fap", "xface-anger.fap"} <= names
    assert len(names) >= 17


@needs_vectors
@pytest.mark.parametrize("path", _streams(), ids=lambda p: p.name)
def test_every_real_stream_plays_to_mp4(generic_face, tmp_path, path):
    stream, _ = read_stream(path)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        values = resolve(stream)
    said = [str(w.message) for w in caught if issubclass(w.category, FaceWarning)]
    assert not [w for w in caught if not issubclass(w.category, FaceWarning)]
    assert ((values >= LOWER) & (values <= UPPER)).all()
    # one warning per clamped FAP, naming it with its frame count
    faps = [int(re.match(r"FAP (\d+) ", m).group(1)) for m in said]
    assert len(faps) == len(set(faps)), said
    for message in said:
        assert re.search(r"in \d+ frames? of the stream \(as far as -?\d", message), message
    played = stream if len(stream) <= LONG else stream.take(list(range(LONG)))
    wav = path.with_suffix(".wav")
    out = tmp_path / f"{path.stem}.mp4"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", FaceWarning)
        warnings.simplefilter("ignore", RenderWarning)
        result = play(played, out, face=generic_face, audio=wav if wav.is_file() else None, **SIZE)
    info = probe_media(out)
    assert info.n_frames == result.n_frames == math.ceil(schedule(played).duration * result.fps - 1e-6)
    assert info.n_frames >= min(len(stream), LONG)


@needs_vectors
def test_the_visage_streams_are_clamped_as_measured(generic_face):
    """angry_0 sends open_jaw down to -64 in 60 frames and both cheek lifts to -20 in 59."""
    stream, _ = read_stream(SHARED / "fba" / "angry_0.fba")
    with pytest.warns(FaceWarning) as caught:
        resolve(stream)
    said = sorted(str(w.message) for w in caught)
    assert said == [
        "FAP 3 (open_jaw) is negative on a unidirectional FAP in 60 frames of the stream (as far as -64): "
        "clamped to 0",
        "FAP 41 (lift_l_cheek) is negative on a unidirectional FAP in 59 frames of the stream (as far as -20): "
        "clamped to 0",
        "FAP 42 (lift_r_cheek) is negative on a unidirectional FAP in 59 frames of the stream (as far as -20): "
        "clamped to 0",
    ]


@needs_vectors
def test_play_cli_says_each_clamp_once_in_one_line(cli, generic_face, tmp_path):
    code, out, err = cli("play", SHARED / "fap" / "xface-anger.fap", "-o", tmp_path / "anger.mp4", "--size", "32")
    assert code == 0, err
    lines = [line for line in err.splitlines() if "clamped" in line]
    assert len(lines) == 3 and all(line.startswith("mpeg4fa play: warning: FAP ") for line in lines), err
    assert "Traceback" not in err and "warnings.warn" not in err
