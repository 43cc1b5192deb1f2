"""What every low-level FAP does to a face, checked against the standard's tables.

For each FAP 3..68 a frame carries that FAP alone, at +V and (unless the FAP is
unidirectional) -V. The moved feature points must do what ``spec/faps.csv``
says, in the face's own FAPU, on both faces (the procedural test head and the
generic CC0 head); every other feature point stays put, except the documented
couplings (the jaw carries the points it weighs, the head carries everything, lip protrusion
carries the outer lip: ``face/data/couplings.csv``; the outer lid centres 3.9/3.10/3.13/3.14,
which no FAP names, ride on the skin around them).
Then: faces of different sizes move in proportion to their FAPU, and the
animation is left/right mirror symmetric. Every deformer that realises the FAPs exactly runs
the same checks (``face`` below: each face under each of them); the block deformer, whose
12-parameter fields realise some FAPs approximately, has its measured errors in test_blocks.py.
"""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.face import motion
from mpeg4fa.face.couplings import PASSIVE_POINTS, SCALP_POINTS, coupled_points
from mpeg4fa.face.fapu import DISTANCES
from mpeg4fa.face.lids import LIDS, lid_corners, lid_drops
from mpeg4fa.face.model import FaceModel
from mpeg4fa.face.rig import CORNER_MARGIN_MM, CORNERS
from mpeg4fa.spec import FAPS, N_FAPS

V = 200.0
TOL = 0.01
LOW_LEVEL = range(3, N_FAPS + 1)
FLIP_X = np.array([-1.0, 1.0, 1.0])
EYE_OF_PUPIL = {"3.5": ("eye_l", "l-eye"), "3.6": ("eye_r", "r-eye")}

# Feature points that are the mirror image of each other (left, right).
FP_PAIRS = (
    ("2.4", "2.5"), ("2.6", "2.7"), ("2.8", "2.9"), ("2.11", "2.12"), ("2.13", "2.14"),
    ("3.1", "3.2"), ("3.3", "3.4"), ("3.5", "3.6"), ("3.7", "3.12"), ("3.9", "3.10"), ("3.11", "3.8"),
    ("3.13", "3.14"), ("4.1", "4.2"), ("4.3", "4.4"), ("4.5", "4.6"), ("5.1", "5.2"), ("5.3", "5.4"),
    ("6.3", "6.4"), ("8.3", "8.4"), ("8.5", "8.6"), ("8.7", "8.8"), ("8.10", "8.9"), ("9.1", "9.2"),
    ("9.5", "9.4"), ("9.7", "9.6"), ("9.13", "9.14"), ("10.1", "10.2"), ("10.3", "10.4"), ("10.5", "10.6"),
    ("10.7", "10.8"), ("10.9", "10.10"), ("11.3", "11.2"),
)
MIDLINE = ("2.1", "2.2", "2.3", "2.10", "6.1", "6.2", "7.1", "8.1", "8.2", "9.3", "9.8", "9.9", "9.10",
           "9.11", "9.12", "9.15", "11.1", "11.4", "11.5", "11.6")


@pytest.fixture
def face(deformed_face):
    """Each face under each exact deformer (tests/conftest.py)."""
    return deformed_face


def _mirror_fap(fap: int) -> tuple[int, float] | None:
    """The FAP that mirrors ``fap`` and the sign its value takes (eye yaw: both positive to the left)."""
    name = FAPS[fap - 1].name
    for a, b in (("_l_", "_r_"), ("_r_", "_l_"), ("_lm", "_rm"), ("_rm", "_lm")):
        if a in name:
            other = next(f for f in FAPS if f.name == name.replace(a, b))
            lateral = {"left", "right"}
            same_x = FAPS[fap - 1].direction in lateral and FAPS[fap - 1].direction == other.direction
            return other.number, (-1.0 if same_x else 1.0)
    return None


MIRROR_FAPS = sorted({(min(f, _mirror_fap(f)[0]), max(f, _mirror_fap(f)[0]), _mirror_fap(f)[1])
                      for f in LOW_LEVEL if _mirror_fap(f)})
LEFT_ONLY = [f for f in LOW_LEVEL if "_l_" in FAPS[f - 1].name or "_lm" in FAPS[f - 1].name]


def _signs(fap: int) -> tuple[float, ...]:
    return (1.0,) if FAPS[fap - 1].unidirectional else (1.0, -1.0)


