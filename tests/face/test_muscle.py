"""The muscle deformer: Waters' linear muscles shape the skin, the FAPU semantics stay exact."""
import numpy as np
import pytest

from conftest import face_under

from mpeg4fa.face.couplings import PASSIVE_POINTS
from mpeg4fa.face.deformers.muscle import contractions, reach_table
from mpeg4fa.face.muscles import load_specs, waters_factor
from mpeg4fa.face.quality import measure, skin_graph
from mpeg4fa.spec import EXPRESSIONS, FAPS, N_FAPS
from mpeg4fa.spec.profiles import EXPRESSION_PROFILES
from test_fap_semantics import TOL, fap_errors

FLIP_X = np.array([-1.0, 1.0, 1.0])
V1 = np.zeros(3)
V2 = np.array([0.0, -10.0, 0.0])  # the muscle axis points down
OMEGA, RS, RF = np.radians(30.0), 10.0, 15.0


def _frame(values):
    v = np.zeros(N_FAPS)
    for fap, value in values.items():
        v[fap - 1] = value
    return v


@pytest.fixture(scope="session")
def muscle_face(request):
    return face_under(request, "generic", "muscle")  # one per session (tests/conftest.py)


@pytest.fixture(scope="session")
def procedural_muscle_face(request):
    return face_under(request, "procedural", "muscle")  # one per session (tests/conftest.py)


def _at(distance, angle_deg):
    """A point at ``distance`` from V1, ``angle_deg`` off the axis (in the x-y plane)."""
    a = np.radians(angle_deg)
    return np.array([[distance * np.sin(a), -distance * np.cos(a), 0.0]])


# -- the Waters displacement on synthetic points ------------------------------------------------


def test_zero_outside_the_zone():
    for p in (_at(12, 31), _at(12, 90), _at(12, 170), _at(15.5, 0), _at(40, 0), V1[None]):
        factor, _ = waters_factor(p, V1, V2, OMEGA, RS, RF)
        assert factor[0] == 0.0, p
    factor, _ = waters_factor(_at(12, 29), V1, V2, OMEGA, RS, RF)
    assert factor[0] > 0


def test_moves_toward_the_attachment():
    rng = np.random.default_rng(1)
    p = rng.normal(size=(200, 3)) * 6 + V2
    factor, direction = waters_factor(p, V1, V2, OMEGA, RS, RF)
    inside = factor > 0
    assert inside.sum() > 20
    towards = (V1 - p[inside]) / np.linalg.norm(V1 - p[inside], axis=1)[:, None]
    assert np.allclose(direction[inside], towards)


def test_radial_rises_to_the_insertion_then_decays():
    d = np.linspace(0.1, RF + 1, 400)
    factor, _ = waters_factor(np.stack([np.zeros_like(d), -d, np.zeros_like(d)], axis=1), V1, V2, OMEGA, RS, RF)
    rising, falling = factor[d < RS], factor[d >= RS]
    assert np.all(np.diff(rising) > 0) and np.all(np.diff(falling) <= 0)
    assert factor[np.argmin(abs(d - RS))] == pytest.approx(1.0, abs=1e-3)
    assert np.allclose(rising, np.cos((1 - d[d < RS] / RS) * np.pi / 2))
    inner = (d >= RS) & (d <= RF)
    assert np.allclose(factor[inner], np.cos((d[inner] - RS) / (RF - RS) * np.pi / 2))
    assert np.all(factor[d > RF] == 0)


def test_angular_cosine_falloff():
    angles = np.linspace(0, 29.9, 50)
    factor = np.array([waters_factor(_at(RS, a), V1, V2, OMEGA, RS, RF)[0][0] for a in angles])
    assert np.allclose(factor, np.cos(np.radians(angles) / OMEGA * np.pi / 2))


def test_muscle_table_names_the_eight_muscles():
    names = {s.muscle for s in load_specs()}
    for muscle in ("frontalis", "corrugator", "levator_palpebrae", "levator_labii_superioris", "zygomatic_major",
                   "risorius", "depressor_labii_inferioris", "mentalis"):
        assert any(n.startswith(muscle) for n in names), muscle
    assert all(s.side == "pair" for s in load_specs())


# -- each muscle in its anatomical sense ----------------------------------------------------------

