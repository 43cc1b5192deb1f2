"""The generic head as plain arrays: one vertex array, parts as contiguous ranges.

A :class:`HeadMesh` is data, not behaviour: the asset builder writes one, the
calibration returns a deformed copy, the animation reads it. All parts share one
vertex array so that a deformation is one ``(V, 3)`` array and a part is a slice
of it. Units are millimetres; x points toward the face's left, y up, z out of
the face (the MPEG-4 neutral-face axes).
"""
from __future__ import annotations

import zipfile
import zlib
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from mpeg4fa.face.errors import FaceError

PARTS = ("skin", "eye_l", "eye_r", "teeth_upper", "teeth_lower", "tongue", "joints")
"""Part names in vertex order. ``joints`` holds one invisible vertex per joint centre,
so that joint centres follow a calibration like any other point."""


@dataclass(frozen=True)
class FaceUnits:
    """Sparse blend-shape deltas (the CC0 ARKit face units), per unit name."""

    names: tuple[str, ...]
    offsets: np.ndarray  # (U+1,) start of each unit's rows in indices/deltas
    indices: np.ndarray  # (K,) vertex indices
    deltas: np.ndarray  # (K, 3) mm

    def unit(self, name: str) -> tuple[np.ndarray, np.ndarray]:
        """``(vertex_indices, deltas)`` of one unit."""
        try:
            k = self.names.index(name)
        except ValueError:
            raise FaceError(f"no face unit named {name!r}", hint=f"known: {', '.join(self.names)}") from None
        a, b = self.offsets[k], self.offsets[k + 1]
        return self.indices[a:b], self.deltas[a:b]

    def dense(self, name: str, n_vertices: int) -> np.ndarray:
        """One unit's deltas as a dense ``(V, 3)`` array."""
        idx, d = self.unit(name)
        out = np.zeros((n_vertices, 3))
        out[idx] = d
        return out


