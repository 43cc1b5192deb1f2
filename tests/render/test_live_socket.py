"""play_live on a real loopback socket opened with ``makefile('rb')`` (default buffering).

The sender writes a stream frame by frame at its own pace and keeps the connection open while
the player shows what has come; before the bit reader took what had arrived (``read1``) the
player saw nothing and raised "source stalled" after ``stall_timeout``.
"""
from __future__ import annotations

import socket
import threading
import time

from mpeg4fa.fba import demo_stream, encode, iter_decode
from mpeg4fa.render import Renderer, play_live
from mpeg4fa.render.realtime import LiveStats

SIZE = {"width": 48, "height": 48}


def _send_slowly(server: socket.socket, data: bytes, release: threading.Event) -> None:
    conn, _ = server.accept()
    with conn:
        body, end = data[:-4], data[-4:]
        step = max(1, len(body) // 20)
        for i in range(0, len(body), step):  # a live sender: a little at a time
            conn.sendall(body[i:i + step])
            time.sleep(0.01)
        release.wait(10.0)  # held open until the player has shown the frames sent so far
        conn.sendall(end)


def test_play_live_on_a_buffered_socket_file(procedural_face):
    stream = demo_stream(seconds=1.0)
    data = encode(stream)
    release = threading.Event()
    with socket.create_server(("127.0.0.1", 0)) as server:
        sender = threading.Thread(target=_send_slowly, args=(server, data, release), daemon=True)
        sender.start()
        stats = LiveStats()
        with socket.create_connection(server.getsockname()) as sock, sock.makefile("rb") as f, \
                Renderer(procedural_face, **SIZE) as renderer:
            shown = []
            for frame in play_live(iter_decode(f, backend="python"), renderer, stall_timeout=5.0, stats=stats):
                shown.append(frame)
                if frame.index >= len(stream) - 2:  # all but the last came while the socket was open
                    release.set()
        sender.join(5.0)
    assert stats.stalls == 0 and stats.received == len(stream)
    assert shown[-1].index == len(stream) - 1
