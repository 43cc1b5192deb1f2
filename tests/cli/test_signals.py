"""SIGTERM and SIGHUP (what `timeout`, `kill` and a closed terminal send) clean up as Ctrl-C does.

Each long command runs in a process of its own, with an earlier output at its target; once
it is at work (its temporary output has appeared, or espeak-ng is loaded) it gets the signal.
It must exit with 128 + the signal after one line, leave no ``.NAME.partial-*`` file and
leave the earlier output byte for byte as it was.
"""
from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mpeg4fa.atomic import PARTIAL_MARK
from mpeg4fa.fba import demo_stream, encode

ROOT = Path(__file__).resolve().parents[2]
SIGNALS = [signal.SIGTERM, signal.SIGHUP]
EARLIER = b"an earlier output that must survive\n"


def _partials(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if PARTIAL_MARK in p.name)


def _start(folder: Path, *argv: str) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "mpeg4fa.cli", *argv], cwd=folder, stdin=subprocess.DEVNULL,
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONPATH": str(ROOT)})


def _wait_for(proc: subprocess.Popen, ready, what: str, timeout: float = 90.0) -> None:
    """Poll (no fixed sleep) until ``ready()``; fail if the command ends first."""
    deadline = time.monotonic() + timeout
    while not ready():
        if proc.poll() is not None:
            pytest.fail(f"the command ended (status {proc.returncode}) before {what}: {proc.stderr.read()}")
        if time.monotonic() > deadline:
            proc.kill()
            pytest.fail(f"no {what} after {timeout:.0f} s")
        time.sleep(0.02)


def _stop(proc: subprocess.Popen, signum: int) -> str:
    proc.send_signal(signum)
    try:
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    return err


def _check_stopped(proc: subprocess.Popen, err: str, command: str, signum: int, folder: Path, *earlier: Path) -> None:
    name = signal.Signals(signum).name
    assert proc.returncode == 1, err
    assert "Traceback" not in err and err.strip().splitlines()[-1] == f"mpeg4fa {command}: terminated ({name})", err
    assert _partials(folder) == []
    for path in earlier:
        assert path.read_bytes() == EARLIER, path


def _long_text(sentences: int) -> str:
    rng = random.Random(26)
    words = "the quick brown fox jumps over a lazy dog while seven engineers measure every signal".split()
    return ". ".join(" ".join(rng.choice(words) for _ in range(12)) for _ in range(sentences)) + "."


@pytest.mark.usefixtures("generic_head_installed")
@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_play_to_mp4(tmp_path, signum):
    (tmp_path / "long.fba").write_bytes(encode(demo_stream(seconds=1200.0)))  # 30,000 frames: minutes to render
    out = tmp_path / "out.mp4"
    out.write_bytes(EARLIER)
    proc = _start(tmp_path, "play", "long.fba", "-o", "out.mp4", "--size", "32", "--no-audio")
    _wait_for(proc, lambda: _partials(tmp_path), "partial MP4")
    _check_stopped(proc, _stop(proc, signum), "play", signum, tmp_path, out)


@pytest.mark.usefixtures("generic_head_installed")
@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_say_while_rendering(tmp_path, signum):
    (tmp_path / "long.txt").write_text(_long_text(40), encoding="utf-8")  # about 2.5 minutes of speech
    out = tmp_path / "out.mp4"
    out.write_bytes(EARLIER)
    proc = _start(tmp_path, "say", "@long.txt", "-o", "out.mp4", "--size", "32", "--aa", "0")
    _wait_for(proc, lambda: _partials(tmp_path), "partial MP4")
    _check_stopped(proc, _stop(proc, signum), "say", signum, tmp_path, out)


@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_encode_while_espeak_speaks(tmp_path, signum):
    """The signal lands in espeak-ng's callbacks (C calling Python), where an exception would be lost."""
    (tmp_path / "long.txt").write_text(_long_text(400), encoding="utf-8")  # seconds of synthesis
    outputs = [tmp_path / "out.fba", tmp_path / "out.wav"]
    for path in outputs:
        path.write_bytes(EARLIER)
    proc = _start(tmp_path, "encode", "@long.txt", "-o", "out.fba", "--audio", "out.wav")
    maps = Path(f"/proc/{proc.pid}/maps")
    _wait_for(proc, lambda: maps.exists() and "espeak" in maps.read_text(errors="replace"), "espeak-ng loaded")
    started = time.monotonic()
    err = _stop(proc, signum)
    assert time.monotonic() - started < 5.0, "the signal waited for the synthesis to end"
    _check_stopped(proc, err, "encode", signum, tmp_path, *outputs)


def test_a_signal_the_process_ignores_stays_ignored(tmp_path):
    """Under nohup (SIGHUP ignored) the command outlives a hang-up and finishes its output."""
    out = tmp_path / "demo.fba"
    proc = subprocess.Popen([sys.executable, "-c",
                             "import os, signal, sys; signal.signal(signal.SIGHUP, signal.SIG_IGN);"
                             "from mpeg4fa.cli import main; os.kill(os.getpid(), signal.SIGHUP);"
                             "sys.exit(main(sys.argv[1:]))", "demo", "-o", str(out)],
                            cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert out.stat().st_size > 0 and _partials(tmp_path) == []


@pytest.mark.parametrize("signum", SIGNALS, ids=lambda s: signal.Signals(s).name)
def test_the_editor_server_stops_cleanly(tmp_path, signum):
    """uvicorn handles SIGTERM itself (and swallowed the exit status); SIGHUP used to cut its loop mid-step."""
    import socket

    import trimesh

    trimesh.creation.icosphere(1).export(tmp_path / "ball.obj")
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    proc = _start(tmp_path, "edit", "ball.obj", "--port", str(port), "--no-browser", "--out", str(tmp_path))

    def listening() -> bool:
        try:
            socket.create_connection(("127.0.0.1", port), timeout=0.5).close()
            return True
        except OSError:
            return False
    _wait_for(proc, listening, "server listening")
    err = _stop(proc, signum)
    assert proc.returncode == 1, err
    assert "Traceback" not in err and err.strip().splitlines()[-1] == \
        f"mpeg4fa edit: terminated ({signal.Signals(signum).name})", err


@pytest.mark.usefixtures("generic_head_installed")
def test_batch_removes_what_its_workers_left(tmp_path):
    """The local cluster's workers die with the batch (or with the process group, as `timeout` kills it) and
    cannot clean up: the batch removes their temporaries once the cluster is closed."""
    (tmp_path / "long.fba").write_bytes(encode(demo_stream(seconds=1200.0)))
    (tmp_path / "jobs.json").write_text('{"defaults": {"size": "32x32"}, "jobs": [{"stream": "long.fba"}]}')
    out = tmp_path / "out"
    out.mkdir()
    (out / "long.mp4").write_bytes(EARLIER)
    proc = _start(tmp_path, "batch", "jobs.json", "-o", "out", "--workers", "1", "--force")
    _wait_for(proc, lambda: _partials(out), "partial MP4")
    _check_stopped(proc, _stop(proc, signal.SIGTERM), "batch", signal.SIGTERM, out, out / "long.mp4")
