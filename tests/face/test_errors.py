"""Bad input to the face layer: a FaceError that says what is wrong and where, never a crash."""
from __future__ import annotations

import io
import pickle
import warnings

import numpy as np
import pytest

from mpeg4fa.face import asset
from mpeg4fa.face.calibrate import calibrate_mesh
from mpeg4fa.face.errors import FaceError, FaceWarning
from mpeg4fa.face.fapu import measure_fapu
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.decoded import FapValueError, check_finite
from mpeg4fa.face.motion import direction
from mpeg4fa.spec import N_FAPS


@pytest.mark.parametrize("frame,fap", [
    ({4: float("nan")}, 4),
    ({19: float("inf")}, 19),
    ({5: -float("inf")}, 5),
])
def test_non_finite_faps_name_the_fap(procedural_face, frame, fap):
    with pytest.raises(FaceError) as info:
        procedural_face.deform(frame)
    assert f"FAP {fap}" in str(info.value)
    assert info.value.where == f"FAP {fap}"
    values = np.zeros(N_FAPS)
    values[fap - 1] = frame[fap]
    with pytest.raises(FaceError):
        procedural_face.deform(values)


@pytest.mark.parametrize("fap,value,bound", [
    (3, -1, 0),  # open_jaw is unidirectional
    (14, -50, 0),  # so is thrust_jaw
    (41, -160, 0),  # and lift_l_cheek (headmotion_long sends -160)
    (47, -1, 0),  # and tongue_roll
    (6, 8193, 8192),  # more than 8 mouth widths
    (31, -1e6, -8192),
    (48, 4e5, np.pi / 1e-5),  # more than pi radians
])
def test_values_no_face_can_show_are_clamped_with_a_warning(procedural_face, fap, value, bound):
    with pytest.warns(FaceWarning, match=f"FAP {fap} "):
        pose = procedural_face.deform({fap: value})
    expected = procedural_face.deform({fap: bound})
    assert np.array_equal(pose.vertices, expected.vertices)


def test_limits_are_inclusive(procedural_face):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        procedural_face.deform({6: 8192, 48: 314159})
        procedural_face.deform({3: 0})


@pytest.mark.parametrize("fap", [1, 2, 0, 69, -3])
def test_high_level_or_unknown_fap_in_a_mapping(procedural_face, fap):
    with pytest.raises(FaceError) as info:
        procedural_face.deform({fap: 5})
    assert info.value.hint, "the error says what to use instead"
    assert "3..68" in str(info.value)
    if fap in (1, 2):
        assert "viseme" in info.value.hint and "expression" in info.value.hint


def test_high_level_columns_of_an_array_are_ignored(procedural_face):
    values = np.zeros(N_FAPS)
    values[:2] = 12345
    assert np.array_equal(procedural_face.deform(values).vertices, procedural_face.mesh.vertices)


@pytest.mark.parametrize("shape", [
    (67,), (69,), (2, N_FAPS), (N_FAPS, 1), (0,), (),
])
def test_wrong_shape_frames(procedural_face, shape):
    with pytest.raises(FaceError) as info:
        procedural_face.deform(np.zeros(shape))
    assert "68" in str(info.value)
    if shape[-1:] != (N_FAPS,):  # check_finite takes one frame or n x 68
        with pytest.raises(FapValueError):  # the decoder-output layer's own error
            check_finite(np.zeros(shape))


def test_unknown_labels_and_names(procedural_head):
    mesh = procedural_head
    for call in (lambda: mesh.fp("12.1"), lambda: mesh.fp_index("2.15"), lambda: mesh.fp("")):
        with pytest.raises(FaceError) as info:
            call()
        assert "feature point" in str(info.value)
    with pytest.raises(FaceError, match="part"):
        mesh.part("nose")
    with pytest.raises(FaceError, match="joint"):
        mesh.joint("knee")
    with pytest.raises(FaceError, match="shape"):
        mesh.with_vertices(np.zeros((3, 3)))
    with pytest.raises(FaceError):
        direction(29)  # dilate_l_pupil ("growing") has no translational direction