# muscle -> (feature point its insertion moves, expected sign per axis x, y, z on the left side; 0: not checked)
SENSE = {
    "frontalis_medial": ("4.1", (0, 1, 0)),
    "frontalis_middle": ("4.3", (0, 1, 0)),
    "frontalis_lateral": ("4.5", (0, 1, 0)),
    "corrugator": ("4.3", (-1, -1, 0)),  # down and in
    "levator_labii_superioris": ("8.5", (0, 1, -1)),
    "zygomatic_major": ("8.3", (1, 1, -1)),  # up, out and back
    "risorius": ("8.3", (1, 0, -1)),
    "depressor_labii_inferioris": ("8.7", (0, -1, 0)),
    "mentalis": ("2.10", (0, 1, 0)),
}


@pytest.mark.parametrize("muscle", sorted(SENSE))
def test_each_muscle_moves_skin_its_anatomical_way(muscle_face, muscle):
    mesh = muscle_face.mesh
    mrig = muscle_face.posing.muscle_rig
    label, signs = SENSE[muscle]
    skin = mesh.part("skin")
    mirror = {a: b for a, b in zip(mesh.fp_labels, [mesh.fp_labels[list(mesh.fp_vertex).index(mesh.mirror[v])]
                                                     for v in mesh.fp_vertex])}
    for side, flip in (("l", np.ones(3)), ("r", FLIP_X)):
        j = mrig.names.index(f"{muscle}_{side}")
        point = label if side == "l" else mirror[label]
        d = mrig.basis[mesh.fp_vertex[mesh.fp_index(point)] - skin.start, :, j] * flip
        assert np.linalg.norm(d) > 0.3, f"{muscle}_{side} barely moves {point}"
        for axis, s in enumerate(signs):
            if s:
                assert s * d[axis] > 0.05 * np.linalg.norm(d), f"{muscle}_{side} moves {point} by {d}"


def test_levator_palpebrae_follows_the_upper_lid(muscle_face):
    rig, mrig = muscle_face.rig, muscle_face.posing.muscle_rig
    k = contractions(rig, mrig, _frame({19: -200, 20: -200}))  # eyes wide: the levators contract
    assert k[mrig.names.index("levator_palpebrae_l")] > 0 and k[mrig.names.index("levator_palpebrae_r")] > 0
    k = contractions(rig, mrig, _frame({19: 300}))  # closing relaxes it below its tone
    assert k[mrig.names.index("levator_palpebrae_l")] < 0 and k[mrig.names.index("levator_palpebrae_r")] == 0


def test_expressions_contract_their_muscles(muscle_face):
    rig, mrig = muscle_face.rig, muscle_face.posing.muscle_rig

    def k(expression, muscle):
        return contractions(rig, mrig, EXPRESSION_PROFILES[expression].astype(float))[mrig.names.index(muscle)]
    assert k("joy", "zygomatic_major_l") > 1.0
    assert k("surprise", "frontalis_medial_l") > 5.0 and k("surprise", "frontalis_lateral_r") > 5.0
    assert k("anger", "corrugator_l") > 0.5
    assert k("disgust", "levator_labii_superioris_r") > 0.3
    for e in EXPRESSIONS:
        assert (contractions(rig, mrig, EXPRESSION_PROFILES[e.name].astype(float))[mrig.solved] >= 0).all()


# -- the FAPU semantics --------------------------------------------------------------------------

REPRESENTATIVE = [(3, 1), (4, -1), (5, 1), (6, 1), (12, 1), (16, 1), (18, 1), (19, 1), (31, 1), (31, -1),
                  (33, 1), (37, 1), (41, 1), (48, 1), (53, 1), (55, -1), (57, -1), (59, 1), (61, 1), (63, 1), (65, 1)]


@pytest.mark.parametrize("fap,sign", REPRESENTATIVE, ids=[f"{f}{'+' if s > 0 else '-'}" for f, s in REPRESENTATIVE])
def test_fap_moves_its_feature_points(muscle_face, procedural_muscle_face, fap, sign):
    for face in (muscle_face, procedural_muscle_face):
        errors = fap_errors(face, fap, sign * 200.0)
        bad = [(what, err) for what, err in errors if not err < TOL]
        assert not bad, f"[{face.mesh.source}] FAP {fap} ({FAPS[fap - 1].name}) = {sign * 200:g}: {bad}"


