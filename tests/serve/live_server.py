"""The live server in-process: uvicorn in a thread on a free 127.0.0.1 port (shared by the serve and e2e tests)."""
from __future__ import annotations

import socket
import threading
import time
from contextlib import contextmanager
from typing import Iterator

import uvicorn


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextmanager
def running(app) -> Iterator[str]:
    """Serve ``app``; yields ``http://127.0.0.1:PORT``."""
    port = free_port()
    server = uvicorn.Server(uvicorn.Config(app, host="127.0.0.1", port=port, log_level="warning", lifespan="off"))
    thread = threading.Thread(target=server.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not server.started:
        if time.monotonic() > deadline or not thread.is_alive():
            raise RuntimeError("uvicorn did not start")
        time.sleep(0.05)
    try:
        yield f"http://127.0.0.1:{port}"
    finally:
        server.should_exit = True
        thread.join(10)


def face_for_tests():
    """The generic head when it is built (ARKit units: the mouth moves), else the procedural head (no units)."""
    from mpeg4fa.face import FaceModel, asset

    if asset.is_installed():
        return FaceModel.default(auto_install=False)
    from procedural_head import build_procedural_head

    return FaceModel(build_procedural_head())
