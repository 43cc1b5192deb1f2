"""Live streaming (``mpeg4fa serve``): tagged text in, speech and its FBA bitstream out over a WebSocket.

Modules: ``protocol`` (the messages, documented there), ``sentences`` (tagged text cut into
sentences, expressions carried across), ``segments`` (one sentence spoken and encoded), ``flow``
(the client's buffer level bounds what is sent), ``app`` (FastAPI: pages, heads, ``/ws``),
``microphone`` (the page's microphone in, faces out), ``client`` (a Python client that plays at a
given speed, for tests and benchmarks), ``fap_head`` (the head the pages pose: a GLB and the face
engine's rig as data), ``heads`` (heads calibrated to an uploaded FDP), ``static/`` (the live page
and the FBA player: fba.js decodes, facerig.js poses, three.js draws, WebAudio plays).
"""
from __future__ import annotations

__all__ = ["create_app"]


def create_app(*args, **kwargs):
    """:func:`mpeg4fa.serve.app.create_app` (imported on first use: FastAPI loads only when serving)."""
    from mpeg4fa.serve.app import create_app as make

    return make(*args, **kwargs)