@dataclass(frozen=True)
class HeadMesh:
    """Vertices, triangles and the labels that make a mesh a face."""

    vertices: np.ndarray  # (V, 3) float64, mm
    part_ranges: dict[str, tuple[int, int]]
    triangles: dict[str, np.ndarray]  # part -> (T, 3) int32 global vertex indices
    corner_uvs: dict[str, np.ndarray]  # part -> (T, 3, 2) texture coordinates per triangle corner
    mirror: np.ndarray  # (V,) index of each vertex's left/right mirror image
    joints: dict[str, int]  # joint name -> vertex index in the joints part
    fp_labels: tuple[str, ...]  # the 84 labels in the standard's order
    fp_vertex: np.ndarray  # (84,) vertex index of each feature point
    fp_reach: np.ndarray  # (84,) edge rings a FAP-driven point moves on the skin (0: anchor)
    face_units: FaceUnits | None = None
    source: str = ""
    info: dict = field(default_factory=dict)

    @property
    def n_vertices(self) -> int:
        return len(self.vertices)

    def part(self, name: str) -> slice:
        """The vertex slice of a part."""
        try:
            a, b = self.part_ranges[name]
        except KeyError:
            raise FaceError(f"no part named {name!r}", hint=f"parts: {', '.join(self.part_ranges)}") from None
        return slice(a, b)

    def feature_points(self, vertices: np.ndarray | None = None) -> np.ndarray:
        """``(84, 3)`` feature point positions of ``vertices`` (default: the neutral mesh)."""
        v = self.vertices if vertices is None else vertices
        return v[self.fp_vertex]

    def fp_index(self, label: str) -> int:
        try:
            return self.fp_labels.index(label)
        except ValueError:
            raise FaceError(f"{label!r} is not an MPEG-4 feature point label", hint="labels look like 2.1 .. 11.6") from None

    def fp(self, label: str, vertices: np.ndarray | None = None) -> np.ndarray:
        """One feature point's position."""
        v = self.vertices if vertices is None else vertices
        return v[self.fp_vertex[self.fp_index(label)]]

    def joint(self, name: str, vertices: np.ndarray | None = None) -> np.ndarray:
        v = self.vertices if vertices is None else vertices
        try:
            return v[self.joints[name]]
        except KeyError:
            raise FaceError(f"no joint named {name!r}", hint=f"joints: {', '.join(self.joints)}") from None

    def all_triangles(self, parts: tuple[str, ...] | None = None) -> np.ndarray:
        names = [p for p in (parts or tuple(self.triangles)) if p in self.triangles]
        return np.concatenate([self.triangles[p] for p in names]) if names else np.zeros((0, 3), np.int32)

    def height(self) -> float:
        """Head height (top of skull to bottom of chin, 11.4.y - 2.1.y): the scale for tolerances."""
        return float(self.fp("11.4")[1] - self.fp("2.1")[1])

    def lateral(self) -> np.ndarray:
        """Each vertex's signed distance (mm) from the midline, + on the face's left (+x): half its x
        offset from its mirror image, so it holds for a calibrated head standing anywhere in the
        sender's frame (shifted or turned), where x = 0 is no longer the midline."""
        x = self.vertices[:, 0]
        return 0.5 * (x - x[self.mirror])

    def with_vertices(self, vertices: np.ndarray, **info) -> "HeadMesh":
        """A copy with other vertex positions (a calibrated or posed head)."""
        if vertices.shape != self.vertices.shape:
            raise FaceError(f"vertex array has shape {vertices.shape}, expected {self.vertices.shape}")
        return replace(self, vertices=np.asarray(vertices, dtype=np.float64), info={**self.info, **info})

    # -- storage -------------------------------------------------------------------------

    def save(self, path: Path) -> None:
        """Write the mesh as one ``.npz`` (no pickles), atomically."""
        arrays: dict[str, np.ndarray] = {
            "vertices": self.vertices, "mirror": self.mirror, "fp_vertex": self.fp_vertex,
            "fp_reach": self.fp_reach, "fp_labels": np.array(self.fp_labels),
            "part_names": np.array(list(self.part_ranges)),
            "part_ranges": np.array(list(self.part_ranges.values()), dtype=np.int64),
            "joint_names": np.array(list(self.joints)),
            "joint_index": np.array(list(self.joints.values()), dtype=np.int64),
            "source": np.array(self.source),
        }
        for name, tri in self.triangles.items():
            arrays[f"tri_{name}"] = tri
            arrays[f"uv_{name}"] = self.corner_uvs[name]
        if self.face_units is not None:
            arrays.update(fu_names=np.array(self.face_units.names), fu_offsets=self.face_units.offsets,
                          fu_indices=self.face_units.indices, fu_deltas=self.face_units.deltas)
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(path.name + ".part")
        with open(tmp, "wb") as f:
            np.savez_compressed(f, **arrays)
        tmp.replace(path)

    @classmethod
    def load(cls, path: Path) -> "HeadMesh":
        try:
            with np.load(path, allow_pickle=False) as z:
                data = {k: z[k] for k in z.files}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile, zlib.error) as exc:
            raise FaceError(f"cannot read the head asset: {exc}", where=str(path),
                            hint="rebuild it with `mpeg4fa model install --force`") from None
        try:
            names = [str(n) for n in data["part_names"]]
            ranges = {n: (int(a), int(b)) for n, (a, b) in zip(names, data["part_ranges"])}
            tris = {n: data[f"tri_{n}"] for n in names if f"tri_{n}" in data}
            uvs = {n: data[f"uv_{n}"] for n in tris}
            units = None
            if "fu_names" in data:
                units = FaceUnits(tuple(str(n) for n in data["fu_names"]), data["fu_offsets"],
                                  data["fu_indices"], data["fu_deltas"])
            return cls(
                vertices=data["vertices"], part_ranges=ranges, triangles=tris, corner_uvs=uvs,
                mirror=data["mirror"],
                joints={str(n): int(i) for n, i in zip(data["joint_names"], data["joint_index"])},
                fp_labels=tuple(str(x) for x in data["fp_labels"]), fp_vertex=data["fp_vertex"],
                fp_reach=data["fp_reach"], face_units=units, source=str(data["source"]),
            )
        except KeyError as exc:
            raise FaceError(f"head asset lacks {exc}", where=str(path),
                            hint="rebuild it with `mpeg4fa model install --force`") from None
