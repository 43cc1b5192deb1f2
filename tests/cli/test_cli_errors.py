"""Issue 26 item 6: one line for a bad option value (no usage dump), OS errors that name their file and
say what to do, no doubled prefixes, option values checked against what the code can do, and text on
standard input read as bytes whatever the locale."""
from __future__ import annotations

import errno
import os
import subprocess
import sys
from pathlib import Path

import pytest

from mpeg4fa.atomic import PARTIAL_MARK
from mpeg4fa.cli import codec, main
from mpeg4fa.errors import MpegFaError
from mpeg4fa.fba import demo_stream, encode

ROOT = Path(__file__).resolve().parents[2]


def _argparse_error(capsys, *argv) -> str:
    """Run a command line that argparse must refuse; its stderr (exit status 2 checked)."""
    with pytest.raises(SystemExit) as info:
        main([str(a) for a in argv])
    assert info.value.code == 2
    return capsys.readouterr().err


@pytest.fixture
def demo(tmp_path) -> Path:
    path = tmp_path / "d.fba"
    path.write_bytes(encode(demo_stream()))
    return path


BAD_VALUES = [  # (command line, option, what the line must say)
    (["play", "D", "-o", "x.mp4", "--fps", "0"], "--fps", "1/16 to 255 15/16"),
    (["play", "D", "-o", "x.mp4", "--fps", "1e308"], "--fps", "more than the bitstream can carry"),
    (["export", "D", "-o", "x.json", "--fps", "nan"], "--fps", "not a finite number"),
    (["encode", "D", "-o", "x.fba", "--fps", "1e308"], "--fps", "255 15/16"),
    (["play", "D", "-o", "x.mp4", "--size", "0x0"], "--size", "16..8192"),
    (["play", "D", "-o", "x.mp4", "--size", "1e308"], "--size", "expected W or WxH"),
    (["play", "D", "-o", "x.mp4", "--crf", "nan"], "--crf", "0..51"),
    (["snapshot", "D", "-o", "x.png", "--aa", "3"], "--aa", "0, 1, 2, 4, 8 or 16"),
    (["snapshot", "D", "-o", "x.png", "--aa", "1e308"], "--aa", "0, 1, 2, 4, 8 or 16"),
    (["snapshot", "D", "-o", "x.png", "--time", "1e308"], "--time", "0..86400"),
    (["snapshot", "D", "-o", "x.png", "--frame", "9" * 30], "--frame", "out of range"),
    (["snapshot", "D", "-o", "x.png", "--frame", "9" * 5000], "--frame", "out of range"),
    (["encode", "D", "-o", "x.fba", "--intra-period", "99999999999999999999"], "--intra-period", "0..22118400"),
    (["encode", "D", "-o", "x.fba", "--quant", "32"], "--quant", "0..31"),
    (["encode", "D", "-o", "x.fba", "--bap-quant", "-1"], "--bap-quant", "0..31"),
    (["say", "hi", "-o", "x.mp4", "--rate", "1e308"], "--rate", "80..450"),
    (["say", "hi", "-o", "x.mp4", "--aa", "5"], "--aa", "0, 1, 2, 4, 8 or 16"),
    (["texture", "D", "--points", "p.json", "-o", "t.png", "--size", "99999"], "--size", "16..8192"),
    (["serve", "--port", "70000"], "--port", "1..65535"),
    (["serve", "--window", "1e308"], "--window", "0.2..60"),
    (["edit", "--port", "0"], "--port", "1..65535"),
    (["batch", "m.json", "-o", "out", "--workers", "0"], "--workers", "1..1024"),
    (["conform", "--timeout", "1e308"], "--timeout", "0.1..3600"),
    (["model", "pose", "--expression", "joy=1e308"], "--expression", "whole number"),
]


@pytest.mark.parametrize("argv, option, said", BAD_VALUES,
                         ids=lambda v: " ".join(v)[:60] if isinstance(v, list) else None)
def test_a_bad_option_value_is_one_line_without_the_usage(capsys, demo, argv, option, said):
    argv = [str(demo) if a == "D" else a for a in argv]
    err = _argparse_error(capsys, *argv)
    command = " ".join(argv[:2]) if argv[0] == "model" else argv[0]
    assert err.count("\n") == 1 and "usage:" not in err and "Traceback" not in err, err
    assert err.startswith(f"mpeg4fa {command}: error: argument {option}"), err
    assert said in err, err


def test_a_missing_argument_is_one_line_too(capsys):
    err = _argparse_error(capsys, "play")
    assert err == "mpeg4fa play: error: the following arguments are required: stream\n"


