"""The words recogniser knows only English (pocketsphinx's bundled dictionary and language model): asked for
another language it is refused in one line that names what to use instead, before any audio is read, from
the command line (exit status 1, no traceback, no output file) and from the library."""
import io
import sys
import wave

import numpy as np
import pytest

from mpeg4fa.speech.align import AlignError, Recording
from mpeg4fa.speech.listen.core import check_language, choose_recognizer


def _wav(path, seconds=0.5, rate=16000):
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes(np.zeros(int(seconds * rate), "<i2").tobytes())
    return path


@pytest.mark.parametrize("command", ["encode", "say"])
@pytest.mark.parametrize("lang", ["es", "zh", "ar"])
def test_words_with_another_language_is_one_line_exit_1(cli, tmp_path, command, lang):
    out = tmp_path / ("x.fba" if command == "encode" else "x.mp4")
    code, stdout, err = cli(command, "--speech", _wav(tmp_path / "r.wav"), "--recognizer", "words", "--lang", lang,
                            "-o", out)
    assert code == 1, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert "only English" in lines[0] and repr(lang) in lines[0], lines[0]
    assert "--recognizer phonetic" in lines[0] and "--transcript" in lines[0], lines[0]
    assert not out.exists()


def test_the_refusal_comes_before_standard_input_is_read(cli, tmp_path, monkeypatch):
    stdin = io.BytesIO(np.zeros(16000, "<i2").tobytes())
    monkeypatch.setattr(sys, "stdin", io.TextIOWrapper(stdin))
    code, _, err = cli("encode", "--speech", "-", "--recognizer", "words", "--lang", "de", "-o", tmp_path / "x.fba")
    assert code == 1 and "only English" in err
    assert stdin.tell() == 0


@pytest.mark.parametrize("lang", ["auto", "en", "en-gb", "EN-us"])
def test_english_and_auto_are_let_through(lang):
    check_language("words", lang)  # auto: no text to tell the language by, taken as English


@pytest.mark.parametrize("recognizer", ["auto", "phonetic"])
def test_other_recognisers_take_any_language(recognizer):
    assert choose_recognizer(recognizer, "es") == "phonetic"
    check_language(choose_recognizer(recognizer, "es"), "es")


def test_the_library_refuses_too():
    pytest.importorskip("pocketsphinx")
    from mpeg4fa.speech.listen import listen
    from mpeg4fa.speech.listen.stream import Source, stream_listened

    rec = Recording(np.zeros(8000, np.int16), 16000, "quiet")
    with pytest.raises(AlignError, match="only English"):
        listen(rec, recognizer="words", lang="fr")
    pieces = iter([rec.samples])
    with pytest.raises(AlignError, match="--recognizer phonetic"):
        stream_listened(Source("quiet", 16000, 0.5, pieces), io.BytesIO(), recognizer="words", lang="hi")
    assert next(pieces, None) is not None  # nothing was read
