"""The face a decoder owns: a head mesh, its FAPU, and the four-layer animation.

>>> face = FaceModel.default()                      # the generic head (built on first use)
>>> face = face.calibrate(fdp, method="dffd")        # fitted to a sender's feature points
>>> pose = face.deform({3: 400, 51: -100})           # FAP number -> value
>>> pose.part("skin"), pose.feature_points

``deform`` takes one frame of low-level FAPs (an array of 68 values, a
``{fap: value}`` mapping, or a decoded :class:`~mpeg4fa.fba.stream.Frame`);
``animate`` plays a whole :class:`~mpeg4fa.fba.stream.FapStream`, resolving
unsent FAPs and the high-level visemes and expressions first.
"""
from __future__ import annotations

import copy
from functools import cached_property
from typing import Iterable, Iterator, Mapping

import numpy as np

from mpeg4fa.face.asset import load_head
from mpeg4fa.face.calibrate import CalibrationReport, calibrate_mesh
from mpeg4fa.face import deformers
from mpeg4fa.face.deformers.arkit import ArkitRig, build_arkit_rig
from mpeg4fa.face.pose import Pose
from mpeg4fa.decoded import FapValueError, FrameResolver, check_finite, clamp, resolve, shown_frame, shown_values
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.fapu import Fapu, measure_fapu
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.reach import saturate
from mpeg4fa.face.rig import Rig, build_rig
from mpeg4fa.fba.stream import FapStream, Frame
from mpeg4fa.spec import N_FAPS

_DEFAULT: "FaceModel | None" = None


