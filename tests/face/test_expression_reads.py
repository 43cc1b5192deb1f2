"""The six expressions at intensity 63 read at a glance (issue 29, item 1).

Each expression's measures (``mpeg4fa/face/data/expression_reads.csv``: joy's lip corners up >= 5 mm,
disgust's upper lip up >= 4 mm and a wrinkled nose, ...) hold under the feature-point and the ARKit
deformers, on the generic head and on the conformance suite's adult and child heads calibrated to
it (thresholds scaled by each head's FAPU), and on the procedural test head.
"""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.conformance.manifest import default_root
from mpeg4fa.face.looks import UNIT, expression_reads, measures, points_of, scale_of
from mpeg4fa.fdp import load_fdp
from mpeg4fa.spec import EXPRESSION_PROFILES

EXPRESSIONS = ("joy", "sadness", "anger", "fear", "disgust", "surprise")
HEADS = ("generic", "adult", "child")
_FACES: dict = {}


def _face(request, head: str, deformer: str):
    if (head, deformer) not in _FACES:
        base = request.getfixturevalue("generic_face")
        if head != "generic":
            key = (head, "fap")
            if key not in _FACES:
                _FACES[key] = base.calibrate(load_fdp(default_root() / "faces" / f"{head}.fdp"), method="elastic")
            base = _FACES[key]
        _FACES[(head, deformer)] = base if deformer == "fap" else base.with_deformer(deformer)
    return _FACES[(head, deformer)]


def _measured(face, name: str) -> dict[str, float]:
    labels = face.mesh.fp_labels
    posed = face.deform(np.asarray(EXPRESSION_PROFILES[name], float))
    return measures(points_of(labels, face.neutral().feature_points), points_of(labels, posed.feature_points))


def _failures(face, name: str) -> list[str]:
    got = _measured(face, name)
    return [f"{r.measure} = {got[r.measure]:.2f} (wanted {r.wanted(scale_of(r.measure, face.fapu))}: {r.why})"
            for r in expression_reads() if r.expression == name
            and not r.holds(got[r.measure], scale_of(r.measure, face.fapu))]


def test_every_expression_has_reads():
    assert {r.expression for r in expression_reads()} == set(EXPRESSIONS)
    assert {r.measure for r in expression_reads()} <= set(UNIT)


@pytest.mark.parametrize("deformer", ["fap", "arkit"])
@pytest.mark.parametrize("head", HEADS)
@pytest.mark.parametrize("name", EXPRESSIONS)
def test_expression_reads_at_full_intensity(request, head, deformer, name):
    face = _face(request, head, deformer)
    assert not _failures(face, name), f"{name} on the {head} head ({deformer}): " + "; ".join(_failures(face, name))


@pytest.mark.parametrize("name", EXPRESSIONS)
def test_expression_reads_on_the_procedural_head(procedural_face, name):
    assert not _failures(procedural_face, name)


def test_the_issue_figures(generic_face):
    """The two figures the issue names, in mm on the generic head."""
    joy, disgust = _measured(generic_face, "joy"), _measured(generic_face, "disgust")
    assert joy["corner_rise"] >= 5.0 and disgust["upper_lip_rise"] >= 4.0
    assert disgust["nose_wrinkle"] >= 0.5
    neutral = _measured(generic_face, "neutral")
    assert all(abs(v) < 1e-9 for v in neutral.values())


def test_reads_fail_a_faint_expression(generic_face):
    """The measures can fail: joy at a third of its intensity is no full smile."""
    labels = generic_face.mesh.fp_labels
    faint = generic_face.deform(np.asarray(EXPRESSION_PROFILES["joy"], float) / 3)
    got = measures(points_of(labels, generic_face.neutral().feature_points), points_of(labels, faint.feature_points))
    assert not next(r for r in expression_reads() if r.measure == "corner_rise").holds(got["corner_rise"])


def test_a_smaller_head_scales_the_thresholds(request):
    child = _face(request, "child", "fap")
    assert scale_of("corner_rise", child.fapu) < 0.8
    assert scale_of("nose_wrinkle", child.fapu) == 1.0