def _frame(fap: int, value: float) -> np.ndarray:
    values = np.zeros(N_FAPS)
    values[fap - 1] = value
    return values


def _yaw(v: np.ndarray) -> float:
    return float(np.arctan2(v[0], v[2]))


def _pitch_down(v: np.ndarray) -> float:
    return float(np.arctan2(-v[1], np.hypot(v[0], v[2])))


CORNER_GIVE = 0.3
"""The most an eye corner may move, as a share of its lids' travel (measured up to 0.27, on the child head calibrated
from the generic one)."""


def _corners_give(mesh, rest: np.ndarray, posed: np.ndarray, corners: tuple[str, str], centre: np.ndarray,
                  travel: float, coupled: set[int]) -> list[tuple[str, float]]:
    """The eye's corners give a little with its lids (face/lid_folds.py): each keeps its x, turns on its arc about the
    eye centre's x axis and moves at most CORNER_GIVE of the lids' travel; they join ``coupled``."""
    errors = []
    for label in corners:
        if label not in mesh.fp_labels or not travel:
            continue
        i = mesh.fp_index(label)
        moved = posed[i] - rest[i]
        arc = abs(np.linalg.norm((posed[i] - centre)[1:]) - np.linalg.norm((rest[i] - centre)[1:]))
        errors += [(f"{label} keeps its x", abs(float(moved[0])) / travel), (f"{label} on its arc", float(arc) / travel),
                   (f"{label} gives at most {CORNER_GIVE}", max(0.0, float(np.linalg.norm(moved)) / travel - CORNER_GIVE))]
        coupled.add(i)
    return errors


