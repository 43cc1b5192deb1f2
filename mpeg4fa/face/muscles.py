"""Waters' (1987) linear muscles on a face: the muscle table, placed on one neutral head, as a basis.

The model (K. Waters, "A muscle model for animating three-dimensional facial
expression", SIGGRAPH 1987; as restated in Parke & Waters, *Computer Facial
Animation*): a linear muscle is a vector from its attachment ``V1`` (on bone) to
its insertion ``V2`` (in the skin). A skin point ``p`` at distance ``D = |p - V1|``
and angle ``mu`` from the muscle axis ``V2 - V1`` moves toward the attachment,

    p' = p + K * A(mu) * R(D) * (V1 - p) / |V1 - p|,

with ``K`` the contraction (mm here), ``R`` the radial factor (0 at the attachment,
rising to 1 at the fall-off start ``Rs``, back to 0 at the fall-off end ``Rf``):

    R = cos((1 - D / Rs) * pi / 2)                for D < Rs
    R = cos((D - Rs) / (Rf - Rs) * pi / 2)        for Rs <= D <= Rf,  0 beyond,

and ``A`` the angular factor inside the zone of influence, a cone of half-angle
``Omega`` about the axis. Waters' ``A = cos(mu)`` does not reach 0 at the cone's
edge for the narrow cones of facial muscles (a step in the skin); this module uses
``A = cos(mu / Omega * pi / 2)``, which is ``cos(mu)`` for ``Omega = 90`` degrees and
falls smoothly to 0 at the edge (0 outside). The displacement is linear in ``K``
for a fixed neutral face, so each muscle is one column of a basis.

Three restrictions keep a muscle on its own skin (all are multiplied into ``A R``):
the skin must be reachable from the insertion along the surface the short way
(:func:`.regions.detour_fade`: an upper-lip muscle leaves the lower lip alone), the lid
margins belong to the lids (fade to 0 over :data:`.rig.LID_CLEAR_MM`, over
:data:`.lids.LID_HEIGHT_MM` for the lid's own levator), and a paired muscle fades out
across the midline (:data:`CROSS_ES`).

The muscles are data (``data/muscles.csv``): attachment and insertion each as a
feature point plus an offset in units of ES0 (the eye separation), so that they
follow a calibrated face; the zone as ``Omega`` and ``Rs``, ``Rf`` in multiples of the
muscle's length. Paired muscles are listed for the face's left side (x > 0) and
mirrored for the right (the feature point's mirror image, the offset's x negated).
"""
from __future__ import annotations

import csv
from dataclasses import dataclass
from importlib import resources

import numpy as np
from scipy.sparse.csgraph import dijkstra

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.fapu import Fapu
from mpeg4fa.face.lids import LID_HEIGHT_MM
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.regions import LID_MARGIN_LOOPS, detour_fade, edge_graph, shortest_loop, smooth_down
from mpeg4fa.face.rig import LID_CLEAR_MM

FLIP_X = np.array([-1.0, 1.0, 1.0])
DRIVERS = ("solve", "lid")  # contraction solved from the feature point targets, or read off the lid FAP
CROSS_ES = 0.25  # a paired muscle's field fades over this (in ES0) either side of the midline


@dataclass(frozen=True)
class MuscleSpec:
    """One row of ``data/muscles.csv`` (a left muscle when ``side == "pair"``)."""

    muscle: str
    side: str  # "pair" (listed left, mirrored right) or "mid"
    attach_fp: str
    attach_offset: tuple[float, float, float]  # in ES0
    insert_fp: str
    insert_offset: tuple[float, float, float]
    omega_deg: float
    rs: float  # fall-off start, in muscle lengths from the attachment
    rf: float  # fall-off end
    driven_by: str
    why: str


@dataclass(frozen=True)
class Muscle:
    """A muscle placed on one face (model units)."""

    name: str  # e.g. "zygomatic_major_l"
    spec: MuscleSpec
    side: str  # "l", "r" or "m"
    attachment: np.ndarray  # V1 (3,)
    insertion: np.ndarray  # V2 (3,)
    omega: float  # radians
    rs: float  # mm
    rf: float  # mm

    @property
    def length(self) -> float:
        return float(np.linalg.norm(self.insertion - self.attachment))


