"""The decoder's face: a generic 3D head, FDP calibration, FAPU and FAP-driven animation.

Four layers, each a function over arrays (seed paper §6):

1. high-level FAPs (visemes, expressions) expand to low-level FAPs through the
   shared profiles in ``spec/``, with unsent FAPs held or interpolated: :mod:`mpeg4fa.decoded`,
   the rules every reader of a stream shares;
2. low-level FAPs move feature points by value x FAPU along the standard's
   directions, or rotate eyes, jaw, lids, tongue and head (:mod:`.motion`);
3. feature point motion spreads to the mesh through Sibson weights cut to edge
   regions (:mod:`.rig`, :mod:`.regions`);
4. the mesh is posed once per frame by a deformer (:mod:`.deformers`: the feature-point
   deformer by default, the sculpted ARKit face units, ...).

Calibration to a sender's feature points: :mod:`.calibrate` (Dirichlet FFD, RBF or the linear
elastic model of :mod:`.elastic`); the static skull as a NURBS surface: :mod:`.nurbs`.
The generic head is built from CC0 assets at set-up: :mod:`.asset`.
"""
from mpeg4fa.face.calibrate import CalibrationReport
from mpeg4fa.face.pose import Pose
from mpeg4fa.face.errors import FaceError, FaceWarning
from mpeg4fa.face.fapu import Fapu, measure_fapu
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.face.model import FaceModel

__all__ = ["FaceModel", "Pose", "HeadMesh", "Fapu", "measure_fapu", "CalibrationReport", "FaceError", "FaceWarning"]
