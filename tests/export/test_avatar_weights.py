"""Per-frame ARKit-52 and Oculus/OVR-15 weights (mpeg4fa.export.weights) and their JSON."""
import json

import numpy as np
import pytest

from mpeg4fa.decoded import resolve
from mpeg4fa.export import arkit_weights, oculus_weights, viseme_weights, write_weights_json
from mpeg4fa.fba import EncodeOptions, encode
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.spec import FAP_BY_NAME, VISEMES
from mpeg4fa.spec.avatars import ARKIT_BLENDSHAPES, OCULUS_VISEMES
from mpeg4fa.spec.profiles import VISEME_PROFILES

MPEG4 = [v.name for v in VISEMES]
CODE = {name: k for k, name in enumerate(MPEG4)}
FPS = 25.0


def _fap1_stream(rows) -> FapStream:
    """A stream sending only FAP 1: ``rows`` of (select1, select2, blend)."""
    stream = FapStream.empty(len(rows))
    stream.source_fps = FPS
    stream.timestamps[:] = np.arange(len(rows)) / FPS
    stream.fap_mask[:, 0] = True
    stream.viseme[:, :3] = [(CODE[a], CODE[b], blend) for a, b, blend in rows]
    return stream


def _low_level_stream(frames) -> FapStream:
    frames = np.asarray(frames)
    stream = FapStream.empty(len(frames))
    stream.source_fps = FPS
    stream.timestamps[:] = np.arange(len(frames)) / FPS
    used = np.flatnonzero(np.abs(frames).max(axis=0) > 0)
    stream.fap_mask[:, used] = True
    stream.fap_values[:, used] = frames[:, used]
    return stream


def _ramp(viseme: str, n: int = 8):
    """From rest to full ``viseme`` in ``n`` frames."""
    return [(viseme, "none", int(round(63 * k / (n - 1)))) for k in range(n)]


def test_fap1_fields_give_the_viseme_weights():
    w = viseme_weights(_fap1_stream([("AA", "none", 63), ("AA", "PP", 21), ("none", "none", 0)]))
    assert w[0, CODE["AA"]] == 1.0
    assert w[1, CODE["AA"]] == pytest.approx(1 / 3) and w[1, CODE["PP"]] == pytest.approx(2 / 3)
    assert w[2, CODE["none"]] == 1.0
    assert np.allclose(w.sum(axis=1), 1.0)


def test_fap1_weights_hold_between_sent_frames():
    stream = _fap1_stream([("ou", "none", 63), ("AA", "none", 63), ("AA", "none", 63)])
    stream.fap_mask[1:, 0] = False  # sent once: a decoder holds it
    assert (viseme_weights(stream)[:, CODE["ou"]] == 1.0).all()


@pytest.mark.parametrize("name", MPEG4[1:])
def test_low_level_visemes_are_fitted_to_the_profiles(name):
    """A stream carrying a viseme's FAPs (no FAP 1) shows that viseme: the fit finds it alone."""
    profile = VISEME_PROFILES["mpeg4"][name]
    w = viseme_weights(_low_level_stream([profile * 0, profile * 0.5, profile]))
    assert w[0, CODE["none"]] == pytest.approx(1.0)
    assert w[1, CODE[name]] == pytest.approx(0.5, abs=1e-6) and w[1, CODE["none"]] == pytest.approx(0.5, abs=1e-6)
    assert w[2, CODE[name]] == pytest.approx(1.0, abs=1e-6)


def test_oculus_weights_are_the_mpeg4_weights_in_ovr_order():
    stream = _fap1_stream(_ramp("AA") + _ramp("ou"))
    w = oculus_weights(stream)
    assert w.names == tuple(v.name for v in OCULUS_VISEMES) and w.kind == "oculus"
    assert np.allclose(w.values.sum(axis=1), 1.0) and (w.values >= 0).all() and (w.values <= 1).all()
    aa, sil = w.names.index("aa"), w.names.index("sil")
    assert w.values[7, aa] == 1.0 and w.values[0, sil] == 1.0
    assert np.allclose(w.times, np.arange(len(stream)) / FPS)


def test_resampled_to_another_rate():
    stream = _fap1_stream(_ramp("AA", 10))
    w = oculus_weights(stream, fps=50.0)
    assert w.fps == 50.0 and len(w.times) == 20 and np.allclose(np.diff(w.times), 0.02)
    assert np.array_equal(w.values[::2], oculus_weights(stream).values)


def test_weights_json_schema(tmp_path):
    w = oculus_weights(_fap1_stream(_ramp("E", 4)))
    path = tmp_path / "w.json"
    write_weights_json(w, path)
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert doc["format"] == "mpeg4fa-oculus-weights" and doc["version"] == 1 and doc["fps"] == FPS
    assert doc["names"] == list(w.names) and len(doc["frames"]) == 4
    assert doc["frames"][3] == {"time": 0.12, "weights": [1.0 if n == "E" else 0.0 for n in w.names]}
    assert [p.name for p in tmp_path.iterdir()] == ["w.json"]  # no temporary left beside it


@pytest.fixture(scope="module")
def head(generic_face):
    return generic_face


def test_arkit_weights_are_the_deformers_and_in_range(head):
    from mpeg4fa.face.deformers.arkit import unit_weights

    stream = _fap1_stream(_ramp("AA") + _ramp("ou") + _ramp("PP") + _ramp("E"))
    w = arkit_weights(stream, head)
    assert w.names == ARKIT_BLENDSHAPES and w.values.shape == (len(stream), 52)
    assert (w.values >= 0).all() and (w.values <= 1).all()
    rig, values = head.arkit_rig, resolve(stream)
    for k in (3, 7, 15):  # jawOpen is one driven unit: exactly the deformer's weight
        assert w.values[k, ARKIT_BLENDSHAPES.index("jawOpen")] == unit_weights(rig, values[k])[
            rig.unit_names.index("jawOpen")]