class FaceModel:
    """A neutral head plus everything needed to pose it from FAPs."""

    DEFORMERS = deformers.names()

    def __init__(self, mesh: HeadMesh, calibration: CalibrationReport | None = None, *,
                 deformer: str = "fap", deformer_options: Mapping | None = None,
                 triangle_face: "FaceModel | None" = None) -> None:
        deformers.check(deformer, mesh, dict(deformer_options or {}))
        self.mesh = mesh
        self.calibration = calibration
        self.deformer = deformer
        self.deformer_options = dict(deformer_options or {})
        self.triangle_face = triangle_face
        """For a face with a NURBS skull: the same face with its triangle skull (calibrations start there)."""

    @property
    def skull(self) -> str:
        """``"nurbs"`` (see :meth:`with_nurbs_skull`) or ``"triangles"``."""
        return "triangles" if self.triangle_face is None else "nurbs"

    def with_deformer(self, deformer: str, **options) -> "FaceModel":
        """The same face posed by another deformer (:mod:`mpeg4fa.face.deformers` lists them), with
        its options (``with_deformer("blocks", regions=("lip_t", "lip_b"))``: elastic lip blocks only)."""
        triangles = self.triangle_face.with_deformer(deformer, **options) if self.triangle_face else None
        other = FaceModel(self.mesh, self.calibration, deformer=deformer, deformer_options=options,
                          triangle_face=triangles)
        for name in ("fapu", "rig"):  # the same mesh: what was set up for it already serves
            if name in self.__dict__:
                other.__dict__[name] = self.__dict__[name]
        return other

    def with_nurbs_skull(self) -> "FaceModel":
        """The same face with the skull cap no FAP moves as a trimmed NURBS surface, tessellated and
        joined to the moving triangles on their own border vertices (:mod:`mpeg4fa.face.nurbs`).

        A face that has one already is returned as it is; calibrating it calibrates its triangle
        head and fits the skull again, so the skull is always the NURBS surface of the shape shown.
        """
        from mpeg4fa.face.nurbs import nurbs_head

        if self.triangle_face is not None:
            return self
        mesh = nurbs_head(self.mesh, self.rig)
        return FaceModel(mesh, self.calibration, deformer=self.deformer, deformer_options=self.deformer_options,
                         triangle_face=self)

    @classmethod
    def from_mesh(cls, vertices, triangles, points, parts=None, uvs=None, *, name: str = "custom mesh",
                  deformer: str = "fap") -> "FaceModel":
        """Any triangle mesh with feature points, rigged as the generic head is (:func:`.custom.head_from_mesh`)."""
        from mpeg4fa.face.custom import head_from_mesh

        return cls(head_from_mesh(vertices, triangles, points, parts, uvs, name=name), deformer=deformer)

    @classmethod
    def default(cls, *, auto_install: bool = True) -> "FaceModel":
        """The generic CC0 head (built into the cache on first use); shared, so its rig is built once."""
        global _DEFAULT
        if _DEFAULT is None:
            _DEFAULT = cls(load_head(auto_install=auto_install))
        return _DEFAULT

    # -- what the face is -----------------------------------------------------------------

    def feature_points(self) -> dict[str, np.ndarray]:
        """Neutral feature point positions, label -> xyz."""
        fps = self.mesh.feature_points()
        return {label: fps[i] for i, label in enumerate(self.mesh.fp_labels)}

    @cached_property
    def fapu(self) -> Fapu:
        """FAPU measured on this neutral face."""
        return measure_fapu(self.feature_points())

    @cached_property
    def rig(self) -> Rig:
        """Precomputed weights (built on first use: Sibson coordinates, regions, jaw and neck)."""
        return build_rig(self.mesh, self.fapu)

    @cached_property
    def posing(self) -> deformers.Deformer:
        """This face's deformer, set up on first use: ``values (68,) -> Pose``."""
        return deformers.build(self.deformer, self.mesh, self.rig, **self.deformer_options)

    @cached_property
    def arkit_rig(self) -> ArkitRig:
        """The ARKit face units' rig (the ARKit deformer's own when that is this face's deformer)."""
        if self.deformer == "arkit":
            return self.posing.arkit
        return build_arkit_rig(self.mesh, self.rig)

    saturates: bool = True
    """Whether FAP values ease into this head's reach before posing (:mod:`mpeg4fa.face.reach`)."""

    def unlimited(self) -> "FaceModel":
        """The same face without its reach limiter (to measure the reach, or what the limiter spares)."""
        other = copy.copy(self)
        other.saturates = False
        return other

    def _pose(self, values: np.ndarray) -> Pose:
        """The one place FAP values become the face's pose: each eased into the head's reach first."""
        return self.posing(saturate(values) if self.saturates else values)

    # -- calibration ----------------------------------------------------------------------

    def calibrate(self, fdp, *, method: str = "dffd", alignment: str = "similarity") -> "FaceModel":
        """A new face fitted to an FDP's feature points (any subset of the 84)."""
        if self.triangle_face is not None:  # through the triangle head, then the skull fitted again
            return self.triangle_face.calibrate(fdp, method=method, alignment=alignment).with_nurbs_skull()
        labels, points = tuple(fdp.labels), np.asarray(fdp.points, dtype=np.float64)
        unknown = [label for label in labels if label not in self.mesh.fp_labels]
        if unknown:
            raise FaceError(f"the FDP names unknown feature points {', '.join(unknown)}")
        mesh, report = calibrate_mesh(self.mesh, labels, points, method=method, alignment=alignment)
        return FaceModel(mesh, report, deformer=self.deformer, deformer_options=self.deformer_options)

    def to_fdp(self, *, with_mesh: bool = False, name: str = "mpeg4fa generic head"):
        """This face's feature points (and optionally its skin mesh) as an FDP a sender can transmit."""
        from mpeg4fa.fdp import Fdp, FdpMesh

        mesh = None
        if with_mesh:
            skin = self.mesh.part("skin")
            mesh = FdpMesh(vertices=self.mesh.vertices[skin], triangles=self.mesh.triangles["skin"] - skin.start,
                           name="skin")
        labels = [label for label in self.mesh.fp_labels if label != "11.5"]
        points = {label: self.mesh.fp(label) for label in labels}
        return Fdp.from_points(points, mesh=mesh, fapu=self.fapu.as_dict(), name=name)

    # -- animation ------------------------------------------------------------------------

    def frame_values(self, frame: "np.ndarray | Mapping[int, float] | Frame") -> np.ndarray:
        """The 68 values a frame shows (:mod:`mpeg4fa.decoded`, the rules every caller shares): a
        stream's frame resolved with the frames before it, so ``deform(stream.frame(k))`` is
        ``animate(stream)``'s pose ``k``; a mapping or array of low-level FAPs as given. Clamps are said."""
        try:
            return shown_frame(frame) if isinstance(frame, Frame) else shown_values(frame)
        except FapValueError as exc:  # said as the face's error: the face was asked to show it
            raise FaceError(exc.message, where=exc.where, hint=exc.hint) from None

    def deform(self, frame: "np.ndarray | Mapping[int, float] | Frame") -> Pose:
        """The face posed by one frame of FAPs."""
        return self._pose(self.frame_values(frame))

    def neutral(self) -> Pose:
        return self._pose(np.zeros(N_FAPS))

    def animate(self, stream: FapStream) -> Iterator[Pose]:
        """One pose per stream frame, with unsent FAPs held or interpolated (see :mod:`mpeg4fa.decoded`)."""
        for values in resolve(stream):
            yield self.pose_values(values)

    def animate_frames(self, frames: Iterable[Frame]) -> Iterator[Pose]:
        """:meth:`animate` for frames as they arrive (a live decoder): resolved one at a time."""
        resolver = FrameResolver()
        for frame in frames:
            yield self.pose_values(resolver.push(frame))

    def pose_values(self, values: np.ndarray) -> Pose:
        """The pose for one row of resolved values (68, as :func:`mpeg4fa.decoded.resolve` gives).

        Resolved rows are already inside what a face shows; anything else is clamped silently here.
        """
        check_finite(values)
        return self._pose(clamp(values)[0])