def test_help_still_shows_the_usage_and_the_allowed_values(capsys):
    with pytest.raises(SystemExit) as info:
        main(["snapshot", "--help"])
    out = capsys.readouterr().out
    assert info.value.code == 0 and out.startswith("usage: mpeg4fa snapshot")
    assert "0 (off; default, fastest), 1, 2, 4, 8 or 16" in " ".join(out.split())


def test_writing_into_a_missing_folder_names_the_file_and_what_to_do(cli, demo, tmp_path):
    target = tmp_path / "nodir" / "x.fap"
    code, _, err = cli("decode", demo, "-o", target)
    assert code == 1 and err.count("\n") == 1, err
    assert err == (f"mpeg4fa decode: error: cannot write {target}: No such file or directory "
                   f"(the folder {target.parent} does not exist: create it first)\n")


def test_a_full_disk_names_the_file_in_process(cli, demo, tmp_path, monkeypatch):
    """write() on a full disk raises an OSError with no file name: the message used to be the bare strerror."""
    def full(stream, path, **kwargs):
        with open(path, "wb") as handle:
            handle.write(b"2.1 half")
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))  # as handle.write() raises it: no filename

    monkeypatch.setattr(codec, "write_fap", full)
    target = tmp_path / "x.fap"
    target.write_bytes(b"earlier")
    code, _, err = cli("decode", demo, "-o", target)
    assert code == 1 and err == (f"mpeg4fa decode: error: cannot write {target}: No space left on device "
                                 "(the disk is full: free some space or write elsewhere)\n"), err
    assert target.read_bytes() == b"earlier" and not [p for p in tmp_path.iterdir() if PARTIAL_MARK in p.name]


@pytest.fixture
def tiny_disk(tmp_path):
    """A 16 KiB tmpfs (root only: skipped where mounting is not permitted)."""
    mount = tmp_path / "tiny"
    mount.mkdir()
    try:
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=16k", "tmpfs", str(mount)], capture_output=True)
    except OSError:
        pytest.skip("no mount command")
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode(errors='replace').strip()}")
    try:
        yield mount
    finally:
        subprocess.run(["umount", str(mount)], capture_output=True)


