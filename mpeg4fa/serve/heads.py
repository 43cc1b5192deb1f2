"""Heads calibrated to a sender's FDP, for the FBA player: the FDP (and the texture it carries) applied.

A user opening a ``.fba`` with its ``.fdp`` sees the face the sender defined, as ``mpeg4fa play --fdp``
shows it: :func:`mpeg4fa.face.assemble.assemble_face` calibrates the generic head to the FDP's feature
points (a case-4 FDP with its own mesh plays that mesh), the FDP's texture is baked onto the skin
(:func:`mpeg4fa.render.fdp_texture.fdp_skin_texture`), and :func:`.fap_head.fap_head` makes the GLB and
rig the page poses. The page posts the file's bytes to ``POST /api/head?name=...``; the answer names
the head's GLB and key (``/api/head/ID.glb``, ``/api/head/ID.json``, ID from the bytes' SHA-256), kept
for the :data:`KEPT` latest FDPs. Bad input is one error naming the file and what is wrong in it.
"""
from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor

KEPT = 8
"""Calibrated heads kept (a few MB each): the same FDP opened again is not calibrated again."""
WORKER = ThreadPoolExecutor(max_workers=1, thread_name_prefix="mpeg4fa-heads")
"""The one thread heads are made on: baking a texture uses the process's OpenGL context
(:func:`mpeg4fa.render.context.gl_context`), which is current on the thread that made it only."""


def calibrated_head(data: bytes, name: str) -> tuple[bytes, dict, dict]:
    """(GLB, key, summary) of the generic head calibrated to the FDP ``data`` (file ``name``)."""
    from mpeg4fa.face.assemble import assemble_face
    from mpeg4fa.fdp.io import fdp_from_data
    from mpeg4fa.render.fdp_texture import fdp_skin_texture
    from mpeg4fa.serve.fap_head import fap_head

    fdp = fdp_from_data(data, name)
    face = assemble_face(fdp=fdp)
    sent = fdp_skin_texture(face.mesh, fdp, source=name)
    glb, key = fap_head(face, texture=None if sent is None else sent.image)
    summary = {"name": name, "points": len(fdp.labels), "texture": None if sent is None else sent.name,
               "deformer": face.deformer}
    return glb, key, summary


def fdp_texture(face, path) -> object:
    """The texture FDP file ``path`` carries, baked onto ``face`` (None without one), made on :data:`WORKER`
    (``serve --fdp``: the page's head wears it; later uploads bake on the same thread)."""
    def bake():
        from mpeg4fa.fdp import load_fdp
        from mpeg4fa.render.fdp_texture import fdp_skin_texture

        sent = fdp_skin_texture(face.mesh, load_fdp(path), source=str(path))
        return None if sent is None else sent.image
    return WORKER.submit(bake).result()


class Heads:
    """The calibrated heads made so far, by id (at most :data:`KEPT`, the oldest dropped first)."""

    def __init__(self) -> None:
        self._heads: OrderedDict[str, tuple[bytes, dict, dict]] = OrderedDict()
        self._lock = threading.Lock()

    def add(self, data: bytes, name: str) -> dict:
        """Calibrate (or find) the head of FDP ``data``; the summary with its ``id``, ``glb`` and ``key`` URLs."""
        ident = hashlib.sha256(data).hexdigest()[:16]
        with self._lock:
            made = self._heads.get(ident)
        if made is None:
            made = calibrated_head(data, name)
            with self._lock:
                self._heads[ident] = made
                while len(self._heads) > KEPT:
                    self._heads.popitem(last=False)
        return {**made[2], "id": ident, "glb": f"/api/head/{ident}.glb", "key": f"/api/head/{ident}.json"}

    def get(self, ident: str) -> tuple[bytes, dict] | None:
        with self._lock:
            made = self._heads.get(ident)
        return None if made is None else (made[0], made[1])
