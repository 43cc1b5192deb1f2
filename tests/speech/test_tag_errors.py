"""Malformed tags (issue 26, item 3): one line with the line and column, exit status 1, in the library and through
the CLI; ``--lenient`` speaks them as text and says so once. ``say "(joy 40 0.5) Hello there"`` used to exit 0
and speak "joy forty zero point five".
"""
from __future__ import annotations

import subprocess
import sys
import warnings

import pytest

from mpeg4fa.cli import main
from mpeg4fa.speech.errors import MarkupError, MarkupWarning
from mpeg4fa.speech.markup import parse_markup

MALFORMED = [  # (text, column, words of the message)
    ("(joy 40 0.5) Hello there", 6, "missing ',' after 'joy'"),           # the reproducer
    ("(joy, 40 0.5) Hello", 10, "missing ',' after '40'"),
    ("(jyo, 40, 0.5) Hello", 2, "unknown expression 'jyo'"),
    ("(joy, 400, 0.5) Hello", 7, "out of range 0..63"),
    ("(joy, -1, 0.5) Hello", 7, "out of range 0..63"),
    ("Hello (joy, 40, 0.5 there", 7, "not closed before the end of the text"),
    ("(joy, 40, 0.5 (fear, 1, 1) Hello", 1, "not closed before the next '('"),
    ("(joy, 40, 0.5, 2) Hello", 14, "tag has 4 parts, needs 3"),
    ("(joy, 4o, 0.5) Hello", 7, "intensity '4o' is not an integer"),
    ("(joy, 40, 0.5s) Hello", 11, "T '0.5s' is not a number"),
    ("(joy, 40, -1) Hello", 11, "negative"),
    ("(joy, 40) Hello", 9, "missing T"),
    ("(joy) Hello", 5, "missing intensity"),
    ("() Hello", 1, "empty tag"),
]
PROSE = ["(see below) Hello", "Hello (Paris, France) there", "(however, we think) so", "(joy is contagious)",
         "f(x) = (3, 4)", "(Smith, 2020) wrote", "(smile, 20) please", "(page, 12) and (jyo, 4)"]


@pytest.mark.parametrize("text, column, words", MALFORMED)
def test_library_names_line_and_column(text, column, words):
    with pytest.raises(MarkupError) as info:
        parse_markup(text)
    assert str(info.value).startswith(f"<text>:1:{column}: ") and words in str(info.value)


@pytest.mark.parametrize("text", PROSE)
def test_parenthesised_prose_still_speaks(text):
    assert parse_markup(text).text == text


@pytest.mark.parametrize("command", ["encode", "say"])
@pytest.mark.parametrize("text, column, words", MALFORMED)
def test_cli_prints_one_line_and_exits_1(tmp_path, capsys, command, text, column, words):
    out = tmp_path / ("out.fba" if command == "encode" else "out.mp4")
    assert main([command, text, "-o", str(out)]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "Traceback" not in err
    assert err.startswith(f"mpeg4fa {command}: error: <text>:1:{column}: ") and words in err
    assert not out.exists() and not list(tmp_path.iterdir())


def test_cli_names_the_file_and_line(tmp_path, capsys):
    script = tmp_path / "script.txt"
    script.write_text("Hello there,\nmy friend.\n  Now (joy 40 0.5) smile.\n", encoding="utf-8")
    assert main(["encode", str(script), "-o", str(tmp_path / "out.fba")]) == 1
    err = capsys.readouterr().err
    assert err == f"mpeg4fa encode: error: {script}:3:12: missing ',' after 'joy' " \
                  "(separate the parts with commas, as in (joy, 40, 0.5))\n"


def test_the_installed_command_exits_1_without_a_traceback(tmp_path):
    run = subprocess.run([sys.executable, "-m", "mpeg4fa.cli", "say", "(joy 40 0.5) Hello there", "-o",
                          str(tmp_path / "w.mp4")], capture_output=True, text=True, timeout=60)
    assert run.returncode == 1 and run.stdout == ""
    assert run.stderr.splitlines() == [run.stderr.strip()] and "<text>:1:6:" in run.stderr


def test_lenient_speaks_malformed_tags_as_text_and_says_so_once():
    with pytest.warns(MarkupWarning) as caught:
        m = parse_markup("(joy 40 0.5) Hello (fear, 99, 1) there (joy, 10, 1) now", lenient=True)
    assert m.text == "(joy 40 0.5) Hello (fear, 99, 1) there now"
    assert [(t.expression, t.intensity) for t in m.tags] == [("joy", 10)]
    assert len(caught) == 1 and len(m.malformed) == 2
    assert str(caught[0].message) == ("<text>:1:6: 2 malformed tags spoken as text (lenient); the first: "
                                      "missing ',' after 'joy'")


def test_lenient_is_silent_when_every_tag_is_right():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        m = parse_markup("(joy, 40, 0.5) Hello", lenient=True)
    assert m.text == "Hello" and m.malformed == ()


def test_lenient_keeps_an_unclosed_tag_as_text():
    with pytest.warns(MarkupWarning, match="not closed"):
        assert parse_markup("Hello (joy, 40, 0.5 there", lenient=True).text == "Hello (joy, 40, 0.5 there"


def test_cli_lenient_encodes_with_one_warning_line(tmp_path, capsys):
    from mpeg4fa.fba import decode

    out = tmp_path / "out.fba"
    assert main(["encode", "--lenient", "(joy 40 0.5) Hello (fear, 99, 1) there", "-o", str(out)]) == 0
    err = capsys.readouterr().err
    warned = [line for line in err.splitlines() if "warning" in line]
    assert warned == ["mpeg4fa encode: warning: <text>:1:6: 2 malformed tags spoken as text (lenient); the first: "
                      "missing ',' after 'joy'"]
    assert len(decode(out.read_bytes())) > 10


def test_encode_text_lenient_keyword():
    from mpeg4fa.speech.encoder import encode_text

    with pytest.raises(MarkupError):
        encode_text("(joy 40 0.5) Hi", engine="estimate")
    with pytest.warns(MarkupWarning):
        encoded = encode_text("(joy 40 0.5) Hi", engine="estimate", lenient=True)
    assert encoded.utterance.markup.text == "(joy 40 0.5) Hi" and encoded.utterance.cues == ()


def test_lenient_reaches_a_recordings_transcript(tmp_path, capsys):
    from mpeg4fa.speech.tts.espeak import EspeakEngine

    recording = tmp_path / "rec.wav"
    EspeakEngine().synthesize("joy 40 0.5. Hello there", voice="en-gb").write_wav(recording)
    args = ["encode", "--speech", str(recording), "--transcript", "(joy 40 0.5) Hello there", "-o",
            str(tmp_path / "out.fba")]
    assert main(args) == 1
    assert capsys.readouterr().err.startswith("mpeg4fa encode: error: <text>:1:6: missing ','")
    assert main(args + ["--lenient"]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert warned == ["mpeg4fa encode: warning: <text>:1:6: 1 malformed tag spoken as text (lenient); the first: "
                      "missing ',' after 'joy'"]