def load_specs() -> tuple[MuscleSpec, ...]:
    """The muscle table, checked (zones in order, known drivers)."""
    with (resources.files("mpeg4fa.face") / "data" / "muscles.csv").open(encoding="utf-8") as f:
        rows = list(csv.DictReader(f))
    specs = []
    for r in rows:
        s = MuscleSpec(
            muscle=r["muscle"], side=r["side"], attach_fp=r["attach_fp"],
            attach_offset=tuple(float(r[f"attach_d{a}"]) for a in "xyz"), insert_fp=r["insert_fp"],
            insert_offset=tuple(float(r[f"insert_d{a}"]) for a in "xyz"), omega_deg=float(r["omega_deg"]),
            rs=float(r["rs"]), rf=float(r["rf"]), driven_by=r["driven_by"], why=r["why"])
        valid = 0 < s.omega_deg <= 90 and 0 < s.rs < s.rf and s.driven_by in DRIVERS and s.side in ("pair", "mid")
        if not valid:
            raise FaceError(f"muscles.csv: bad row for {s.muscle}",
                            hint="0 < omega_deg <= 90, 0 < rs < rf, driven_by one of solve|lid, side pair|mid")
        specs.append(s)
    return tuple(specs)


def waters_factor(points: np.ndarray, attachment: np.ndarray, insertion: np.ndarray, omega: float,
                  rs: float, rf: float) -> tuple[np.ndarray, np.ndarray]:
    """Waters' ``A * R`` per point (0 outside the zone) and the unit direction toward the attachment.

    ``points`` (N, 3); ``omega`` the cone's half-angle (radians); ``rs``, ``rf`` distances (mm)
    from the attachment. The displacement of a contraction ``K`` is ``K * factor[:, None] * direction``.
    """
    rel = attachment - points
    d = np.linalg.norm(rel, axis=1)
    axis = insertion - attachment
    axis = axis / np.linalg.norm(axis)
    with np.errstate(invalid="ignore", divide="ignore"):
        direction = np.where(d[:, None] > 0, rel / np.where(d > 0, d, 1.0)[:, None], 0.0)
        cos_mu = np.clip(-(direction @ axis), -1.0, 1.0)
    mu = np.arccos(cos_mu)
    angular = np.where(mu < omega, np.cos(np.minimum(mu / omega, 1.0) * np.pi / 2), 0.0)
    radial = np.where(d < rs, np.cos((1.0 - d / rs) * np.pi / 2),
                      np.where(d <= rf, np.cos(np.clip((d - rs) / (rf - rs), 0.0, 1.0) * np.pi / 2), 0.0))
    return np.maximum(angular * radial, 0.0), direction


def _mirror_labels(mesh: HeadMesh) -> dict[str, str]:
    """Each feature point's mirror image (by the mesh's vertex mirror; nearest mirrored point else)."""
    fps = mesh.feature_points()
    by_vertex = {int(v): label for label, v in zip(mesh.fp_labels, mesh.fp_vertex)}
    out = {}
    for i, label in enumerate(mesh.fp_labels):
        other = by_vertex.get(int(mesh.mirror[mesh.fp_vertex[i]]))
        if other is None:
            other = mesh.fp_labels[int(np.argmin(np.linalg.norm(fps - fps[i] * FLIP_X, axis=1)))]
        out[label] = other
    return out


