"""Bad command lines: one error line, the right exit status, no traceback, and nothing lost or left behind.

Exit status: 1 for bad input (any layer's error, a missing file), 2 for option values and
options that do not go together (argparse's and UsageError), 1 for Ctrl-C as for any other stop. After a
failure no output exists (not even a temporary); an input the command refused to
overwrite is byte-identical.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import pytest

from mpeg4fa.atomic import PARTIAL_MARK
from mpeg4fa.cli import main
from mpeg4fa.fba import demo_stream, encode

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture
def stream(tmp_path):
    path = tmp_path / "talk.fba"
    path.write_bytes(encode(demo_stream()))
    return path


def usage(capsys, *argv) -> str:
    """Run a command line argparse or UsageError must refuse; its stderr."""
    try:
        code = main([str(a) for a in argv])
    except SystemExit as exc:
        code = exc.code
    err = capsys.readouterr().err
    assert code == 2, err
    assert "Traceback" not in err and err.strip().splitlines()[-1].startswith("mpeg4fa ")
    return err


def nothing_written(folder: Path, *keep: Path) -> None:
    left = sorted(p.name for p in folder.iterdir() if p not in keep)
    assert left == [], left


# -- option values: argparse types, exit 2 -----------------------------------------------------------------

@pytest.mark.parametrize("value, said", [("-5", "not a positive"), ("nan", "finite"), ("1e400", "finite"),
                                         ("300", "bitstream"), ("0", "not a positive"), ("x", "not a number")])
@pytest.mark.parametrize("command", ["encode", "say", "play"])
def test_fps_is_finite_and_what_the_bitstream_carries(capsys, tmp_path, stream, command, value, said):
    first = {"encode": "Hello", "say": "Hello", "play": stream}[command]
    err = usage(capsys, command, first, "-o", tmp_path / "out.mp4", f"--fps={value}")
    assert "--fps" in err and said in err
    nothing_written(tmp_path, stream)


@pytest.mark.parametrize("argv, said", [
    (["encode", "{stream}", "--intra-period", "-3"], "--intra-period"),
    (["encode", "{stream}", "--intra-period", "2.5"], "whole number"),
    (["encode", "{stream}", "--quant", "32"], "--quant"),
    (["encode", "{stream}", "--quant", "-1"], "--quant"),
    (["encode", "{stream}", "--bap-quant", "99"], "--bap-quant"),
    (["encode", "{stream}", "--mask-types", "1,2"], "--mask-types"),
    (["encode", "Hello", "--rate", "5"], "--rate"),
    (["encode", "Hello", "--rate", "1e9"], "--rate"),
    (["say", "Hello", "--rate", "0"], "--rate"),
    (["say", "Hello", "--size", "0"], "--size"),
    (["say", "Hello", "--size", "9000"], "--size"),
    (["say", "Hello", "--aa", "-1"], "--aa"),
    (["say", "Hello", "--aa", "99"], "--aa"),
    (["play", "{stream}", "--size", "big"], "--size"),
    (["play", "{stream}", "--aa", "nan"], "--aa"),
    (["play", "{stream}", "--crf", "52"], "--crf"),
    (["snapshot", "{stream}", "--frame", "1.5"], "--frame"),
    (["snapshot", "{stream}", "--time", "-1"], "--time"),
    (["snapshot", "{stream}", "--time", "inf"], "--time"),
    (["snapshot", "{stream}", "--frame", "1", "--time", "1"], "not allowed"),
    (["texture", "{stream}", "--points", "p.json", "--size", "8"], "--size"),
])
def test_numeric_options_are_checked(capsys, tmp_path, stream, argv, said):
    argv = [a.replace("{stream}", str(stream)) for a in argv] + ["-o", str(tmp_path / "out.png")]
    assert said in usage(capsys, *argv)
    nothing_written(tmp_path, stream)


@pytest.mark.parametrize("argv, said", [(["--fap", "3=nan"], "finite"), (["--fap", "3=1e400"], "finite"),
                                        (["--fap", "99=1"], "3..68"), (["--expression", "joy=64"], "0..63"),
                                        (["--expression", "joy=x"], "whole number")])
def test_model_pose_values_are_checked(capsys, argv, said):
    assert said in usage(capsys, "model", "pose", *argv)


# -- options that do not go together: UsageError, exit 2 in every command -----------------------------------

def test_clashes_exit_2_everywhere(capsys, tmp_path, stream):
    assert "say where the frames go" in usage(capsys, "play", stream)
    assert "go together" in usage(capsys, "texture", stream, "--points", "p.json", "--side", stream,
                                  "-o", tmp_path / "s.png")
    assert "no audio" in usage(capsys, "encode", "Hi", "-o", tmp_path / "a.fba", "--engine", "estimate",
                               "--audio", tmp_path / "a.wav")
    assert "apply to text input" in usage(capsys, "encode", stream, "-o", tmp_path / "a.fba", "--timings",
                                          tmp_path / "t.json")
    assert "both describe the face" in usage(capsys, "encode", "Hi", "-o", tmp_path / "a.fba", "--fdp-out",
                                             tmp_path / "f.fdp", "--face-mesh", "m.obj", "--front", "f.png")
    assert "odd" in usage(capsys, "say", "Hi", "-o", tmp_path / "a.mp4", "--size", "33")
    nothing_written(tmp_path, stream)


# -- an -o of another kind of file: refused before any work, saying what to run instead -----------------------

@pytest.mark.parametrize("command, name, said", [
    ("say", "s.wav", "encode TEXT -o {tmp}/s.fba --audio {tmp}/s.wav"),  # was: a folder of PNGs called s.wav
    ("say", "s.FBA", "encode TEXT -o {tmp}/s.fba"),
    ("say", "s.json", "--timings {tmp}/s.json"),
    ("say", "s.png", "-o {tmp}/s/ for a folder of PNG frames"),
    ("play", "s.png", "snapshot STREAM -o {tmp}/s.png"),
    ("play", "s.wav", "use -o {tmp}/s.mp4"),
    ("play", "s.fap", "decode STREAM -o {tmp}/s.fap"),
    ("play", "s.mkv", ".mkv video is not supported"),
    ("snapshot", "s.mp4", "play STREAM -o {tmp}/s.mp4"),
    ("snapshot", "s.wav", "name it {tmp}/s.png"),
    ("snapshot", "s", "no image suffix"),
])
def test_an_output_of_another_kind_is_a_usage_error(capsys, tmp_path, stream, command, name, said):
    first = {"say": "Hello", "play": stream, "snapshot": stream}[command]
    err = usage(capsys, command, first, "-o", tmp_path / name, "--size", "32")
    assert f"-o {tmp_path / name}" in err and said.format(tmp=tmp_path) in err and err.count("\n") == 1
    nothing_written(tmp_path, stream)


def test_an_existing_folder_with_a_suffix_still_takes_png_frames(cli, tmp_path, stream):
    frames = tmp_path / "take.png"
    frames.mkdir()
    code, out, err = cli("play", stream, "-o", frames, "--size", "32", "--no-audio")
    assert code == 0, err
    assert len(list(frames.glob("frame_*.png"))) == len(demo_stream())


# -- an output that is an input or another output: refused, the input untouched ----------------------------

def test_outputs_that_are_inputs_or_each_other_are_refused(capsys, tmp_path, stream):
    original = stream.read_bytes()
    script = tmp_path / "script.txt"
    script.write_text("Hello there.", encoding="utf-8")
    wav = tmp_path / "x.wav"
    wav.write_bytes(b"RIFF")
    photo, points = tmp_path / "photo.png", tmp_path / "p.json"
    photo.write_bytes(b"png")
    points.write_text("{}")
    link = tmp_path / "again.fba"
    os.link(stream, link)  # a hard link is the same file under another name
    refused = [
        (["decode", stream, "-o", stream], "-o"),
        (["encode", stream, "-o", stream, "--quant", "5"], "-o"),
        (["encode", stream, "-o", link], "-o"),
        (["encode", stream, "-o", tmp_path / "sub" / ".." / "talk.fba"], "-o"),
        (["encode", "Hello", "-o", tmp_path / "a.fba", "--audio", tmp_path / "a.fba"], "--audio"),
        (["encode", "Hello", "-o", tmp_path / "a.fba", "--timings", tmp_path / "a.fba"], "--timings"),
        (["encode", "Hello", "-o", tmp_path / "a.fba", "--fdp-out", tmp_path / "a.fba"], "--fdp-out"),
        (["encode", script, "-o", script], "-o"),
        (["play", stream, "-o", wav, "--audio", wav], "-o"),
        (["play", stream, "-o", tmp_path / "a.mp4", "--fdp", tmp_path / "a.mp4"], "-o"),
        (["snapshot", stream, "-o", stream], "-o"),
        (["texture", photo, "--points", points, "-o", photo], "-o"),
        (["texture", photo, "--points", points, "-o", points], "-o"),
        (["texture", photo, "--points", points, "-o", tmp_path / "s.png", "--preview", tmp_path / "s.png"],
         "--preview"),
        (["say", script, "-o", script], "-o"),
        (["say", wav, "-o", tmp_path / "x.mp4", "--keep"], "--keep"),
    ]
    for argv, label in refused:
        err = usage(capsys, *argv)
        assert label in err and ("same file" in err or "overwritten" in err), err
    assert stream.read_bytes() == original and wav.read_bytes() == b"RIFF"
    assert script.read_text(encoding="utf-8") == "Hello there." and photo.read_bytes() == b"png"
    nothing_written(tmp_path, stream, script, wav, photo, points, link)


# -- a path-like argument that names no readable file: an error, never speech ---------------------------------

@pytest.mark.parametrize("command", ["encode", "say"])
@pytest.mark.parametrize("arg, said", [("missing.txt", "no such file"), ("talk.fap", "no such file"),
                                       ("notes/today", "no such file"), ("{dir}", "is a directory"),
                                       ("/dev/urandom", "device"), ("@missing.txt", "no such file")])
def test_a_path_like_argument_must_name_a_readable_file(cli, tmp_path, monkeypatch, command, arg, said):
    monkeypatch.chdir(tmp_path)
    arg = arg.replace("{dir}", str(tmp_path))
    code, _, err = cli(command, arg, "-o", tmp_path / "out.mp4", "--engine", "estimate")
    assert code == 1 and said in err and len(err.strip().splitlines()) == 1, err
    assert arg.lstrip("@") in err and ("--text" in err) != arg.startswith("@")
    nothing_written(tmp_path)


def test_text_stays_text_and_text_forces_it(cli, tmp_path):
    for argv in (["Hello there"], ["Hello"], ["3.14"], ["x.txt", "--text"], ["notes/today", "--text"]):
        out = tmp_path / "a.fba"
        code, _, err = cli("encode", *argv, "-o", out, "--engine", "estimate")
        assert code == 0 and out.stat().st_size > 0, (argv, err)
        assert "<text>" in err
        out.unlink()


def test_a_text_file_that_is_not_utf8_is_located(cli, tmp_path):
    bad = tmp_path / "bad.txt"
    bad.write_bytes(b"Hello\nthere \xff")
    code, _, err = cli("encode", bad, "-o", tmp_path / "a.fba", "--engine", "estimate")
    assert code == 1 and "bad.txt:2:7" in err and "UTF-8" in err
    nothing_written(tmp_path, bad)


# -- text in a script no voice speaks ------------------------------------------------------------------------

@pytest.mark.parametrize("text, script", [("مرحبا", "Arabic"), ("שלום", "Hebrew"), ("안녕", "Hangul"),
                                          ("こんにちは", "Hiragana"), ("สวัสดี", "Thai"), ("नमस्ते", "Devanagari"),
                                          ("Привет мир", "Cyrillic"), ("Γειά σου", "Greek")])
def test_unspoken_scripts_are_an_error_naming_them(cli, tmp_path, text, script):
    code, _, err = cli("encode", text, "-o", tmp_path / "a.fba", "--engine", "estimate")
    assert code == 1 and f"<text>:1:1: cannot speak {script} text: {text!r}" in err
    assert len(err.strip().splitlines()) == 1
    nothing_written(tmp_path)


# -- nothing left behind: failures and Ctrl-C -----------------------------------------------------------------

def test_ctrl_c_exits_1_and_leaves_no_partial_output(cli, tmp_path, stream, monkeypatch):
    import mpeg4fa.cli.codec as codec

    def interrupted(s, path, **kwargs):
        Path(path).write_text("2.1 half")
        raise KeyboardInterrupt

    monkeypatch.setattr(codec, "write_fap", interrupted)
    code, _, err = cli("decode", stream, "-o", tmp_path / "talk.fap")
    assert code == 1 and "interrupted" in err and "Traceback" not in err
    nothing_written(tmp_path, stream)


def test_an_unwritable_output_is_one_line_and_writes_nothing(cli, tmp_path):
    code, _, err = cli("encode", "Hello", "-o", tmp_path / "a.fba", "--audio", tmp_path / "no" / "a.wav")
    assert code == 1 and len(err.strip().splitlines()) == 1 and str(tmp_path / "no" / "a.wav") in err
    assert PARTIAL_MARK not in err
    nothing_written(tmp_path)  # the stream is not left behind without its audio


@pytest.mark.usefixtures("generic_head_installed")
@pytest.mark.parametrize("name", ["talk.mp4", "frames"])
def test_a_failing_play_leaves_no_video_and_no_frames(cli, tmp_path, stream, monkeypatch, name):
    from mpeg4fa.render import RenderError
    from mpeg4fa.render.renderer import Renderer

    calls = []
    real = Renderer.render

    def failing(self, *args, **kwargs):
        calls.append(1)
        if len(calls) > 2:
            raise RenderError("lost the context", where="renderer")
        return real(self, *args, **kwargs)

    monkeypatch.setattr(Renderer, "render", failing)
    code, _, err = cli("play", stream, "-o", tmp_path / name, "--size", "32", "--no-audio")
    assert code == 1 and "lost the context" in err
    nothing_written(tmp_path, stream)


# -- warnings: one line whatever their origin ----------------------------------------------------------------

def test_any_warning_is_one_line(cli, stream, monkeypatch):
    import mpeg4fa.cli.codec as codec

    real = codec.describe

    def noisy(*args, **kwargs):
        warnings.warn("a third-party library\nsays something", UserWarning)
        warnings.warn("and again", RuntimeWarning)
        return real(*args, **kwargs)

    monkeypatch.setattr(codec, "describe", noisy)
    code, _, err = cli("info", stream)
    assert code == 0
    assert err.splitlines() == ["mpeg4fa info: warning: a third-party library says something",
                                "mpeg4fa info: warning: and again"]


# -- through a real process: no traceback text, the right status ---------------------------------------------

def run(*argv, **kwargs) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mpeg4fa.cli", *map(str, argv)], capture_output=True, text=True,
                          cwd=kwargs.pop("cwd", ROOT), timeout=120, **kwargs)


def test_in_a_process_no_traceback_reaches_the_user(tmp_path, stream):
    cases = [
        (["encode", "Hello", "-o", tmp_path / "a.fba", "--fps", "nan"], 2),
        (["decode", stream, "-o", stream], 2),
        (["encode", "missing.txt", "-o", tmp_path / "a.fba"], 1),
        (["encode", "Привет", "-o", tmp_path / "a.fba", "--engine", "estimate"], 1),
        (["encode", "Hello", "-o", tmp_path / "a.fba", "--audio", tmp_path / "no" / "a.wav"], 1),
    ]
    for argv, status in cases:
        done = run(*argv)
        assert done.returncode == status, (argv, done.stderr)
        assert "Traceback" not in done.stderr and "Exception ignored" not in done.stderr, done.stderr
        assert done.stderr.strip().splitlines()[-1].startswith("mpeg4fa "), done.stderr
    nothing_written(tmp_path, stream)


def test_in_a_process_ctrl_c_exits_130_without_traceback(tmp_path):
    out = tmp_path / "a.fba"
    proc = subprocess.Popen([sys.executable, "-m", "mpeg4fa.cli", "encode", "-", "-o", str(out), "--engine",
                             "estimate"], stdin=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=ROOT)
    try:
        _wait_until_blocked(proc.pid)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 1 and "Traceback" not in err and "interrupted" in err, err
    nothing_written(tmp_path)


def _wait_until_blocked(pid: int, timeout: float = 60.0) -> None:
    """Until the process sleeps without using CPU (imports done, reading standard input)."""
    stat = Path(f"/proc/{pid}/stat")
    if not stat.exists():
        pytest.skip("needs /proc to see when the process waits")
    still, last, start = 0, None, time.monotonic()
    while time.monotonic() - start < timeout:
        fields = stat.read_text().rsplit(")", 1)[1].split()
        state, cpu = fields[0], int(fields[11]) + int(fields[12])
        still = still + 1 if state == "S" and cpu == last else 0
        if still >= 10:  # a full second asleep: a pause in the imports is shorter
            return
        last = cpu
        time.sleep(0.1)
    pytest.fail("the command never waited for its input")
