"""Creases and folds at the extremes (issue 29 item 3): the poses, and what counts as a fold.

A crease shows when skin triangles fold over (a dark line across the forehead when the brows
go up at twice their usual extreme, under the eyes when the cheeks lift to 600) or when the
neck, turning with the head, twists into itself. Per pose this module gives:

* **folded**: skin triangles whose normal turned by more than 90 degrees from rest
  (:func:`.quality.folded_triangles`; those inside the lip and lid loops are not counted);
* **flipped**: pairs of neighbouring skin triangles that faced the same side at rest
  (normals less than :data:`SAME_SIDE_DEGREES` apart) and face against each other posed
  (more than 90 degrees): a fold line (a pair already at a sharp edge at rest, like the
  neck's sides where they flare into the shoulders at the cut, is no new fold);
* **strain / floor**: the worst edge strain (:func:`.quality.measure`) over the least any
  interpolation of the pose could have. The floor is :func:`.quality.strain_floor` over the
  skin feature points plus the neck's cut rim, held by the shoulders: a head turned 40
  degrees carries its chin some 80 mm round while the rim stays, and the neck between must
  take that.

A pose passes when nothing folds or flips and its strain is within :data:`FLOOR_FACTOR` times
the floor (or under :data:`STRAIN_LIMIT`, a strain no one sees).
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.sparse.csgraph import dijkstra

from mpeg4fa.face import motion
from mpeg4fa.face.model import FaceModel
from mpeg4fa.face.quality import SkinGraph, folded_triangles, measure, skin_graph, used_magnitudes
from mpeg4fa.face.regions import triangle_pairs, unit_normals
from mpeg4fa.spec import ANGLE_UNIT, FAPS, I_MAX_DEFAULT, N_FAPS, QUANT_STEP

FLOOR_FACTOR = 2.0
"""Worst strain allowed, as a multiple of the pose's floor (the issue's criterion)."""
STRAIN_LIMIT = 0.5
"""A strain this small passes whatever the floor (the smooth-skin tests' limit)."""
TURN_DEGREES = 40.0
"""The head turns the issue asks about, with the jaw open."""
BROWS_FACTOR = 2.0
"""The brows at twice their usual extreme (the largest value streams and profiles use)."""
CHEEK_LIFT = 600.0
"""FAPs 41/42 at this value (ENS): the cheeks lifted as far as the issue asks."""
SAME_SIDE_DEGREES = 60.0
"""Neighbouring triangles this close in direction at rest count as one smooth sheet."""
RIM_BAND_MM = 0.5
"""Skin vertices within this of the neck's lowest point form its cut rim (held by the shoulders)."""


def _frame(**faps: float) -> np.ndarray:
    v = np.zeros(N_FAPS)
    for key, value in faps.items():
        v[int(key[1:]) - 1] = value
    return v


def _values(mapping: dict[int, float]) -> np.ndarray:
    v = np.zeros(N_FAPS)
    for fap, value in mapping.items():
        v[fap - 1] = value
    return v


def turn(degrees: float) -> float:
    """A head rotation of ``degrees`` in FAP units (AU)."""
    return float(np.radians(degrees) / ANGLE_UNIT)


def crease_poses(face: FaceModel | None = None) -> dict[str, np.ndarray]:
    """The named poses of the issue: brows x2 (up and down), cheeks at 600, the head turned
    40 degrees each way about each axis with the jaw open, and anger with a 37 degree turn."""
    from mpeg4fa.spec.profiles import EXPRESSION_PROFILES

    used = used_magnitudes()
    brows = range(31, 37)
    jaw = used[3][0]  # the widest a viseme opens the jaw
    poses = {
        "brows x2 up": _values({f: BROWS_FACTOR * used[f][0] for f in brows}),
        "brows x2 down": _values({f: -BROWS_FACTOR * used[f][1] for f in brows}),
        "brows 400": _values({f: 400.0 for f in brows}),
        "squeeze x2": _values({f: BROWS_FACTOR * used[f][0] for f in (37, 38)}),
        "cheeks 600": _values({41: CHEEK_LIFT, 42: CHEEK_LIFT}),
        "cheek l 600": _values({41: CHEEK_LIFT}),
    }
    for name, fap in (("yaw", 49), ("pitch", 48), ("roll", 50)):
        for sign in (1, -1):
            poses[f"{name} {sign * TURN_DEGREES:+.0f} jaw open"] = _values({fap: sign * turn(TURN_DEGREES), 3: jaw})
    poses["yaw 40 pitch 20 jaw open"] = _values({49: turn(TURN_DEGREES), 48: turn(20.0), 3: jaw})
    anger = np.asarray(EXPRESSION_PROFILES["anger"], float).copy()
    anger[:2] = 0
    anger[48] = turn(37.0)
    poses["anger yaw 37"] = anger
    return poses


def full_range_faps() -> list[int]:
    """The FAPs that move skin (translations, the jaw, the lids): those a full range can crease."""
    return [f for f in range(3, N_FAPS + 1) if motion.kind(f) in ("translate", "jaw", "lid")
            and FAPS[f - 1].group != 6]  # group 6 is the tongue


def full_range_value(fap: int) -> float:
    """The largest value a stream carries for ``fap`` with the default I range (fap_quant 1)."""
    return float(I_MAX_DEFAULT[fap - 1] * QUANT_STEP[fap - 1])


def full_range_poses() -> dict[str, np.ndarray]:
    """Every skin FAP alone at +- its full I range (+ only for the unidirectional ones)."""
    poses = {}
    for fap in full_range_faps():
        top = full_range_value(fap)
        for sign in ((1,) if FAPS[fap - 1].unidirectional else (1, -1)):
            poses[f"FAP {fap} {sign * top:+g}"] = _values({fap: sign * top})
    return poses


@dataclass(frozen=True)
class Crease:
    """What one pose does to the skin (see the module docstring)."""

    folded: int
    flipped: int
    strain: float
    floor: float
    near: str

    @property
    def ratio(self) -> float:
        return self.strain / self.floor if self.floor > 0 else (0.0 if self.strain <= STRAIN_LIMIT else np.inf)

    def ok(self) -> bool:
        return self.folded == 0 and self.flipped == 0 and (self.strain <= STRAIN_LIMIT or self.ratio <= FLOOR_FACTOR)

    def as_dict(self) -> dict:
        return {**asdict(self), "ratio": float(self.ratio), "ok": self.ok()}


def neck_rim(mesh) -> np.ndarray:
    """Skin vertices on the neck's cut (its lowest band): the shoulders hold them."""
    skin = mesh.part("skin")
    y = mesh.vertices[skin, 1]
    return np.flatnonzero(y < y.min() + RIM_BAND_MM) + skin.start


def flipped_pairs(rest: np.ndarray, posed: np.ndarray, triangles: np.ndarray) -> int:
    """Neighbouring triangles that faced the same side at rest and face against each other posed."""
    a, b = triangle_pairs(triangles)
    n0, n1 = unit_normals(rest, triangles), unit_normals(posed, triangles)
    before = np.einsum("ij,ij->i", n0[a], n0[b])
    after = np.einsum("ij,ij->i", n1[a], n1[b])
    return int(((before > np.cos(np.radians(SAME_SIDE_DEGREES))) & (after < 0)).sum())


def held_floor(mesh, posed: np.ndarray, graph: SkinGraph) -> tuple[float, str]:
    """:func:`.quality.strain_floor` with the neck's rim among the points (held where it is)."""
    skin = mesh.part("skin")
    fp_idx = [i for i, v in enumerate(mesh.fp_vertex) if skin.start <= v < skin.stop]
    fp_verts, first = np.unique(mesh.fp_vertex[fp_idx], return_index=True)
    labels = [mesh.fp_labels[fp_idx[k]] for k in first]
    rim = neck_rim(mesh)
    verts = np.concatenate([fp_verts, rim])
    names = labels + ["neck rim"] * len(rim)
    geo_graph = graph.geodesic(mesh.vertices)
    geo = dijkstra(geo_graph, indices=fp_verts)[:, verts]
    d = np.asarray(posed)[verts] - mesh.vertices[verts]
    diff = np.linalg.norm(d[:len(fp_verts), None] - d[None], axis=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.where((geo > 0) & np.isfinite(geo), diff / geo, 0.0)
    i, j = np.unravel_index(int(np.argmax(ratio)), ratio.shape)
    return float(ratio[i, j]), f"{names[i]}-{names[j]}"


def measure_pose(face: FaceModel, values: np.ndarray, graph: SkinGraph | None = None) -> Crease:
    """Folds, flips and strain against its floor of ``face`` posed by ``values`` (68)."""
    mesh = face.mesh
    graph = graph or skin_graph(mesh)
    posed = face.pose_values(np.asarray(values, float)).vertices
    q = measure(mesh, posed, graph)
    floor, _ = held_floor(mesh, posed, graph)
    is_in = np.zeros(mesh.n_vertices, bool)
    is_in[graph.inside] = True
    outside = graph.triangles[~is_in[graph.triangles].any(axis=1)]
    folded = int(folded_triangles(mesh.vertices, posed, outside).sum())
    return Crease(folded=folded, flipped=flipped_pairs(mesh.vertices, posed, outside), strain=q.max_strain,
                  floor=floor, near=q.near)
