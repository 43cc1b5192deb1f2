"""Decoded streams written for other tools: glTF heads with their animation, and face-tracking formats.

* :mod:`.weights`: per-frame ARKit-52 blend-shape weights (as the ARKit deformer drives the head)
  and Oculus/OVR-15 viseme weights, and their JSON;
* :mod:`.gltf`: the (calibrated) head as a GLB, its parts and materials, the stream baked as ARKit-named
  morph-target weights or per-frame vertex targets (:func:`export_glb`);
* :mod:`.events`: Azure-style viseme events (``AudioOffset`` ticks, ``VisemeId``) at each change of
  the viseme shown, and their JSON.

The maps between our visemes and those systems' are data in ``spec/`` (:mod:`mpeg4fa.spec.avatars`).
"""
from __future__ import annotations

from mpeg4fa.export.events import VisemeChange, azure_events, viseme_changes, write_azure_json
from mpeg4fa.export.gltf import GlbExport, build_glb, export_glb
from mpeg4fa.export.weights import (Weights, arkit_weights, oculus_weights, viseme_arkit_table, viseme_weights,
                                    write_weights_json)

__all__ = [
    "Weights", "arkit_weights", "oculus_weights", "viseme_arkit_table", "viseme_weights", "write_weights_json",
    "VisemeChange", "viseme_changes", "azure_events", "write_azure_json", "GlbExport", "build_glb", "export_glb",
]
