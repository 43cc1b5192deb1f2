"""Photos that share too few labels: the error names the photo and the labels each one has (fuzz full1,
target points: an unlocated FdpValueError from build._side_scale, 'where' empty); through the CLI the same
error names both points files (cli/speech.py _located)."""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from mpeg4fa.fdp import FdpValueError, points_from_photos

from .test_build import FACE, front_photo, side_photo


def test_no_shared_label_names_the_side_photo_and_the_labels():
    face = {k: np.array(p, float) for k, p in FACE.items()}
    front = front_photo({k: face[k] for k in ("9.3", "2.1", "11.1")})
    side = side_photo({k: face[k] for k in ("11.6", "3.7", "3.11")}, "left")
    with pytest.raises(FdpValueError) as err:
        points_from_photos(front, side, side_view="left")
    assert err.value.field == ("left",) and err.value.where == "left"
    message = str(err.value)
    assert "0 label(s) annotated on both photos (none; front: 9.3, 2.1, 11.1; left: 11.6, 3.7, 3.11)" in message


def test_a_photo_point_far_outside_any_photo_is_refused_at_its_label():
    """fuzz points:29937@0: a side point at 1e308 passed as finite, and the depth check's mean overflowed
    (a numpy warning); photo points share the meshes' coordinate bound."""
    face = {k: np.array(p, float) for k, p in FACE.items()}
    side = side_photo(face, "left")
    side["9.3"] = (1e308, side["9.3"][1])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(FdpValueError, match=r"left photo point 9.3 must be \(x, y\) pixels \(finite numbers "
                                                r"within \+-1e\+09\)") as err:
            points_from_photos(front_photo(face), side, side_view="left")
    assert err.value.field == ("left", "9.3")