def test_jaw_opens_with_the_open_viseme(head):
    jaw = ARKIT_BLENDSHAPES.index("jawOpen")
    opening = arkit_weights(_fap1_stream(_ramp("AA")), head).values[:, jaw]
    assert opening[0] == 0 and (np.diff(opening) >= 0).all() and opening[-1] > 0.3
    closed = arkit_weights(_fap1_stream(_ramp("PP")), head).values[-1, jaw]
    assert closed < opening[-1] / 3
    pucker = ARKIT_BLENDSHAPES.index("mouthPucker")
    assert arkit_weights(_fap1_stream(_ramp("ou")), head).values[-1, pucker] > 0.1


def test_lids_drive_the_blinks(head):
    frames = np.zeros((3, len(FAP_BY_NAME)))
    frames[1, FAP_BY_NAME["close_t_l_eyelid"].number - 1] = 512
    frames[2, FAP_BY_NAME["close_t_l_eyelid"].number - 1] = 1024
    frames[2, FAP_BY_NAME["close_t_r_eyelid"].number - 1] = 2000
    w = arkit_weights(_low_level_stream(frames), head)
    left, right = ARKIT_BLENDSHAPES.index("eyeBlinkLeft"), ARKIT_BLENDSHAPES.index("eyeBlinkRight")
    assert w.values[:, left].tolist() == [0.0, 0.5, 1.0] and w.values[:, right].tolist() == [0.0, 0.0, 1.0]


def test_a_head_without_units_is_refused(procedural_face):
    from mpeg4fa.errors import MpegFaError
    with pytest.raises(MpegFaError, match="no ARKit face units"):
        arkit_weights(_fap1_stream(_ramp("AA")), procedural_face)


def test_export_weights_on_the_command_line(cli, tmp_path):
    src = tmp_path / "talk.fba"
    src.write_bytes(encode(_fap1_stream(_ramp("AA") + _ramp("PP")), EncodeOptions()))
    out = tmp_path / "talk.ovr.json"
    code, printed, err = cli("export", src, "--format", "oculus-json", "-o", out)
    assert code == 0, err
    doc = json.loads(out.read_text())
    assert doc["format"] == "mpeg4fa-oculus-weights" and len(doc["frames"]) == 16 and "16 frames" in printed
    assert cli("export", src, "-o", tmp_path / "x.json")[0] == 2  # .json alone names no format
    assert cli("export", src, "--format", "oculus-json", "--fps", "50", "-o", out)[0] == 0
    doc = json.loads(out.read_text())
    assert doc["fps"] == 50.0 and len(doc["frames"]) == 32
    assert cli("export", src, "--format", "azure-json", "--fps", "50", "-o", tmp_path / "a.json")[0] == 2
    assert cli("export", src, "--fps", "50", "-o", tmp_path / "a.glb")[0] == 2
    assert cli("export", src, "--format", "oculus-json", "-o", src)[0] != 0 and src.stat().st_size > 0


@pytest.mark.usefixtures("generic_head_installed")
def test_export_arkit_json_on_the_command_line(cli, tmp_path):
    src = tmp_path / "talk.fba"
    src.write_bytes(encode(_fap1_stream(_ramp("AA")), EncodeOptions()))
    out = tmp_path / "talk.arkit.json"
    code, _, err = cli("export", src, "--format", "arkit-json", "-o", out)
    assert code == 0, err
    doc = json.loads(out.read_text())
    assert doc["names"] == list(ARKIT_BLENDSHAPES) and doc["frames"][-1]["weights"][17] > 0.3


def test_every_viseme_of_both_sets_has_arkit_weights(head):
    from mpeg4fa.export import viseme_arkit_table

    table = viseme_arkit_table(head)
    assert set(table) == {(s, v) for s, names in VISEME_PROFILES.items() for v in names}
    jaw, pucker = ARKIT_BLENDSHAPES.index("jawOpen"), ARKIT_BLENDSHAPES.index("mouthPucker")
    for weights in table.values():
        assert weights.shape == (52,) and (weights >= 0).all() and (weights <= 1).all()
    assert not table[("mpeg4", "none")].any() and not table[("zh", "none")].any()
    assert table[("mpeg4", "AA")][jaw] > 3 * table[("mpeg4", "PP")][jaw]
    assert table[("zh", "a")][jaw] > 3 * table[("zh", "bpm")][jaw]
    assert table[("zh", "uv")][pucker] > table[("zh", "i")][pucker]


@pytest.mark.parametrize("frames", [0, 1, 4096, 4097, 9000])
def test_weights_json_written_in_blocks_is_the_whole_document(tmp_path, frames):
    """The writer turns a block of frames into text at a time (a million frames as one document took 3.3 GB):
    the file is still exactly the one document, block edges included."""
    from mpeg4fa.export.weights import Weights, weights_document

    rng = np.random.default_rng(frames)
    w = Weights("arkit", ARKIT_BLENDSHAPES, np.arange(frames) / 25.0, rng.random((frames, len(ARKIT_BLENDSHAPES))), 25.0)
    path = tmp_path / "w.json"
    write_weights_json(w, path)
    assert path.read_text(encoding="utf-8") == json.dumps(weights_document(w), separators=(",", ":")) + "\n"
