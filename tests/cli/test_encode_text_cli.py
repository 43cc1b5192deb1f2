"""`mpeg4fa encode TEXT`: speech, FAP stream, timings and the speaker's FDP from the command line."""
import io
import json
import wave

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.fba import decode
from mpeg4fa.fdp import load_fdp

TEXT = "(joy, 40, 0.5) Hello there, (sadness, 20, 1) my old friend."


def _wav_seconds(path):
    with wave.open(str(path)) as f:
        return f.getnframes() / f.getframerate()


def test_text_to_stream_audio_and_timings(cli, tmp_path):
    out, wav, timings = tmp_path / "talk.fba", tmp_path / "talk.wav", tmp_path / "talk.json"
    code, _, err = cli("encode", TEXT, "-o", out, "--audio", wav, "--timings", timings)
    assert code == 0, err
    stream = decode(out)
    assert abs(stream.duration - _wav_seconds(wav)) < 0.04  # frames cover the audio
    assert "bits/frame" in err and "high-level" in err
    rows = json.loads(timings.read_text(encoding="utf-8"))
    assert set(rows[0]) == {"phoneme", "viseme", "start", "end"}
    spoken = [r for r in rows if r["viseme"] != "none"]
    assert spoken[0]["viseme"] == "kk" and all(r["start"] <= r["end"] for r in rows)
    assert max(r["end"] for r in rows) <= _wav_seconds(wav) + 1e-6
    assert stream.viseme[:, 0].any() and stream.expression[:, 0].any()  # FAP 1 and FAP 2 at the high level


def test_text_from_stdin_and_from_a_file(cli, tmp_path, monkeypatch):
    monkeypatch.setattr("sys.stdin", io.StringIO("你好，世界"))
    code, _, err = cli("encode", "-", "-o", tmp_path / "a.fba", "--level", "both", "--engine", "estimate")
    assert code == 0, err
    script = tmp_path / "script.txt"
    script.write_text("(surprise, 30, 0.2) Oh! The bridge is closed.\n", encoding="utf-8")
    code, _, err = cli("encode", script, "-o", tmp_path / "b.fba", "--level", "low", "--engine", "estimate")
    assert code == 0 and str(script) in err
    assert len(decode(tmp_path / "b.fba")) > 10


def test_a_long_text_is_not_taken_for_a_file_name(cli, tmp_path):
    long_text = "Hello there. " * 40  # longer than any file name may be
    code, _, err = cli("encode", long_text, "-o", tmp_path / "a.fba", "--engine", "estimate")
    assert code == 0, err


def test_stream_input_still_reencodes_and_refuses_text_options(cli, tmp_path):
    cli("encode", "Hello", "-o", tmp_path / "a.fba", "--engine", "estimate")
    code, _, err = cli("encode", tmp_path / "a.fba", "-o", tmp_path / "b.fba")
    assert code == 0 and decode(tmp_path / "b.fba").duration == pytest.approx(decode(tmp_path / "a.fba").duration)
    code, _, err = cli("encode", tmp_path / "a.fba", "-o", tmp_path / "c.fba", "--audio", tmp_path / "x.wav")
    assert code == 2 and "--audio apply to text input" in err


def test_errors_are_one_line(cli, tmp_path):
    code, _, err = cli("encode", "Hello (joi, 40, 0.5) there", "-o", tmp_path / "a.fba")
    assert code == 1 and "1:8" in err and "joy" in err and len(err.strip().splitlines()) == 1
    code, _, err = cli("encode", "Hello", "-o", tmp_path / "a.fba", "--engine", "estimate", "--audio", tmp_path / "a.wav")
    assert code == 2 and "no audio" in err
    code, _, err = cli("encode", "Hello", "-o", tmp_path / "a.fba", "--fdp-out", tmp_path / "f.fdp",
                       "--front", tmp_path / "missing.png", "--side-points", tmp_path / "side.json")
    assert code == 2 and "--front-points" in err and "--side missing" in err
    code, _, err = cli("encode", "Hello", "-o", tmp_path / "a.fba", "--fdp-out", tmp_path / "f.fdp",
                       "--front", tmp_path / "missing.png")   # no points: the face is to be found in the photo
    assert code == 1 and "missing.png" in err and len(err.strip().splitlines()) == 1


