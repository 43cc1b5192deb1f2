"""The 52 ARKit face units of a head as named shapes, and their weights over a stream's frames.

Why a module of its own: a glTF head's morph targets and an ARKit blendshape track
are the same numbers. The ARKit deformer (:mod:`mpeg4fa.face.deformers.arkit`) drives
30 *driven* shapes: most are one unit; ``browInnerUp``, ``mouthPucker`` and
``cheekPuff`` are driven per side (``browInnerUp[left]`` is the left half of the
mirror-symmetric unit, so the two halves sum to the whole). Here every ARKit unit
gets one shape and one weight: a driven unit its driven shape (the two halves
summed) and the weight the deformer gives it (the mean of its two halves', so a
one-sided raise of a two-sided unit shows as half of it on both sides); a unit no
FAP drives (``eyeBlinkLeft``, ``mouthClose`` ...) its sculpted shape and weight 0.

What this leaves out of the ARKit deformer's pose: the correction that puts the
skin's feature points exactly where the FAPs say, the eyes, lids, teeth and tongue
(taken from the feature-point deformer there) and the head turn. The shapes move
the skin only.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.errors import MpegFaError
from mpeg4fa.face.deformers.arkit import ArkitRig, unit_weights
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.model import FaceModel


class NoFaceUnitsError(MpegFaError):
    """The head carries no ARKit face units, so they cannot be exported or driven."""


@dataclass(frozen=True)
class ArkitUnits:
    names: tuple[str, ...]   # the head's ARKit unit names (52 on the generic head), in its order
    shapes: np.ndarray       # (U, V, 3) float64 vertex deltas in mm, every mesh vertex (0 off the skin)
    mixing: np.ndarray       # (U, D): driven-shape weights -> unit weights (1 or 1/2 per driven shape)
    rig: ArkitRig

    def weights(self, values: np.ndarray) -> np.ndarray:
        """(n, U) unit weights in 0..1 for (n, 68) resolved FAP rows, as the ARKit deformer drives them."""
        driven = unit_weights(self.rig, np.atleast_2d(np.asarray(values, np.float64)).T).T  # (n, D)
        return driven @ self.mixing.T


def base_unit(driven: str) -> str:
    """``browInnerUp[left]`` -> ``browInnerUp``; a plain unit name as it is."""
    return driven.partition("[")[0]


def arkit_units(face: FaceModel, *, where: str | None = None) -> ArkitUnits:
    """The face's ARKit units as whole-mesh shapes and the map from the deformer's driven shapes."""
    units = face.mesh.face_units
    if units is None:
        raise NoFaceUnitsError("this head has no ARKit face units to animate as morph targets", where=where,
                               hint="the generic head has them (`mpeg4fa model install`); for this head use "
                                    "--animation vertex")
    try:
        rig = face.arkit_rig
    except FaceError as exc:  # pragma: no cover - a head with units always has the rig
        raise NoFaceUnitsError(exc.message, where=where, hint="use --animation vertex") from None
    names = tuple(units.names)
    n_vertices = face.mesh.n_vertices
    skin = face.mesh.part("skin")
    driven = rig.deltas.toarray().reshape(skin.stop - skin.start, 3, -1)  # (n_skin, 3, D)
    shapes = np.zeros((len(names), n_vertices, 3))
    mixing = np.zeros((len(names), len(rig.unit_names)))
    for d, name in enumerate(rig.unit_names):
        u = names.index(base_unit(name))
        shapes[u, skin] += driven[:, :, d]
        mixing[u, d] = 1.0
    mixing /= np.maximum(mixing.sum(axis=1, keepdims=True), 1.0)
    for u, name in enumerate(names):
        if not mixing[u].any():
            shapes[u] = units.dense(name, n_vertices)
    return ArkitUnits(names=names, shapes=shapes, mixing=mixing, rig=rig)
