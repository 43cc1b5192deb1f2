"""The head for the browser's FBA player: morph targets per FAP, so the page applies decoded FAPs itself.

The page (``static/fbaplayer.html``) decodes the stream with fba.js and needs a head it can pose from
FAP values alone. This is the representation chosen (issue 31): the GLB of
:func:`mpeg4fa.export.gltf.build_glb` in its ``vertex`` form, fed a still with two frames per FAP, so
that each FAP has two targets, the face engine's poses at two values minus the rest pose
(:func:`samples`), and the page weighs them to follow each FAP's motion to second order and sums
over the FAPs. Head pitch, yaw and roll (FAPs 48-50) are not targets but a rotation of the whole
head about feature point 7.1, as the face engine turns it. A FAP alone is exact at its two values
and close between; FAPs acting together add, where the face engine pins each feature point to its
own FAP (the inner and outer lip corners): the browser test measures it and the README states it.
"""
from __future__ import annotations

import json

import numpy as np

from mpeg4fa.face.model import FaceModel
from mpeg4fa.spec import ANGLE_UNIT, FAPS

HEAD_ROTATION = (48, 49, 50)
"""head_pitch, head_yaw, head_roll: a rotation of the whole head, not targets."""
TRANSLATION_UNIT = 200.0
"""FAPU of the pose each translational target is made from (a wide mouth movement)."""
ROTATION_UNIT = 10000.0
"""AU of the pose each rotational target (the eyeballs, the tongue roll) is made from: 0.1 rad."""
PIVOT = "7.1"
"""The feature point the head turns about (the top of the spine)."""


def unit(fap: int) -> float:
    """The value target ``fap`` is made at: 200 FAPU, or 10000 AU (0.1 rad) for a rotation."""
    return ROTATION_UNIT if FAPS[fap - 1].fapu == "AU" else TRANSLATION_UNIT


def samples(fap: int) -> tuple[float, float]:
    """The two values FAP ``fap``'s targets are made at: +-unit, or unit and twice it for a FAP the face
    shows only one way (negative values clamp to 0: ``unidirectional`` in spec/faps.csv)."""
    u = unit(fap)
    return (u, 2 * u) if FAPS[fap - 1].unidirectional else (u, -u)


def fap_head(face: FaceModel) -> tuple[bytes, dict]:
    """The GLB and its key: ``{"targets": [FAP of each morph target or null], "at": [value it was made at],
    "angle_unit": rad per AU, "rotation": [48, 49, 50], "pivot": [x, y, z] in metres,
    "feature_points": {"labels": [...], "rest": [[x, y, z] metres]}}``.

    Each FAP has two targets, its poses at the two :func:`samples`, so that the page can follow a
    curved motion (the jaw's arc, a lid over the eyeball) to second order: a value ``v`` weighs them
    so that ``w1 * v1 + w2 * v2 = v`` and ``w1 * v1**2 + w2 * v2**2 = v**2``.
    """
    import pygltflib as gl

    from mpeg4fa.export.gltf import MM, build_glb
    from mpeg4fa.fba.stream import FapStream

    made = [(f, v) for f in range(3, len(FAPS) + 1) if f not in HEAD_ROTATION for v in samples(f)]
    still = FapStream.empty(len(made) + 1)
    still.source_fps = 25.0
    still.timestamps[:] = np.arange(len(made) + 1) / 25.0
    still.fap_mask[:, 2:] = True  # every low-level FAP sent on every frame: nothing held from the frame before
    for k, (fap, value) in enumerate(made, start=1):
        still.fap_values[k, fap - 1] = int(value)
    data, _ = build_glb(still, face, animation="vertex", name="head")
    gltf = gl.GLTF2.load_from_bytes(data)
    names = gltf.meshes[0].extras["targetNames"]  # "frame K": the still's frame K, i.e. made[K - 1]
    frames = [int(n.split()[1]) for n in names]
    rest = face.mesh.vertices[np.asarray(face.mesh.fp_vertex)] * MM
    key = {"targets": [None if k == 0 else made[k - 1][0] for k in frames],
           "at": [None if k == 0 else made[k - 1][1] for k in frames],
           "angle_unit": float(ANGLE_UNIT), "rotation": list(HEAD_ROTATION),
           "pivot": (face.mesh.fp(PIVOT) * MM).tolist(),
           "feature_points": {"labels": list(face.mesh.fp_labels), "rest": rest.tolist()}}
    return data, key


def write_fap_head(face: FaceModel, glb_path, key_path) -> dict:
    """Write the GLB and its key (JSON) for a static player folder; returns the key."""
    from mpeg4fa.atomic import atomic_outputs

    data, key = fap_head(face)
    with atomic_outputs(glb_path, key_path) as (glb_tmp, key_tmp):
        glb_tmp.write_bytes(data)
        key_tmp.write_text(json.dumps(key), encoding="utf-8")
    return key


__all__ = ["fap_head", "write_fap_head", "unit", "samples", "HEAD_ROTATION", "PIVOT"]