@pytest.mark.parametrize("expression", [e.name for e in EXPRESSIONS if e.number])
def test_feature_points_match_the_feature_point_deformer(generic_face, muscle_face, expression):
    v = EXPRESSION_PROFILES[expression].astype(float)
    a = muscle_face.deform(v)
    b = generic_face.deform(v)
    # the passive points ride on the skin (tests/face/test_fap_semantics.py)
    fixed = [i for i, label in enumerate(generic_face.mesh.fp_labels) if label not in PASSIVE_POINTS]
    assert np.abs(a.feature_points[fixed] - b.feature_points[fixed]).max() <= 1e-9 * generic_face.mesh.height()
    assert np.abs(a.part("skin") - b.part("skin")).max() > 0.2  # the muscles shape the skin between the points


def test_reach_table_reports_every_skin_fap(muscle_face):
    table = reach_table(muscle_face.mesh, muscle_face.rig, muscle_face.posing.muscle_rig)
    faps = {r.fap for r in table}
    assert {31, 33, 35, 59, 53, 18}.issubset(faps) and 43 not in faps  # the tongue is not skin
    assert all(0 <= r.fit <= 1.0 + 1e-9 for r in table)  # NNLS never does worse than no muscle at all
    raised = {r.fap: r.own for r in table if r.value > 0}
    assert raised[59] < 0.9 and raised[31] < 0.6  # the corner and brow raisers do most of the work
    along = {r.fap: r.along for r in table if r.value > 0}
    assert along[31] > 0.8 and along[59] > 0.5 and along[37] > 0.5  # frontalis, zygomatic, corrugator
    lowered = {r.fap: r.own for r in table if r.value < 0}
    assert lowered[31] > 0.9 and lowered[59] > 0.99  # no muscle of the set pulls these straight down


# -- quality and symmetry ------------------------------------------------------------------------


def test_no_more_folds_than_the_feature_point_deformer(generic_face, muscle_face):
    graph = skin_graph(generic_face.mesh)
    for e in EXPRESSIONS:
        v = EXPRESSION_PROFILES[e.name].astype(float)
        mine = measure(generic_face.mesh, muscle_face.deform(v).vertices, graph)
        theirs = measure(generic_face.mesh, generic_face.deform(v).vertices, graph)
        assert mine.folded <= theirs.folded, f"{e.name}: {mine.describe()} vs {theirs.describe()}"
        assert mine.max_strain <= 1.5 * theirs.max_strain + 0.1, f"{e.name}: {mine.describe()} vs {theirs.describe()}"


@pytest.mark.parametrize("expression", [e.name for e in EXPRESSIONS if e.number])
def test_expressions_are_mirror_symmetric(muscle_face, expression):
    mesh = muscle_face.mesh
    v = muscle_face.deform(EXPRESSION_PROFILES[expression].astype(float)).vertices
    assert np.abs(v[mesh.mirror] * FLIP_X - v).max() <= 1e-6


@pytest.mark.parametrize("left,right", [(59, 60), (31, 32), (55, 56), (6, 7), (19, 20)])
def test_mirrored_faps_give_mirrored_poses(muscle_face, left, right):
    mesh = muscle_face.mesh
    for value in (200.0, -200.0):
        sign = 1.0
        a = muscle_face.deform(_frame({left: value})).vertices
        b = muscle_face.deform(_frame({right: sign * value})).vertices
        assert np.abs(b[mesh.mirror] * FLIP_X - a).max() <= 1e-6


def test_muscles_follow_a_resized_face(procedural_face, procedural_muscle_face):
    """Attachments and insertions are feature points plus offsets in ES0: an unevenly stretched
    face gets stretched muscles, and its feature points still move as the FAPU say."""
    from mpeg4fa.face.model import FaceModel

    mesh = procedural_face.mesh
    stretched = FaceModel(mesh.with_vertices(mesh.vertices * np.array([1.2, 0.9, 1.1])), deformer="muscle")
    small = procedural_muscle_face.posing.muscle_rig.muscles
    big = stretched.posing.muscle_rig.muscles
    for a, b in zip(small, big):
        assert b.name == a.name
        assert abs(b.insertion[0]) == pytest.approx(abs(a.insertion[0]) * 1.2, rel=0.2)
    v = EXPRESSION_PROFILES["joy"].astype(float)
    plain = stretched.with_deformer("fap").deform(v).feature_points
    fixed = [i for i, label in enumerate(mesh.fp_labels) if label not in PASSIVE_POINTS]
    assert np.abs(stretched.deform(v).feature_points[fixed] - plain[fixed]).max() <= 1e-9 * mesh.height() * 1.2