def fap_errors(face: FaceModel, fap: int, value: float) -> list[tuple[str, float]]:
    """Relative errors of one FAP at one value: (what, error); qualitative faults raise."""
    mesh, fapu, rig = face.mesh, face.fapu, face.rig
    record = FAPS[fap - 1]
    kind = motion.kind(fap)
    pose = face.deform(_frame(fap, value))
    rest = mesh.feature_points()
    moved = pose.feature_points - rest
    index = {label: i for i, label in enumerate(mesh.fp_labels)}
    targets = [index[label] for label in record.feature_point]
    errors: list[tuple[str, float]] = []
    coupled = set(targets)

    if kind == "translate" or fap in (14, 15):
        amount = value * fapu.unit(record.fapu)
        direction = motion.direction(fap)
        for i in targets:
            along = float(moved[i] @ direction)
            errors.append((f"{mesh.fp_labels[i]} along {record.direction}", abs(along - amount) / abs(amount)))
            drift = float(np.linalg.norm(moved[i] - along * direction))
            errors.append((f"{mesh.fp_labels[i]} drift", drift / abs(amount)))
    elif fap == 3:
        amount = value * fapu.unit("MNS")
        errors.append(("2.1 drop", abs(-moved[index["2.1"]][1] - amount) / amount))
    elif kind == "lid":
        amount = value * fapu.unit("IRISD")
        i = targets[0]
        vertical = float(moved[i] @ motion.direction(fap))
        errors.append((f"{mesh.fp_labels[i]} vertical", abs(vertical - amount) / abs(amount)))
        # the lid slides on an arc about the eyeball's horizontal axis
        centre = mesh.joint("l-eye" if fap in (19, 21) else "r-eye")
        before = np.linalg.norm((rest[i] - centre)[1:])
        after = np.linalg.norm((pose.feature_points[i] - centre)[1:])
        errors.append((f"{mesh.fp_labels[i]} arc radius", abs(after - before) / abs(amount)))
        errors += _corners_give(mesh, rest, pose.feature_points, lid_corners(fap), centre, abs(amount), coupled)
    elif fap in motion.EYE_ROTATION:
        eye, axis = motion.EYE_ROTATION[fap]
        label = record.feature_point[0]
        centre = mesh.joint(EYE_OF_PUPIL[label][1])
        b = rest[index[label]] - centre
        a = pose.feature_points[index[label]] - centre
        angle = (_yaw(a) - _yaw(b)) if axis == "yaw" else (_pitch_down(a) - _pitch_down(b))
        amount = value * fapu.unit("AU")
        errors.append((f"{label} {axis} angle", abs(angle - amount) / abs(amount)))
        errors.append((f"{label} stays on the eyeball", abs(np.linalg.norm(a) - np.linalg.norm(b)) / np.linalg.norm(b)))
        assert np.abs(pose.part(eye)[0] - pose.feature_points[index[label]]).max() == 0
        if axis == "pitch":  # the eye's lids ride on its pitch (face/lids.py): their points drop by lid_drops
            drops = lid_drops(rig.lids, rig.rest, _frame(fap, value), fapu.unit("IRISD"))
            for lid, (lid_eye, _, point, *_) in LIDS.items():
                if lid_eye == eye:
                    i = index[point]
                    errors.append((f"{point} rides on the pitch", abs(-moved[i][1] - drops[lid]) / abs(drops[lid])))
                    coupled.add(i)
            travel = sum(abs(drops[lid]) for lid, (lid_eye, *_) in LIDS.items() if lid_eye == eye)
            corners = next(lid_corners(lid) for lid, (lid_eye, *_) in LIDS.items() if lid_eye == eye)
            errors += _corners_give(mesh, rest, pose.feature_points, corners, centre, travel, coupled)
    elif fap in motion.EYE_THRUST:
        label = record.feature_point[0]
        amount = value * fapu.unit("ES")
        errors.append((f"{label} forward", float(np.linalg.norm(moved[index[label]] - [0, 0, amount])) / abs(amount)))
    elif kind == "pupil":
        eye = motion.PUPIL[fap]
        neutral = face.neutral().pupil_diameter[eye]
        amount = value * fapu.unit("IRISD")
        errors.append((f"{eye} pupil diameter", abs(pose.pupil_diameter[eye] - neutral - amount) / abs(amount)))
        other = "eye_r" if eye == "eye_l" else "eye_l"
        assert pose.pupil_diameter[other] == neutral
        assert np.array_equal(pose.vertices, mesh.vertices), "a pupil FAP moved vertices"
    elif kind == "tongue_roll":
        amount = value * fapu.unit("AU")
        left, right = index["6.3"], index["6.4"]
        assert moved[left][1] > 0 and moved[right][1] > 0, "tongue roll must lift both borders"
        asymmetry = float(np.abs(moved[left] - moved[right] * FLIP_X).max())
        errors.append(("6.3/6.4 symmetric", asymmetry / np.abs(moved[left]).max()))
        for i in (left, right):
            p0, p1 = rest[i], pose.feature_points[i]
            angle = np.arctan2(p1[1] - p0[1], abs(p1[0]))  # about the midline axis at the border's height
            errors.append((f"{mesh.fp_labels[i]} roll angle", abs(angle - amount) / amount))
    elif kind == "head":
        axis = motion.HEAD[fap]
        angles = {"pitch": 0.0, "yaw": 0.0, "roll": 0.0}
        angles[axis] = value * fapu.unit("AU")
        rotation = motion.head_rotation(angles["pitch"], angles["yaw"], angles["roll"])
        centre = rest[index["7.1"]]
        expected = (rest - centre) @ rotation.T + centre - rest
        scale = np.linalg.norm(expected, axis=1).max()
        errors.append(("head rotation about 7.1", float(np.linalg.norm(moved - expected, axis=1).max()) / scale))
        nose, top = moved[index["9.3"]], moved[index["11.4"]]
        sign = np.sign(value)
        if axis == "pitch":
            assert sign * nose[1] < 0, "head pitch +: the nose goes down"
        elif axis == "yaw":
            assert sign * nose[0] > 0, "head yaw +: the nose turns to the face's left (+x)"
        else:
            assert sign * top[0] < 0, "head roll +: the top of the head tilts to the face's right (-x)"
        coupled = set(range(len(rest)))
    else:  # pragma: no cover - every FAP has a kind
        raise AssertionError(f"FAP {fap}: kind {kind}")

    for label, fraction in coupled_points(fap).items():  # documented couplings (face/data/couplings.csv)
        i = index[label]
        amount = fraction * value * fapu.unit(record.fapu)
        errors.append((f"{label} coupled", float(np.linalg.norm(moved[i] - amount * motion.direction(fap))) / abs(value * fapu.unit(record.fapu))))
        coupled.add(i)
    coupled |= {index[label] for label in PASSIVE_POINTS if label in index}  # they ride on the skin
    coupled |= {index[label] for label in SCALP_POINTS if label in index}  # the scalp slides with a raised forehead
    for inner, outer in CORNERS:  # a lip corner sent across the other one pushes it ahead
        for mine, other, sign in ((inner, outer, 1.0), (outer, inner, -1.0)):
            if mine in record.feature_point and other in index:
                i, o = index[mine], index[other]
                side = np.sign(rest[index[outer], 0] - rest[index[inner], 0]) * sign  # from mine toward other
                want = side * max(side * rest[o, 0], side * pose.feature_points[i, 0] + CORNER_MARGIN_MM)
                expected = np.array([want - rest[o, 0], 0.0, 0.0])
                errors.append((f"{other} kept across {mine}",
                               float(np.linalg.norm(moved[o] - expected)) / abs(value * fapu.unit(record.fapu))))
                coupled.add(o)
    if fap in motion.JAW:
        jaw_vertices = set(rig.jaw_rows[0].tolist())
        coupled |= {i for i, v in enumerate(mesh.fp_vertex) if int(v) in jaw_vertices}
    unit = fapu.unit(record.fapu) if record.fapu != "AU" else min(fapu.unit(s) for s in DISTANCES)
    others = [i for i in range(len(rest)) if i not in coupled]
    if others:
        drift = np.linalg.norm(moved[others], axis=1)
        worst = int(np.argmax(drift))
        errors.append((f"others ({mesh.fp_labels[others[worst]]}) / FAPU", float(drift[worst]) / unit))
    return errors


