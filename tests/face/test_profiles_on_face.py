"""The shared viseme and expression profiles, played on a face, look like what they are named.

``spec/viseme_faps.csv`` and ``spec/expression_faps.csv`` are our own tables (the
standard only names visemes and expressions); these tests pose both faces with
them and check the mouth and brow shapes that make a viseme readable.
"""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.spec import EXPRESSION_PROFILES, VISEME_PROFILES


def _shape(face, values=None) -> dict[str, float | np.ndarray]:
    pose = face.neutral() if values is None else face.deform(np.asarray(values, dtype=float))
    fp = {label: pose.feature_points[i] for i, label in enumerate(face.mesh.fp_labels)}
    return {
        "fp": fp,
        "gap": float(fp["2.2"][1] - fp["2.3"][1]),  # inner lip opening
        "width": float(fp["8.3"][0] - fp["8.4"][0]),  # outer mouth width
        "chin": float(fp["2.1"][1]),
    }


@pytest.fixture(scope="module")
def neutral(face):
    return _shape(face)


def viseme(face, name, set_name="mpeg4"):
    return _shape(face, VISEME_PROFILES[set_name][name])


def expression(face, name):
    return _shape(face, EXPRESSION_PROFILES[name])


@pytest.mark.parametrize("set_name,name", [("mpeg4", "PP"), ("zh", "bpm")])
def test_bilabial_closes_the_mouth(face, neutral, set_name, name):
    s = viseme(face, name, set_name)
    assert s["gap"] <= neutral["gap"] + 0.5


@pytest.mark.parametrize("set_name,name", [("mpeg4", "AA"), ("zh", "a")])
def test_open_vowel_opens_the_mouth(face, neutral, set_name, name):
    s = viseme(face, name, set_name)
    assert s["gap"] >= 8.0, f"inner lip gap {s['gap']:.1f} mm"
    assert s["chin"] < neutral["chin"] - 8.0


@pytest.mark.parametrize("set_name,name", [("mpeg4", "ou"), ("zh", "uv")])
def test_rounded_vowel_narrows_the_mouth(face, neutral, set_name, name):
    s = viseme(face, name, set_name)
    assert s["width"] < neutral["width"] - 2.0


@pytest.mark.parametrize("set_name,name", [("mpeg4", "ou"), ("zh", "uv")])
def test_rounded_vowel_protrudes_the_inner_lips(face, neutral, set_name, name):
    s = viseme(face, name, set_name)
    for label in ("2.2", "2.3"):
        assert s["fp"][label][2] > neutral["fp"][label][2] + 1.0, label


@pytest.mark.parametrize("set_name,name", [("mpeg4", "E"), ("mpeg4", "ih"), ("zh", "i")])
def test_spread_vowel_widens_the_mouth(face, neutral, set_name, name):
    assert viseme(face, name, set_name)["width"] > neutral["width"] + 2.0


def test_joy_raises_the_mouth_corners(face, neutral):
    s = expression(face, "joy")
    for label in ("8.3", "8.4"):
        assert s["fp"][label][1] > neutral["fp"][label][1] + 1.0, label


def test_sadness(face, neutral):
    s = expression(face, "sadness")
    for label in ("8.3", "8.4"):
        assert s["fp"][label][1] < neutral["fp"][label][1] - 1.0, label
    for label in ("4.1", "4.2"):
        assert s["fp"][label][1] > neutral["fp"][label][1] + 1.0, label


def test_anger(face, neutral):
    s = expression(face, "anger")
    for label in ("4.1", "4.2"):
        assert s["fp"][label][1] < neutral["fp"][label][1] - 1.0, label
        assert abs(s["fp"][label][0]) < abs(neutral["fp"][label][0]) - 1.0, label


def test_surprise(face, neutral):
    s = expression(face, "surprise")
    for label in ("4.1", "4.2", "4.3", "4.4", "4.5", "4.6"):
        assert s["fp"][label][1] > neutral["fp"][label][1] + 1.0, label
    assert s["chin"] < neutral["chin"] - 3.0, "the jaw drops"
    assert s["gap"] > neutral["gap"] + 3.0


def test_profiles_are_symmetric_on_the_face(face, request):
    """Every profile poses a mirror-symmetric face (the tables treat both sides alike)."""
    mesh = face.mesh
    flip = np.array([-1.0, 1.0, 1.0])
    profiles = [p for s in VISEME_PROFILES.values() for p in s.values()] + list(EXPRESSION_PROFILES.values())
    for values in profiles:
        v = face.deform(np.asarray(values, dtype=float)).vertices
        assert np.abs(v[mesh.mirror] * flip - v).max() <= 1e-6
