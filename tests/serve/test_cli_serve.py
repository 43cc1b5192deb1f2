"""``mpeg4fa serve`` as a user runs it: a process on a free port, a client that says a sentence, Ctrl-C."""
from __future__ import annotations

import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mpeg4fa.serve.client import play
from serve.live_server import free_port

MPEG4FA = [sys.executable, "-m", "mpeg4fa.cli"]


def wait_for_port(port: int, seconds: float = 20.0) -> None:
    deadline = time.monotonic() + seconds
    while True:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=1).close()
            return
        except OSError:
            assert time.monotonic() < deadline, f"nothing listens on {port}"
            time.sleep(0.1)


@pytest.mark.usefixtures("generic_head_installed")  # the command serves the generic head
def test_serve_command_speaks_to_a_client():
    port = free_port()
    proc = subprocess.Popen([*MPEG4FA, "serve", "--port", str(port), "--no-browser", "--window", "1.5"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            cwd=Path(__file__).resolve().parents[2])
    try:
        line = proc.stdout.readline()  # printed once the head and the engine are ready
        assert f"serving http://127.0.0.1:{port}/" in line, (line, proc.stderr.read() if proc.poll() else "")
        assert f"http://127.0.0.1:{port}/player" in line
        wait_for_port(port)
        played = play(f"ws://127.0.0.1:{port}/ws", "Hello from the command line.", speed=4.0)
        assert played.done and not played.errors and played.hello["window"] == 1.5
        assert played.frames > 10 and played.audio_seconds > 1.0
    finally:
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(20)
        except subprocess.TimeoutExpired:
            proc.kill()
    assert proc.returncode == 1  # stopped by a signal, as every command: one line, exit 1


def test_serve_refuses_a_port_in_use(cli):
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        code, out, err = cli("serve", "--port", port, "--no-browser")
    assert code == 1 and err.count("\n") == 1
    assert f"port {port} on 127.0.0.1" in err and "in use" in err


def test_serve_help(cli):
    with pytest.raises(SystemExit) as exit_:
        cli("serve", "--help")
    assert exit_.value.code == 0


def test_a_client_text_frame_that_is_not_utf8_is_one_console_line():
    """Fuzz of 2026-12-07: each such frame put uvicorn's own UnicodeDecodeError traceback on the server's console
    (the client is closed with 1007 and the server goes on): any client could fill the console at will."""
    import logging
    import sys

    from mpeg4fa.cli.local_server import _ClientFaultsInOneLine

    try:
        b"\xff".decode()
    except UnicodeDecodeError:
        info = sys.exc_info()
    keep = _ClientFaultsInOneLine()
    fault = logging.LogRecord("uvicorn.error", logging.ERROR, __file__, 1,
                              "Invalid UTF-8 sequence received from client.", None, info)
    ours = logging.LogRecord("uvicorn.error", logging.ERROR, __file__, 1, "Exception in ASGI application", None, info)
    assert keep.filter(fault) and fault.exc_info is None
    assert keep.filter(ours) and ours.exc_info is info  # a fault of the server's own keeps its traceback