def test_fapu_errors(procedural_face):
    with pytest.raises(FaceError, match="FAPU"):
        procedural_face.fapu.unit("XYZ")
    points = procedural_face.feature_points()
    del points["9.15"]
    with pytest.raises(FaceError, match="9.15"):
        measure_fapu(points)
    flipped = {label: p * np.array([-1.0, 1.0, 1.0]) for label, p in procedural_face.feature_points().items()}
    with pytest.raises(FaceError, match="non-positive"):
        measure_fapu(flipped)


def test_bad_calibration_requests(procedural_head):
    mesh = procedural_head
    p = mesh.fp("9.3")[None]
    with pytest.raises(FaceError, match="method"):
        calibrate_mesh(mesh, ("9.3",), p, method="spline")
    with pytest.raises(FaceError, match="alignment"):
        calibrate_mesh(mesh, ("9.3",), p, alignment="affine")
    with pytest.raises(FaceError, match="feature point"):
        calibrate_mesh(mesh, ("13.1",), p)
    with pytest.raises(FaceError, match="finite"):
        calibrate_mesh(mesh, ("9.3",), p * np.nan)


def test_face_error_text_and_pickling():
    e = FaceError("it broke", where="FAP 3", hint="try again")
    assert str(e) == "FAP 3: it broke (try again)"
    assert isinstance(e, ValueError)
    back = pickle.loads(pickle.dumps(e))
    assert (back.message, back.where, back.hint) == ("it broke", "FAP 3", "try again")


# -- the cached asset ---------------------------------------------------------------------------


@pytest.fixture
def empty_cache(tmp_path, monkeypatch):
    monkeypatch.setenv("MPEG4FA_CACHE", str(tmp_path))
    return tmp_path


def test_missing_asset_without_auto_install(empty_cache):
    assert asset.cache_dir() == empty_cache and not asset.is_installed()
    with pytest.raises(FaceError) as info:
        asset.load_head(auto_install=False)
    assert "mpeg4fa model install" in info.value.hint
    assert str(empty_cache) in str(info.value)


@pytest.mark.parametrize("content", [b"", b"not a numpy file at all" * 10, b"\x93NUMPY garbage"])
def test_corrupt_asset(empty_cache, content):
    asset.head_path().write_bytes(content)
    with pytest.raises(FaceError) as info:
        asset.load_head(auto_install=False)
    assert "model install" in info.value.hint


def test_asset_missing_arrays(empty_cache):
    with open(asset.head_path(), "wb") as f:
        np.savez(f, vertices=np.zeros((3, 3)))
    with pytest.raises(FaceError) as info:
        asset.load_head(auto_install=False)
    assert "lacks" in str(info.value)


def _valid_npz() -> bytes:
    buf = io.BytesIO()
    np.savez_compressed(buf, vertices=np.random.default_rng(0).random((2000, 3)))
    return buf.getvalue()


@pytest.mark.parametrize("damage", ["truncated", "scrambled"])
def test_damaged_asset(empty_cache, damage):
    data = bytearray(_valid_npz())
    if damage == "truncated":
        data = data[: len(data) // 2]
    else:
        for k in range(200, 400):
            data[k] ^= 0x55
    asset.head_path().write_bytes(bytes(data))
    with pytest.raises(FaceError):
        asset.load_head(auto_install=False)


def test_save_and_load_round_trip(procedural_head, tmp_path):
    path = tmp_path / "head.npz"
    procedural_head.save(path)
    back = HeadMesh.load(path)
    assert np.array_equal(back.vertices, procedural_head.vertices)
    assert back.part_ranges == procedural_head.part_ranges and back.joints == procedural_head.joints
    assert back.fp_labels == procedural_head.fp_labels and back.face_units is None
    for part in procedural_head.triangles:
        assert np.array_equal(back.triangles[part], procedural_head.triangles[part])
    assert not list(tmp_path.glob("*.part")), "the temporary file is gone"
