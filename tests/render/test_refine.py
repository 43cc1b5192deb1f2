"""The skin about the mouth drawn finer (render/refine.py): rounder between its mesh's corners, the same at them,
flat and unsplit along the patch's outline (no crack, no T-junction), on every viseme and expression."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.render.refine import LEVEL, SHARE, mouth_patch, refine, refined_vertices
from mpeg4fa.render.scene import build_layout, vertex_data
from mpeg4fa.spec.profiles import VISEME_PROFILES, expression_blend


@pytest.fixture(scope="module")
def patch(generic_face):
    layout = build_layout(generic_face.mesh)
    skin = len(generic_face.mesh.triangles["skin"])
    rows = mouth_patch(layout, np.arange(skin))
    return generic_face, layout, refine(layout, rows)


def _turns_across_parents(points: np.ndarray, triangles: np.ndarray, parents: np.ndarray) -> np.ndarray:
    """Degrees between the normals of each pair of finer triangles that share an edge and are cut from different
    triangles of the mesh: the turns across the mesh's own edges (a flat split keeps the mesh's creases there)."""
    v = points[triangles]
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1, keepdims=True), 1e-12)
    edges: dict[tuple[int, int], list[int]] = {}
    for t, tri in enumerate(np.asarray(triangles)):
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            edges.setdefault((min(a, b), max(a, b)), []).append(t)
    pairs = np.array([ts for ts in edges.values() if len(ts) == 2 and parents[ts[0]] != parents[ts[1]]])
    return np.degrees(np.arccos(np.clip((n[pairs[:, 0]] * n[pairs[:, 1]]).sum(axis=1), -1.0, 1.0)))


def test_the_patch_is_the_lips(patch):
    """The lips (every vertex of theirs a viewer sees from outside lies in it), skin only, a small share of it."""
    face, layout, p = patch
    assert 300 < len(p.triangles) < 0.1 * len(face.mesh.triangles["skin"])
    assert (layout.material[layout.indices[p.triangles]] == 0).all()  # skin only
    lips = np.flatnonzero(layout.lips > 0.5)
    seen = lips[layout.cavity[lips] < 0.05]
    assert np.isin(seen, layout.indices[p.triangles]).mean() > 0.95


@pytest.mark.parametrize("look", ["neutral", "viseme AA", "viseme PP", "expression joy", "expression surprise"])
def test_the_finer_skin_keeps_the_corners_and_rounds_between_them(patch, look):
    """Every mesh corner of the patch is where the mesh has it; across the mesh's own edges the finer triangles turn
    less than the same cut left flat does (the outline bends in more, smaller steps); and along the patch's outline
    no point is added (no T-junction with the skin beside it)."""
    face, layout, p = patch
    values = np.zeros(68)
    if look != "neutral":
        kind, name = look.split()
        values = np.asarray(VISEME_PROFILES["mpeg4"][name] if kind == "viseme" else expression_blend(name, 63, name, 0),
                            float)
        values[:2] = 0
    pose = face.pose_values(values)
    data = vertex_data(layout, pose.vertices)
    points = refined_vertices(p, data).astype(np.float64)
    at_corner = p.weights.max(axis=1) > 0.999
    corner_of = p.corners[np.arange(len(p.corners)), p.weights.argmax(axis=1)]
    assert np.abs(points[at_corner, :3] - data[corner_of[at_corner], :3]).max() < 1e-4
    flat = (p.weights[:, :, None] * data[p.corners, :3].astype(np.float64)).sum(axis=1)  # the same cut, not bent
    bent = np.median(_turns_across_parents(points[:, :3], p.indices, p.parents))
    creased = np.median(_turns_across_parents(flat, p.indices, p.parents))
    assert bent < 0.8 * creased, (bent, creased)  # measured 0.69-0.73 of it (neutral, AA, PP, joy, surprise)
    # the outline: edges of the patch shared with no other patch triangle keep no point between their corners
    count: dict[tuple[int, int], int] = {}
    source = layout.source
    for tri in layout.indices[p.triangles]:
        for a, b in ((tri[0], tri[1]), (tri[1], tri[2]), (tri[2], tri[0])):
            key = (min(source[a], source[b]), max(source[a], source[b]))
            count[key] = count.get(key, 0) + 1
    outline = {e for e, k in count.items() if k == 1}
    on_edge = (p.weights > 0).sum(axis=1) == 2
    for k in np.flatnonzero(on_edge):
        ends = tuple(sorted(source[p.corners[k][p.weights[k] > 0]]))
        assert ends not in outline, ends
    assert len(outline) > 20 and LEVEL >= 2


def test_the_operators_give_phong_tessellation(patch):
    """Each point as the formula has it (the flat point moved by SHARE x its corners' share toward the weighted mean of
    its projections onto the corners' tangent planes), on a pose with random normals."""
    face, layout, p = patch
    rng = np.random.default_rng(3)
    data = vertex_data(layout, face.mesh.vertices).astype(np.float64)
    normals = rng.normal(size=(len(data), 3))
    data[:, 3:] = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    got = refined_vertices(p, data, out=np.empty((p.n_points, 6)))
    corner_p, corner_n = data[p.corners, :3], data[p.corners, 3:]
    w = p.weights[:, :, None]
    flat = (w * corner_p).sum(axis=1)
    onto = flat[:, None, :] - ((flat[:, None, :] - corner_p) * corner_n).sum(axis=2, keepdims=True) * corner_n
    share = np.where(np.isin(layout.source, _outline_vertices(layout, p)), 0.0, SHARE)[p.corners]
    alpha = (p.weights * share).sum(axis=1)[:, None]
    want = flat + alpha * ((w * onto).sum(axis=1) - flat)
    assert np.abs(got[:, :3] - want).max() < 1e-9


def _outline_vertices(layout, p) -> np.ndarray:
    """Mesh vertices of the patch that a skin triangle outside it uses too."""
    inside = np.zeros(len(layout.indices), bool)
    inside[p.triangles] = True
    skin = layout.material[layout.indices[:, 0]] == 0
    return np.unique(layout.source[layout.indices[~inside & skin]])
