"""Text and voices the speech commands cannot take: one located line, exit 1, nothing written (issue 26).

Run in-process with ``capfd``, so that a line espeak-ng's C library prints on stderr is seen too.
"""
from __future__ import annotations

import io
import json
import subprocess
import sys
from pathlib import Path

import pytest

from mpeg4fa.cli import main

ROOT = Path(__file__).resolve().parents[2]


def run(capfd, *argv) -> tuple[int, str, str]:
    capfd.readouterr()
    code = main([str(a) for a in argv])
    out, err = capfd.readouterr()
    return code, out, err


def test_a_command_line_byte_that_is_not_utf8_is_refused_as_on_stdin(capfd, tmp_path, monkeypatch):
    """``encode --text $'hello \\xff there'`` ended in a UnicodeEncodeError traceback from espeak-ng's binding.
    Python hands the byte over as U+DCFF; it is now read back as the byte and judged as standard input's are."""
    out = tmp_path / "x.fba"
    code, _, err = run(capfd, "encode", "--text", "hello \udcff there", "-o", out)
    assert code == 1 and not out.exists()
    (line,) = err.strip().splitlines()
    assert line.startswith("mpeg4fa encode: error: <text>:1:7: not UTF-8: byte 0xff (byte offset 6)"), line
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(b"hello \xff there")))
    code, _, err_stdin = run(capfd, "encode", "-", "-o", out)
    assert code == 1 and not out.exists()
    problem = line.split("<text>:1:7: ")[1].split(" (")[0]
    assert f"<stdin>:1:7: {problem}" in err_stdin


def test_the_real_command_line_too(tmp_path):
    """The same through ``argv`` bytes, as a shell passes them."""
    out = tmp_path / "x.fba"
    done = subprocess.run([sys.executable, "-m", "mpeg4fa.cli", "encode", "--text", b"hello \xff there", "-o", out,
                           "--engine", "estimate"], cwd=ROOT, capture_output=True, timeout=120)
    err = done.stderr.decode()
    assert done.returncode == 1 and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert "<text>:1:7: not UTF-8: byte 0xff" in err and not out.exists()


def test_a_voice_no_utf8_can_spell_is_one_line(capfd, tmp_path):
    code, _, err = run(capfd, "encode", "--text", "Hello", "--voice", "\udcff", "-o", tmp_path / "x.fba")
    assert code == 1 and "unknown voice" in err and len(err.strip().splitlines()) == 1, err


def test_voices_leaves_out_those_without_a_dictionary(capfd):
    code, out, err = run(capfd, "voices")
    codes = {line.split()[0] for line in out.splitlines()}
    assert code == 0 and "en-us" in codes and not codes & {"fo", "kaa", "xex"}
    assert "left out: fo, kaa, xex (espeak-ng has no dictionary for them in this installation)" in err
    code, out, _ = run(capfd, "voices", "--json")
    assert code == 0 and not {v["language"] for v in json.loads(out)} & {"fo", "kaa", "xex"}


@pytest.mark.parametrize("flag", ["--lang", "--voice"])
def test_a_voice_without_its_dictionary_is_one_clear_line(capfd, tmp_path, flag):
    """``--lang fo`` said "gave no phonemes ... check the script" after espeak-ng's own "Can't read
    dictionary file" line on stderr."""
    out = tmp_path / "x.fba"
    code, _, err = run(capfd, "encode", "--text", "Hey there", flag, "fo", "-o", out)
    assert code == 1 and not out.exists()
    (line,) = err.strip().splitlines()
    assert "espeak-ng has no dictionary for fo in this installation" in line and "Can't read" not in err