def place_muscles(mesh: HeadMesh, fapu: Fapu, specs: tuple[MuscleSpec, ...] | None = None) -> list[Muscle]:
    """Every muscle of the table on this face, left then right for each pair."""
    specs = load_specs() if specs is None else specs
    mirror = _mirror_labels(mesh)
    scale = fapu.ES0
    out = []
    for s in specs:
        sides = (("l", 1.0), ("r", -1.0)) if s.side == "pair" else (("m", 1.0),)
        for side, sx in sides:
            a_fp, i_fp = (s.attach_fp, s.insert_fp) if sx > 0 else (mirror[s.attach_fp], mirror[s.insert_fp])
            flip = np.array([sx, 1.0, 1.0])
            v1 = mesh.fp(a_fp) + scale * flip * np.array(s.attach_offset)
            v2 = mesh.fp(i_fp) + scale * flip * np.array(s.insert_offset)
            length = float(np.linalg.norm(v2 - v1))
            if length <= 0:
                raise FaceError(f"muscle {s.muscle}: attachment and insertion coincide on this face")
            out.append(Muscle(name=f"{s.muscle}_{side}", spec=s, side=side, attachment=v1, insertion=v2,
                              omega=np.radians(s.omega_deg), rs=s.rs * length, rf=s.rf * length))
    return out


def _margin_distance(mesh: HeadMesh, limit: float) -> np.ndarray:
    """Surface distance of every skin vertex to the nearest lid margin (inf beyond ``limit``)."""
    skin = mesh.part("skin")
    local = mesh.vertices[skin]
    tris = mesh.triangles["skin"] - skin.start
    margins = np.concatenate([shortest_loop(mesh, labels) for labels in LID_MARGIN_LOOPS]) - skin.start
    return dijkstra(edge_graph(local, tris), indices=margins, min_only=True, limit=limit)


def muscle_basis(mesh: HeadMesh, muscles: list[Muscle], fapu: Fapu) -> np.ndarray:
    """``(skin vertices, 3, M)``: each muscle's skin displacement per mm of contraction.

    A paired muscle fades out across the midline: whole up to :data:`CROSS_ES` x ES0 from it on
    its own side, half on it, 0 as far on the other side (Waters' cones are wide: a left
    frontalis would lift the right brow; a symmetric pair adds up to whole on the midline).

    On a mirror-symmetric face the right muscle's field is the exact mirror image of the
    left's (the edge graphs of a mirrored mesh are not quite mirrored: distances differ by
    a fraction of an edge), so that symmetric FAPs pose a symmetric face.
    """
    skin = mesh.part("skin")
    local = mesh.vertices[skin]
    tris = mesh.triangles["skin"] - skin.start
    insert_v = np.array([int(np.argmin(np.linalg.norm(local - m.insertion, axis=1))) for m in muscles])
    surface, _ = detour_fade(local, tris, insert_v)
    to_margin = _margin_distance(mesh, max(LID_CLEAR_MM, LID_HEIGHT_MM))
    clear = 1.0 - smooth_down(to_margin / LID_CLEAR_MM)
    clear_lid = 1.0 - smooth_down(to_margin / LID_HEIGHT_MM)
    basis = np.zeros((len(local), 3, len(muscles)))
    x = mesh.lateral()[skin]
    for j, m in enumerate(muscles):
        factor, direction = waters_factor(local, m.attachment, m.insertion, m.omega, m.rs, m.rf)
        factor = factor * surface[j] * (clear_lid if m.spec.driven_by == "lid" else clear)
        if m.side in ("l", "r"):
            c = CROSS_ES * fapu.ES0  # 1 at c on its own side, 1/2 on the midline, 0 at c across
            factor = factor * smooth_down((c - (1.0 if m.side == "l" else -1.0) * x) / (2.0 * c))
        basis[:, :, j] = factor[:, None] * direction
    mirror = mesh.mirror[skin] - skin.start
    if _is_symmetric(mesh):
        index = {m.name: j for j, m in enumerate(muscles)}
        for j, m in enumerate(muscles):
            if m.side == "l":
                basis[:, :, index[m.name[:-2] + "_r"]] = basis[mirror, :, j] * FLIP_X
            elif m.side == "m":
                basis[:, :, j] = 0.5 * (basis[:, :, j] + basis[mirror, :, j] * FLIP_X)
    return basis


def _is_symmetric(mesh: HeadMesh) -> bool:
    skin = mesh.part("skin")
    mirror = mesh.mirror[skin]
    if mirror.min() < skin.start or mirror.max() >= skin.stop:
        return False
    v = mesh.vertices
    return bool(np.abs(v[mirror] * FLIP_X - v[skin]).max() <= 1e-9 * max(mesh.height(), 1.0))
