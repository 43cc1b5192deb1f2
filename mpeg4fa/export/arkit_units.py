"""The 52 ARKit face units of a head as named shapes, and their weights over a stream's frames.

Why a module of its own: a glTF head's morph targets and an ARKit blendshape track
are the same numbers. The ARKit deformer (:mod:`mpeg4fa.face.deformers.arkit`) drives
30 *driven* shapes: most are one unit; ``browInnerUp``, ``mouthPucker`` and
``cheekPuff`` are driven per side (``browInnerUp[left]`` is the left half of the
mirror-symmetric unit, so the two halves sum to the whole). Here every ARKit unit
gets one shape and one weight: a driven unit its driven shape (the two halves
summed) and the weight the deformer gives it (the mean of its two halves', so a
one-sided raise of a two-sided unit shows as half of it on both sides); a unit no
FAP drives (``eyeLookInLeft``, ``mouthClose`` ...) its sculpted shape and weight 0.

The parts the deformer takes from the feature-point layer ride along where a unit's
FAP moves them: each driven shape also holds the lower teeth and tongue as the
deformer moves them under the shape's FAP (the jaw
drops with ``jawOpen``, the tongue comes out with ``tongueOut``), linear in the weight
through the pose at weight :data:`CARRY_AT`. Left out of the ARKit deformer's pose: the correction
that puts the skin's feature points exactly where the FAPs say, the eye turns (no FAP
drives the ``eyeLook*`` units) and the head turn (a transform, not a shape: the glTF export
animates it as a node's rotation).

The lids are the exception to "sculpted shape": the deformer turns them over the eyeball
itself (the sculpted ``eyeBlink*`` units push them straight through it), so ``eyeBlinkLeft``
and ``eyeBlinkRight`` are the deformer's own lid turn at the top lid FAP's (19, 20) value of
:data:`LID_SHUT` (one IRISD0: the lid covers the iris), weighted by the FAP over that, 0..1.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.errors import MpegFaError
from mpeg4fa.face.deformers.arkit import ArkitRig, deform_arkit, unit_weights
from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.model import FaceModel
from mpeg4fa.spec import FAP_BY_NAME, FAPU, N_FAPS


class NoFaceUnitsError(MpegFaError):
    """The head carries no ARKit face units, so they cannot be exported or driven."""


LID_UNITS = {"eyeBlinkLeft": FAP_BY_NAME["close_t_l_eyelid"].number,
             "eyeBlinkRight": FAP_BY_NAME["close_t_r_eyelid"].number}
"""The blink units and the top lid FAP that drives each."""
LID_SHUT = float(FAPU["IRISD"].divisor)
"""The lid FAP value (IRISD units) at which a blink unit's weight is 1: the lid moved by one IRISD0."""


@dataclass(frozen=True)
class ArkitUnits:
    names: tuple[str, ...]   # the head's ARKit unit names (52 on the generic head), in its order
    shapes: np.ndarray       # (U, V, 3) float64 vertex deltas in mm, every mesh vertex (0 off the skin)
    mixing: np.ndarray       # (U, D): driven-shape weights -> unit weights (1 or 1/2 per driven shape)
    rig: ArkitRig
    lids: tuple[tuple[int, int], ...] = ()  # (unit, FAP column) of the blink units the lid FAPs weigh

    def weights(self, values: np.ndarray) -> np.ndarray:
        """(n, U) unit weights in 0..1 for (n, 68) resolved FAP rows, as the ARKit deformer drives them."""
        rows = np.atleast_2d(np.asarray(values, np.float64))
        out = unit_weights(self.rig, rows.T).T @ self.mixing.T  # (n, D) driven -> (n, U)
        for unit, column in self.lids:
            out[:, unit] = np.clip(rows[:, column] / LID_SHUT, 0.0, 1.0)
        return out


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
    halves = np.maximum(mixing.sum(axis=1, keepdims=True), 1.0)
    off_skin = np.ones(n_vertices, bool)
    off_skin[skin] = False
    carried = _carried(face, rig)[:, off_skin]  # (D, off-skin vertices, 3)
    shapes[:, off_skin] = np.einsum("ud,dvk->uvk", mixing / halves, carried)
    mixing /= halves
    for u, name in enumerate(names):
        if not mixing[u].any():
            shapes[u] = units.dense(name, n_vertices)
    lids = tuple((names.index(name), fap - 1) for name, fap in LID_UNITS.items() if name in names)
    rest = deform_arkit(face.rig, rig, np.zeros(N_FAPS)).vertices
    for unit, column in lids:
        shut = np.zeros(N_FAPS)
        shut[column] = LID_SHUT
        shapes[unit] = deform_arkit(face.rig, rig, shut).vertices - rest
    return ArkitUnits(names=names, shapes=shapes, mixing=mixing, rig=rig, lids=lids)


CARRY_AT = 0.5
"""The weight at which the carried parts' motion is sampled (a secant: the jaw's path is curved, and
speech keeps ``jawOpen`` mostly below this; at 0.4 the lower teeth are within 0.3 mm of the deformer's)."""


def _carried(face: FaceModel, rig: ArkitRig) -> np.ndarray:
    """(D, V, 3): what each driven shape's FAP does to every vertex in the ARKit deformer's pose, per unit of
    the shape's weight, sampled at :data:`CARRY_AT` (the mean over its FAPs when it has several); used off
    the skin."""
    rest = deform_arkit(face.rig, rig, np.zeros(N_FAPS)).vertices
    out = np.zeros((len(rig.unit_names), face.mesh.n_vertices, 3))
    for d in range(len(rig.unit_names)):
        faps = np.flatnonzero(rig.gains[d])
        for f in faps:
            values = np.zeros(N_FAPS)
            values[f] = CARRY_AT / rig.gains[d, f]
            out[d] += (deform_arkit(face.rig, rig, values).vertices - rest) / (CARRY_AT * len(faps))
    return out
