"""Text in a script no voice here speaks is refused, naming the script and the characters, never spoken as silence."""
from __future__ import annotations

import pytest

from mpeg4fa.speech import MarkupError, encode_text
from mpeg4fa.speech.script import check_speakable, line_column, script_of

REFUSED = [("Arabic", "مرحبا"), ("Hebrew", "שלום"), ("Hangul", "안녕하세요"), ("Hiragana", "こんにちは"),
           ("Katakana", "カタカナ"), ("Thai", "สวัสดี"), ("Devanagari", "नमस्ते"), ("Cyrillic", "Привет"),
           ("Greek", "Γειά"), ("Katakana", "ｶﾀｶﾅ")]  # the last half-width: inside the CJK forms block


@pytest.mark.parametrize("char, script", [("a", "Latin"), ("é", "Latin"), ("Ａ", "Latin"), ("ﬁ", "Latin"),
                                          ("你", "Han"), ("ا", "Arabic"), ("я", "Cyrillic"), ("α", "Greek"),
                                          ("가", "Hangul"), ("ก", "Thai"), ("٣", "Arabic-Indic"), ("3", None),
                                          ("。", None), ("́", None), ("ʼ", None), ("€", None), (" ", None)])
def test_script_of(char, script):
    assert script_of(char) == script


@pytest.mark.parametrize("script, word", REFUSED)
def test_other_scripts_are_refused_with_the_characters(script, word):
    with pytest.raises(MarkupError) as info:
        check_speakable(f"Hello {word} there", "auto", name="s.txt")
    err = info.value
    assert (err.line, err.column, err.source) == (1, 7, "s.txt")
    assert f"cannot speak {script} text: {word!r}" in str(err) and "English and Mandarin" in err.hint


@pytest.mark.parametrize("text", ["Hello, world! 3.14 € (x)", "naïve café Größe", "你好，世界！", "Hi 你好 123",
                                  "ＡＢＣ", "don\u02bct", "a\u0301"])
def test_latin_han_digits_and_punctuation_are_spoken(text):
    check_speakable(text, "auto")
    check_speakable(text, "zh")


def test_hanzi_with_lang_en_keep_their_message():
    with pytest.raises(MarkupError, match="Chinese but --lang is en") as info:
        check_speakable("line one\nsay 你好", "en")
    assert (info.value.line, info.value.column) == (2, 5)


def test_line_column_counts_from_one():
    assert line_column("ab\ncd", 0) == (1, 1) and line_column("ab\ncd", 4) == (2, 2)


def test_the_library_refuses_it_too():
    with pytest.raises(MarkupError, match="cannot speak Cyrillic text: 'Привет мир'"):
        encode_text("(joy, 40, 0.5) Привет мир!", engine="estimate")


def test_the_quote_is_short_for_a_long_run():
    with pytest.raises(MarkupError) as info:
        check_speakable("ش" * 500)
    assert len(info.value.message) < 120


def test_a_script_error_points_into_the_source_past_the_tags():
    """The place is where the user wrote the word, tags and leading spaces counted (was 1:1 for the stripped text)."""
    from mpeg4fa.speech.encoder import encode_text

    with pytest.raises(MarkupError) as info:
        encode_text("(joy, 40, 0.5) Hello\n  (sadness, 20, 1) then مرحبا", engine="estimate")
    assert (info.value.line, info.value.column) == (2, 25)
