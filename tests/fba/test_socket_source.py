"""iter_decode on a live socket read through an ordinarily buffered file (``sock.makefile('rb')``).

A buffered file's ``read(n)`` waits until ``n`` bytes have come or the peer closes; the decoder
asked for 64 KiB at a time, so a live stream of a few hundred bytes a second decoded nothing
until the sender hung up. Here the sender sends all but the end code and keeps the socket open:
the frames must come out while it waits, on both backends: the reference decodes every plane
whose bits are in; the compiled path decodes a P plane only once a worst-case margin of bits has
arrived after it (about 100 bytes for this stream), so it holds the last frames back until more
data or the end code comes.
"""
from __future__ import annotations

import queue
import socket
import threading

import pytest

from mpeg4fa.fba import demo_stream, encode, iter_decode

WAIT = 20.0  # s: a generous bound; without the fix the reader blocks for good


def _reader(sock: socket.socket, backend: str, out: queue.Queue) -> None:
    try:
        with sock.makefile("rb") as f:  # default buffering, as anyone would open it
            for frame in iter_decode(f, backend=backend):
                out.put(frame)
        out.put("end")
    except Exception as exc:  # handed to the test
        out.put(exc)


@pytest.mark.parametrize("backend", ["python", "compiled"])
def test_frames_come_out_of_a_buffered_socket_before_it_closes(backend):
    stream = demo_stream(seconds=20.0)
    data = encode(stream)
    before_close = len(stream) - 1 if backend == "python" else len(stream) // 2
    head, tail = data[:-4], data[-4:]  # everything but the end code
    ours, theirs = socket.socketpair()
    got: queue.Queue = queue.Queue()
    thread = threading.Thread(target=_reader, args=(theirs, backend, got), daemon=True)
    thread.start()
    try:
        ours.sendall(head)
        frames = []
        while len(frames) < before_close:  # the last plane waits for what follows it
            item = got.get(timeout=WAIT)
            assert not isinstance(item, (Exception, str)), item
            frames.append(item)
        ours.sendall(tail)
        ours.shutdown(socket.SHUT_WR)
        while (item := got.get(timeout=WAIT)) != "end":
            assert not isinstance(item, Exception), item
            frames.append(item)
    finally:
        ours.close()
        thread.join(timeout=WAIT)
    assert [f.index for f in frames] == list(range(len(stream)))
    assert [f.timestamp for f in frames] == pytest.approx(list(stream.timestamps))
