"""Live streaming (``mpeg4fa serve``): tagged text in, speech, FBA frames and ARKit weights out over a WebSocket.

Modules: ``protocol`` (the messages, documented there), ``sentences`` (tagged text cut into
sentences, expressions carried across), ``segments`` (one sentence spoken, encoded, decoded and
weighed), ``flow`` (the client's buffer level bounds what is sent), ``app`` (FastAPI: page, GLB,
``/ws``), ``client`` (a Python client that plays at a given speed, for tests and benchmarks),
``static/`` (the browser player: three.js + WebAudio).
"""
from __future__ import annotations

__all__ = ["create_app"]


def create_app(*args, **kwargs):
    """:func:`mpeg4fa.serve.app.create_app` (imported on first use: FastAPI loads only when serving)."""
    from mpeg4fa.serve.app import create_app as make

    return make(*args, **kwargs)