CASES = [(fap, sign) for fap in LOW_LEVEL for sign in _signs(fap)]


@pytest.mark.parametrize("fap,sign", CASES, ids=[f"{f}{'+' if s > 0 else '-'}" for f, s in CASES])
def test_fap_moves_its_feature_points(face, fap, sign):
    errors = fap_errors(face, fap, sign * V)
    bad = [(what, err) for what, err in errors if not err < TOL]
    assert not bad, f"FAP {fap} ({FAPS[fap - 1].name}) = {sign * V:g}: {bad}"


def test_worst_relative_error(face, capsys):
    worst = (0.0, "")
    for fap, sign in CASES:
        for what, err in fap_errors(face, fap, sign * V):
            if err >= worst[0]:
                worst = (err, f"FAP {fap} {sign * V:+g}: {what}")
    with capsys.disabled():
        print(f"\n[{face.mesh.source}, {face.deformer}] worst relative FAP error {worst[0]:.3e} ({worst[1]})")
    assert worst[0] < TOL


# -- faces of different sizes -----------------------------------------------------------------


@pytest.fixture(scope="module")
def resized_faces(procedural_face):
    """The procedural face scaled by 1.3, and stretched unevenly (x 1.2, y 0.9, z 1.1)."""
    v = procedural_face.mesh.vertices
    return {
        "uniform 1.3": FaceModel(procedural_face.mesh.with_vertices(v * 1.3)),
        "uneven": FaceModel(procedural_face.mesh.with_vertices(v * np.array([1.2, 0.9, 1.1]))),
    }


SIZE_FAPS = [f for f in LOW_LEVEL if motion.kind(f) in ("translate", "lid", "jaw") or f in motion.EYE_THRUST]


@pytest.mark.parametrize("which", ["uniform 1.3", "uneven"])
def test_displacement_scales_with_fapu(procedural_face, resized_faces, which):
    small, big = procedural_face, resized_faces[which]
    if which == "uniform 1.3":
        for symbol in DISTANCES:
            assert big.fapu.unit(symbol) / small.fapu.unit(symbol) == pytest.approx(1.3, rel=1e-12)
    for fap in SIZE_FAPS:
        record = FAPS[fap - 1]
        label = record.feature_point[0]
        i = small.mesh.fp_index(label)
        d_small = small.deform(_frame(fap, V)).feature_points[i] - small.mesh.feature_points()[i]
        d_big = big.deform(_frame(fap, V)).feature_points[i] - big.mesh.feature_points()[i]
        axis = motion.direction(fap)
        ratio = (d_big @ axis) / (d_small @ axis)
        expected = big.fapu.unit(record.fapu) / small.fapu.unit(record.fapu)
        assert ratio == pytest.approx(expected, rel=1e-9), f"FAP {fap} ({record.name}) on {label}"


# -- left / right symmetry ----------------------------------------------------------------------