def _project(points: dict, view: str, scale: float) -> dict:
    """Orthographic pixel positions (x right, y down) on a 400x480 photo, the points centred."""
    across = {"front": np.array([1.0, 0, 0]), "left": np.array([0, 0, -1.0])}[view]
    xy = np.array([[p @ across, p[1]] for p in points.values()])
    mid = (xy.min(axis=0) + xy.max(axis=0)) / 2
    return {label: [200 + scale * (x - mid[0]), 240 - scale * (y - mid[1])] for label, (x, y) in zip(points, xy)}


def _similarity_residual(a: np.ndarray, b: np.ndarray) -> float:
    """RMS of b - (s a + t) after the best uniform scale and translation, relative to b's size."""
    a0, b0 = a - a.mean(axis=0), b - b.mean(axis=0)
    s = (a0 * b0).sum() / (a0 * a0).sum()
    return float(np.sqrt(((b0 - s * a0) ** 2).sum(axis=1).mean()) / np.ptp(b, axis=0).max())


def test_fdp_from_a_front_and_a_side_photo(cli, tmp_path, procedural_face):
    """Points seen on a front and a left photo come back as the head's 3D feature points (up to scale)."""
    truth = {label: procedural_face.mesh.fp(label) for label in procedural_face.mesh.fp_labels
             if label[0] in "23489" and label != "11.5"}
    side_seen = {k: v for k, v in truth.items() if v[0] >= -1e-6}  # a left photo sees the face's left half
    (tmp_path / "front.json").write_text(json.dumps(_project(truth, "front", 2.0)))
    (tmp_path / "side.json").write_text(json.dumps(_project(side_seen, "left", 1.5)))
    Image.new("RGB", (400, 480), (180, 140, 120)).save(tmp_path / "front.png")
    Image.new("RGB", (400, 480), (180, 140, 120)).save(tmp_path / "side.png")
    args = ["encode", "Hello", "-o", tmp_path / "a.fba", "--engine", "estimate",
            "--fdp-out", tmp_path / "face.fdp", "--front", tmp_path / "front.png",
            "--front-points", tmp_path / "front.json", "--side", tmp_path / "side.png",
            "--side-points", tmp_path / "side.json", "--side-view", "left"]
    code, _, err = cli(*args)
    assert code == 0, err
    fdp = load_fdp(tmp_path / "face.fdp")
    got = {label: fdp.points[fdp.index(label)] for label in fdp.labels}
    assert set(got) >= set(side_seen) and len(got) >= 0.8 * len(truth)  # right-half points via their twins
    direct = sorted(side_seen)
    assert _similarity_residual(np.array([truth[k] for k in direct]), np.array([got[k] for k in direct])) < 1e-6
    assert fdp.textures and fdp.textures[0].media_type == "image/png" and fdp.texture_coords is not None
    assert (fdp.texture_coords >= 0).all() and (fdp.texture_coords <= 1).all()
    mirrored = {k: [400 - x, y] for k, (x, y) in _project(side_seen, "left", 1.5).items()}
    (tmp_path / "side.json").write_text(json.dumps(mirrored))  # the nose now points the wrong way
    code, _, err = cli(*args)
    assert code == 1 and "side.json" in err and len(err.strip().splitlines()) == 1


def test_fdp_from_a_mesh_with_feature_points(cli, tmp_path):
    obj = tmp_path / "face.obj"
    obj.write_text("v 0 0 0\nv 10 0 0\nv 0 10 0\nv 10 10 5\nvt 0 0\nvt 1 0\nvt 0 1\nvt 1 1\n"
                   "f 1/1 2/2 4/4 3/3\n")
    (tmp_path / "points.json").write_text(json.dumps({"9.3": 3, "2.1": [5, -2, 1]}))
    code, _, err = cli("encode", "Hi", "-o", tmp_path / "a.fba", "--engine", "estimate", "--fdp-out",
                       tmp_path / "face.json", "--face-mesh", obj, "--face-points", tmp_path / "points.json")
    assert code == 0, err
    fdp = load_fdp(tmp_path / "face.json")
    assert fdp.mesh is not None and len(fdp.mesh.triangles) == 2
    assert fdp.points[fdp.index("9.3")].tolist() == [10, 10, 5]


@pytest.mark.usefixtures("generic_head_installed")
def test_fdp_of_the_default_head(cli, tmp_path):
    code, _, err = cli("encode", "Hi", "-o", tmp_path / "a.fba", "--engine", "estimate", "--fdp-out",
                       tmp_path / "face.fdp")
    assert code == 0, err
    fdp = load_fdp(tmp_path / "face.fdp")
    assert len(fdp.labels) > 60 and fdp.fapu is not None