def test_a_full_disk_names_the_file_for_real(tiny_disk, tmp_path):
    stream = tmp_path / "long.fba"
    stream.write_bytes(encode(demo_stream(seconds=60.0)))  # its .fap text is far more than 16 KiB
    target = tiny_disk / "x.fap"
    target.write_bytes(b"earlier")
    done = subprocess.run([sys.executable, "-m", "mpeg4fa.cli", "decode", str(stream), "-o", str(target)],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 1 and done.stderr == (
        f"mpeg4fa decode: error: cannot write {target}: No space left on device "
        "(the disk is full: free some space or write elsewhere)\n"), done.stderr
    assert target.read_bytes() == b"earlier" and sorted(p.name for p in tiny_disk.iterdir()) == ["x.fap"]


@pytest.mark.usefixtures("generic_head_installed")
@pytest.mark.parametrize("where, said", [(["--frame", "999"], "frame 999 is outside the stream"),
                                         (["--time", "99"], "time 99.0 s is outside the stream")])
def test_snapshot_says_its_name_once(cli, demo, tmp_path, where, said):
    code, _, err = cli("snapshot", demo, *where, "-o", tmp_path / "x.png", "--size", "32")
    assert code == 1 and err.count("\n") == 1 and err.count("snapshot") == 1 and said in err, err


@pytest.mark.usefixtures("generic_head_installed")
def test_snapshot_more_samples_than_the_context_allows_is_one_line(cli, demo, tmp_path):
    from mpeg4fa.render.context import gl_context

    if gl_context().max_samples >= 16:
        pytest.skip("this GL context takes 16 samples")
    code, _, err = cli("snapshot", demo, "--aa", "16", "-o", tmp_path / "x.png", "--size", "32")
    assert code == 1 and err.count("\n") == 1 and "16 samples" in err and "one of 0, 1, 2" in err, err


def test_the_renderer_refuses_what_opengl_cannot_take(procedural_face):
    from mpeg4fa.render import RenderError, Renderer

    for samples in (3, 2.5, 1e308, -1, "4"):
        with pytest.raises(RenderError, match="anti-aliasing samples") as info:
            Renderer(procedural_face, width=32, height=32, samples=samples)
        assert "0, 1, 2, 4, 8 or 16" in str(info.value)


def test_the_library_refuses_an_absurd_frame_rate_quickly():
    """encode_text(fps=1e308) made frames for ever; now it is the codec's FbaError (an MpegFaError)."""
    from mpeg4fa.speech.encoder import encode_text

    for fps in (1e308, 1e-300, 256.0):
        with pytest.raises(MpegFaError, match="frame rate"):
            encode_text("hello", fps=fps, engine="estimate")


def test_limits_say_the_range():
    from mpeg4fa.limits import CRF, SAMPLES, LimitError, parse_size

    with pytest.raises(LimitError, match=r"crf 1e\+308 is out of range: give 0\.\.51"):
        CRF.check(1e308)
    with pytest.raises(ValueError):  # a LimitError is a ValueError too
        SAMPLES.check(3)
    assert parse_size("640x480") == (640, 480) and parse_size("64") == (64, 64) and SAMPLES.check(4.0) == 4


def test_the_batch_manifest_does_not_import_the_cli():
    done = subprocess.run([sys.executable, "-c", "import sys, mpeg4fa.batch.manifest; "
                                                 "print(any(m.startswith('mpeg4fa.cli') for m in sys.modules))"],
                          capture_output=True, text=True, cwd=ROOT)
    assert done.stdout.strip() == "False", done.stderr


@pytest.mark.parametrize("env", [{"LC_ALL": "C.UTF-8"}, {"LC_ALL": "C.UTF-8", "PYTHONIOENCODING": "utf-8:strict"},
                                 {"LC_ALL": "C"}], ids=["C.UTF-8", "strict", "C"])
def test_bytes_on_stdin_that_are_not_utf8_are_located(tmp_path, env):
    base = {k: v for k, v in os.environ.items() if k not in ("PYTHONIOENCODING", "LANG", "LC_ALL", "LC_CTYPE")}
    done = subprocess.run([sys.executable, "-m", "mpeg4fa.cli", "encode", "-", "-o", str(tmp_path / "x.fba"),
                           "--engine", "estimate"], input=b"hello\nsay \xff\xfe world", capture_output=True,
                          cwd=ROOT, env={**base, **env})
    err = done.stderr.decode()
    assert done.returncode == 1 and err.count("\n") == 1 and "Traceback" not in err, err
    assert err.startswith("mpeg4fa encode: error: <stdin>:2:5: not UTF-8") and "byte offset 10" in err, err
    assert not (tmp_path / "x.fba").exists()


def test_utf8_on_stdin_is_read_whatever_the_locale(tmp_path):
    base = {k: v for k, v in os.environ.items() if k not in ("PYTHONIOENCODING", "LANG", "LC_ALL", "LC_CTYPE")}
    done = subprocess.run([sys.executable, "-m", "mpeg4fa.cli", "encode", "-", "-o", str(tmp_path / "x.fba"),
                           "--engine", "estimate"], input="Grüße, café".encode(), capture_output=True,
                          cwd=ROOT, env={**base, "LC_ALL": "C"})
    assert done.returncode == 0, done.stderr.decode()


def test_a_subcommand_says_its_full_name(cli):
    code, _, err = cli("model", "pose", "--viseme", "XX")
    assert code == 1 and err.startswith("mpeg4fa model pose: error: unknown viseme 'XX'"), err


def test_validate_of_a_missing_file_is_an_error_naming_it_once(cli, tmp_path):
    missing = tmp_path / "nothere.fba"
    for semantic in ((), ("--semantic",)):
        code, out, err = cli("validate", missing, *semantic)
        assert code == 1 and out == "" and err.count(str(missing)) == 1 and err.startswith("mpeg4fa validate: error:")


@pytest.mark.parametrize("argv", [["decode", "{bad}", "-o", "{out}.fap"], ["info", "{bad}"], ["info", "--json", "{bad}"],
                                  ["encode", "{bad}", "-o", "{out}.fba"]])
def test_a_damaged_stream_is_named_with_its_bit_offset(cli, demo, tmp_path, argv):
    """Fuzz of 2026-12-07: a corrupt .fba gave ``... at bit N (byte M), frame F`` without saying which file."""
    data = bytearray(demo.read_bytes())
    bad = tmp_path / "damaged.fba"
    bad.write_bytes(bytes(data[:8]) + b"\xff" * (len(data) - 8))
    code, _, err = cli(*[a.format(bad=bad, out=tmp_path / "out") for a in argv])
    assert code == 1 and f"error: {bad}: " in err and " at bit " in err and err.count(str(bad)) == 1, err