@pytest.mark.parametrize("which", ["procedural", "generic"])
def test_head_is_mirror_symmetric(request, which):
    mesh = request.getfixturevalue(f"{which}_face").mesh
    v = mesh.vertices
    assert np.array_equal(mesh.mirror[mesh.mirror], np.arange(len(v)))
    assert np.abs(v[mesh.mirror] * FLIP_X - v).max() <= 1e-9
    fp = {label: mesh.fp(label) for label in mesh.fp_labels}
    paired = set()
    for left, right in FP_PAIRS:
        assert fp[left][0] > 0 > fp[right][0], (left, right)
        assert np.abs(fp[left] * FLIP_X - fp[right]).max() <= 1e-9, (left, right)
        assert mesh.mirror[mesh.fp_vertex[mesh.fp_index(left)]] == mesh.fp_vertex[mesh.fp_index(right)]
        paired |= {left, right}
    for label in MIDLINE:
        assert abs(fp[label][0]) <= 1e-9, label
    assert paired | set(MIDLINE) == set(mesh.fp_labels)


def test_procedural_triangulation_is_mirrored(procedural_head):
    """Edges map to edges, so that edge-ring regions (and so the rig) are symmetric too.

    (The generic head's are not quite: MakeHuman's mirrored quads are split along
    unmirrored diagonals.)"""
    mesh = procedural_head
    tris = mesh.all_triangles().astype(np.int64)
    edges = np.sort(np.concatenate([tris[:, [0, 1]], tris[:, [1, 2]], tris[:, [2, 0]]]), axis=1)
    edges = np.unique(edges, axis=0)
    mirrored = np.unique(np.sort(mesh.mirror[edges], axis=1), axis=0)
    assert np.array_equal(mirrored, edges)


@pytest.mark.parametrize("left,right,sign", MIRROR_FAPS, ids=[f"{a}-{b}" for a, b, _ in MIRROR_FAPS])
def test_mirrored_faps_give_mirrored_poses(face, left, right, sign):
    mesh = face.mesh
    for value in (V, -V) if not FAPS[left - 1].unidirectional else (V,):
        a = face.deform(_frame(left, value)).vertices
        b = face.deform(_frame(right, sign * value)).vertices
        assert np.abs(b[mesh.mirror] * FLIP_X - a).max() <= 1e-6, f"FAP {left} vs FAP {right} at {value:g}"


UNPAIRED = [f for f in LOW_LEVEL if _mirror_fap(f) is None and motion.kind(f) != "jaw"]
ANTISYMMETRIC = {f for f in LOW_LEVEL if FAPS[f - 1].direction in ("left", "right")} | {49, 50}


@pytest.mark.parametrize("fap", UNPAIRED)
def test_midline_faps_give_symmetric_poses(face, fap):
    """A FAP without a mirror partner poses a symmetric face; one that moves sideways (or turns or
    tilts the head) gives at -v the mirror image of its pose at +v."""
    mesh = face.mesh
    a = face.deform(_frame(fap, V)).vertices
    if fap in ANTISYMMETRIC:
        b = face.deform(_frame(fap, -V)).vertices
    else:
        b = a
    assert np.abs(b[mesh.mirror] * FLIP_X - a).max() <= 1e-6


@pytest.mark.parametrize("which", [
    "procedural", "generic"])
@pytest.mark.parametrize("fap", sorted(motion.JAW))
def test_jaw_pose_is_symmetric(request, which, fap):
    face = request.getfixturevalue(f"{which}_face")
    mesh = face.mesh
    a = face.deform(_frame(fap, V)).vertices
    b = face.deform(_frame(fap, -V)).vertices if fap in ANTISYMMETRIC else a
    assert np.abs(b[mesh.mirror] * FLIP_X - a).max() <= 1e-6


@pytest.mark.parametrize("fap", LEFT_ONLY)
def test_left_faps_move_only_the_left_side(face, fap):
    """A left FAP moves the face's left side (x > 0); the regions of points beside the midline
    (inner brows, mid lips) may reach a little across it, but never as far as the right eye's
    centre line (x = -ES0/2), and more than 5 % of the motion stays within ES0/4 of the midline."""
    mesh = face.mesh
    x = mesh.vertices[:, 0]
    for value in _signs(fap):
        d = np.linalg.norm(face.deform(_frame(fap, value * V)).vertices - mesh.vertices, axis=1)
        if motion.kind(fap) == "pupil":
            assert d.max() == 0
            continue
        assert d.max() > 0
        assert x[d > 0].min() > -face.fapu.ES0 / 2, f"FAP {fap} moved a vertex at x = {x[d > 0].min():.1f} mm"
        strong = d > 0.05 * d.max()
        assert x[strong].min() > -face.fapu.ES0 / 4, f"FAP {fap} moved x = {x[strong].min():.1f} mm by > 5 %"
        assert (x[d > 0.5 * d.max()] > 0).all()
