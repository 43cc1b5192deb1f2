"""Huge or degenerate meshes given to the rig (fuzz obj campaigns of issue 26 item 9: numpy warnings at
face/lids.py and face/custom.py): refused with one FaceError before the arithmetic, or, for an eye modelled
shut, rigged without a division by zero."""
from __future__ import annotations

import re
import warnings

import numpy as np
import pytest

from mpeg4fa.face import FaceError
from mpeg4fa.face.custom import head_from_mesh
from mpeg4fa.face.lids import build_lids
from mpeg4fa.fdp.model import MAX_COORDINATE


@pytest.fixture(autouse=True)
def _no_stray_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


@pytest.fixture(scope="module")
def skin(procedural_head):
    """The procedural head's skin as a plain mesh: (vertices, triangles, points; the pupils as coordinates)."""
    t = procedural_head.triangles["skin"]
    keep = np.unique(t)
    new = np.full(procedural_head.n_vertices, -1)
    new[keep] = np.arange(len(keep))
    points = {label: int(new[v]) for label, v in zip(procedural_head.fp_labels, procedural_head.fp_vertex)
              if new[v] >= 0}
    points["3.5"], points["3.6"] = procedural_head.fp("3.5").tolist(), procedural_head.fp("3.6").tolist()
    return procedural_head.vertices[keep], new[t], points


def test_an_eye_modelled_shut_rigs_without_dividing_by_zero(skin):
    v, t, points = skin
    v = v.copy()
    v[points["3.1"], :2] = v[points["3.3"], :2]  # the upper lid point on the lower margin: no lid opening
    lids = build_lids(head_from_mesh(v, t, points))
    assert not np.abs(lids[19].ratios).any() and len(lids[20].rows) and np.isfinite(lids[20].ratios).all()


@pytest.mark.parametrize("value", [1e308, -2 * MAX_COORDINATE, np.nan])
def test_a_vertex_beyond_the_bound_is_refused_before_the_rig(skin, value):
    v, t, points = skin
    v = v.copy()
    v[7, 1] = value
    with pytest.raises(FaceError, match=rf"vertex 7 is at .*within \+-{re.escape(f'{MAX_COORDINATE:g}')}") as info:
        head_from_mesh(v, t, points)
    assert info.value.where == "vertices/7"


def test_uvs_and_coordinate_points_beyond_the_bound_are_refused(skin):
    v, t, points = skin
    uvs = np.zeros((len(v), 2))
    uvs[3] = (0.5, 1e300)
    with pytest.raises(FaceError, match="the uv of vertex 3 is at"):
        head_from_mesh(v, t, points, uvs=uvs)
    with pytest.raises(FaceError, match="feature point 3.5 must be a vertex index or"):
        head_from_mesh(v, t, {**points, "3.5": [1e308, 0.0, 0.0]})


def test_a_mesh_without_area_is_refused(skin):
    v, t, points = skin
    flat = v.copy()
    flat[:, 1:] = 0.0  # every vertex on the x axis
    with pytest.raises(FaceError, match="the mesh has no area"):
        head_from_mesh(flat, t, points)
