"""Rounded visemes read as rounded: the mouth narrows by a quarter of MW0 and the lips come forward.

Lip protrusion needs the outer lip to follow FAPs 16/17 (documented couplings in
``face/data/couplings.csv``): with the inner lip points alone the vermilion border stays put.
"""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.spec.profiles import VISEME_PROFILES

ROUNDED = [("mpeg4", "ou"), ("mpeg4", "oh"), ("zh", "uv"), ("zh", "o")]


@pytest.mark.parametrize("deformer", ["fap", "arkit"])
@pytest.mark.parametrize("viseme_set,name", ROUNDED)
def test_rounded_visemes_narrow_the_mouth_and_push_the_lips_forward(generic_face, deformer, viseme_set, name):
    face = generic_face.with_deformer(deformer)
    mesh = face.mesh
    pose = face.deform(VISEME_PROFILES[viseme_set][name].astype(float))
    fp = pose.feature_points
    corner = [mesh.fp_index(label) for label in ("8.3", "8.4")]
    width0 = np.linalg.norm(mesh.fp("8.3") - mesh.fp("8.4"))
    width = np.linalg.norm(fp[corner[0]] - fp[corner[1]])
    assert (width0 - width) >= 0.25 * face.fapu.MW0, (width0 - width) / face.fapu.MW0
    forward = {label: fp[mesh.fp_index(label)][2] - mesh.fp(label)[2] for label in ("8.1", "2.2", "2.3")}
    assert forward["8.1"] >= 1.5 and forward["2.2"] >= 2.0, forward
    assert forward["2.3"] >= 1.0, forward
    # the lower vermilion does not fall back behind the neutral lip although the jaw opens
    assert fp[mesh.fp_index("8.2")][2] - mesh.fp("8.2")[2] >= -1.0


def test_spread_visemes_do_not_narrow(generic_face):
    mesh = generic_face.mesh
    width0 = np.linalg.norm(mesh.fp("8.3") - mesh.fp("8.4"))
    for name in ("E", "ih"):
        fp = generic_face.deform(VISEME_PROFILES["mpeg4"][name].astype(float)).feature_points
        assert np.linalg.norm(fp[mesh.fp_index("8.3")] - fp[mesh.fp_index("8.4")]) >= width0
