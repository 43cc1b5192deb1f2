"""Expression-tag markup: plain text, tag offsets, and an exact line:column for every mistake.

The offsets decide when the face changes, and the errors are what a user sees
after a typo in a long script, so both are checked to the character.
"""
from __future__ import annotations

import re
import string

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mpeg4fa.spec import EXPRESSION_PROFILES
from mpeg4fa.speech.errors import MarkupError
from mpeg4fa.speech.markup import INTENSITY_MAX, Markup, Tag, parse_markup

EXAMPLE = "(joy, 40, 0.5) Hello there (sadness, 20, 1) oh no (joy, 0, 0.3)"


def where(source: str, *, expressions: list[str] | None = None) -> tuple[int, int]:
    """line:column of the error the source raises."""
    with pytest.raises(MarkupError) as info:
        parse_markup(source, expressions=expressions)
    return info.value.line, info.value.column


def error(source: str, **kwargs: object) -> MarkupError:
    with pytest.raises(MarkupError) as info:
        parse_markup(source, **kwargs)  # type: ignore[arg-type]
    return info.value


def summary(markup: Markup) -> list[tuple[str, int, float, int]]:
    return [(t.expression, t.intensity, t.seconds, t.offset) for t in markup.tags]


# -- the example and the basics ----------------------------------------------------------------------


def test_example_from_the_brief() -> None:
    m = parse_markup(EXAMPLE)
    assert m.text == "Hello there oh no"
    assert summary(m) == [("joy", 40, 0.5, 0), ("sadness", 20, 1.0, 12), ("joy", 0, 0.3, 17)]
    assert [(t.line, t.column) for t in m.tags] == [(1, 1), (1, 28), (1, 51)]
    assert m.text[m.tags[1].offset:].startswith("oh no")
    assert m.tags[2].offset == len(m.text)
    assert m.name == "<text>"


def test_results_are_frozen_and_typed() -> None:
    m = parse_markup("(joy, 40, 1) hi", name="script.txt")
    assert m.name == "script.txt"
    tag = m.tags[0]
    assert isinstance(tag, Tag) and isinstance(m.tags, tuple)
    assert type(tag.intensity) is int and type(tag.seconds) is float
    with pytest.raises(AttributeError):
        tag.offset = 3  # type: ignore[misc]
    with pytest.raises(AttributeError):
        m.text = "x"  # type: ignore[misc]


def test_default_expressions_are_the_profiles() -> None:
    for name in EXPRESSION_PROFILES:
        assert parse_markup(f"({name}, 10, 1)").tags[0].expression == name


@pytest.mark.parametrize("part, seconds", [("0.5", 0.5), ("1", 1.0), (".25", 0.25), ("2.", 2.0),
                                           ("0", 0.0), ("+1.5", 1.5), ("-0", 0.0), ("007.50", 7.5)])
def test_time_spellings(part: str, seconds: float) -> None:
    tag = parse_markup(f"(joy, 1, {part}) x").tags[0]
    assert tag.seconds == seconds
    assert str(tag.seconds) != "-0.0"


@pytest.mark.parametrize("part, intensity", [("0", 0), ("63", 63), ("+7", 7), ("007", 7), ("-0", 0)])
def test_intensity_spellings(part: str, intensity: int) -> None:
    assert parse_markup(f"(joy, {part}, 1)").tags[0].intensity == intensity


def test_whitespace_inside_tags_and_uppercase_names() -> None:
    m = parse_markup("a ( JOY ,\t40 ,\n 0.5\n) b (Sadness,1,1)c")
    assert m.text == "a b c"
    assert summary(m) == [("joy", 40, 0.5, 2), ("sadness", 1, 1.0, 4)]
    assert [(t.line, t.column) for t in m.tags] == [(1, 3), (3, 5)]


# -- the whitespace rule ---------------------------------------------------------------------------


@pytest.mark.parametrize("source, text, offsets", [
    ("(joy,1,1)Hello", "Hello", [0]),                      # at the start
    ("   (joy,1,1)   Hello", "Hello", [0]),                # leading whitespace trimmed
    ("Hello(joy,1,1)", "Hello", [5]),                      # at the end
    ("Hello (joy,1,1) \n ", "Hello", [5]),
    ("Hello  (joy,1,1)  there", "Hello there", [6]),       # one space, not four
    ("Hello (joy,1,1)there", "Hello there", [6]),          # space on one side is enough
    ("Hello(joy,1,1) there", "Hello there", [6]),
    ("Hello(joy,1,1)there", "Hellothere", [5]),            # no space written, none added
    ("a (joy,1,1)(fear,2,2) b", "a b", [2, 2]),            # adjacent tags share the offset
    ("a (joy,1,1) (fear,2,2)\n(anger,3,3) b", "a b", [2, 2, 2]),
    ("a(joy,1,1)(fear,2,2)b", "ab", [1, 1]),
    ("(joy,1,1)(fear,2,2)", "", [0, 0]),                   # nothing but tags
    ("  (joy,1,1)  ", "", [0]),
    ("a\n\n(joy,1,1)\n\nb", "a b", [2]),                   # a gap's whitespace becomes one space
    ("a  b (joy,1,1) c\td", "a  b c\td", [5]),             # other whitespace is kept as written
])
def test_whitespace_rule(source: str, text: str, offsets: list[int]) -> None:
    m = parse_markup(source)
    assert m.text == text
    assert [t.offset for t in m.tags] == offsets


def test_text_without_tags_is_only_stripped() -> None:
    assert parse_markup("  Hello,  world.\n  Second line\t\n").text == "Hello,  world.\n  Second line"
    assert parse_markup("").text == "" and parse_markup("").tags == ()
    assert parse_markup(" \n\t ").text == ""


def test_unicode_offsets_are_characters() -> None:
    m = parse_markup("(joy, 30, 0.5)你好，世界")
    assert m.text == "你好，世界"
    assert summary(m) == [("joy", 30, 0.5, 0)]
    m = parse_markup("你好(joy, 30, 0.5)世界 (sadness, 10, 1) 再见 😀 (fear,1,1) é")
    assert m.text == "你好世界 再见 😀 é"
    assert [t.offset for t in m.tags] == [2, 5, 10]
    assert m.text[10] == "é"


# -- ordinary parentheses and escapes --------------------------------------------------------------


@pytest.mark.parametrize("source", [
    "(see below)", "f(x) = (3, 4)", "a stray ) here", ")(", "((", "(e.g., this)",
    "(1, 2, 3)", "(, joy, 1, 1)", "smile :) and :(", "(-joy, 1, 1)", "(4joy, 1, 1)",
    "(however, we think) so", "(Paris, France)", "(joy is contagious)", "(joyful day)", "(Joy\nto the world)",
])
def test_ordinary_parentheses_stay_text(source: str) -> None:
    m = parse_markup(source)
    assert m.text == source and m.tags == ()


def test_tags_inside_ordinary_parentheses() -> None:
    m = parse_markup("(see (joy, 9, 1) below) done)")
    assert m.text == "(see below) done)"
    assert summary(m) == [("joy", 9, 1.0, 5)]


@pytest.mark.parametrize("source, text", [
    (r"\(joy, 40, 0.5) hi", "(joy, 40, 0.5) hi"),
    (r"a \(b\) c", "a (b) c"),
    (r"\(\)", "()"),
    (r"back\\slash", r"back\slash"),
    (r"C:\path\to \x", r"C:\path\to \x"),                # other backslashes are plain text
    ("end\\", "end\\"),
    (r"\\", "\\"),
])
def test_escapes(source: str, text: str) -> None:
    m = parse_markup(source)
    assert m.text == text and m.tags == ()


def test_escaped_backslash_before_a_tag() -> None:
    m = parse_markup(r"a\\(joy, 1, 1) b")
    assert m.text == "a\\ b"
    assert summary(m) == [("joy", 1, 1.0, 3)]
    assert (m.tags[0].line, m.tags[0].column) == (1, 4)


def test_escaped_parenthesis_is_not_whitespace() -> None:
    m = parse_markup(r"(joy,1,1) \( (fear,1,1) \)")
    assert m.text == "( )"
    assert [t.offset for t in m.tags] == [0, 2]


# -- custom expression sets ------------------------------------------------------------------------


def test_custom_expression_set() -> None:
    m = parse_markup("(Smirk, 20, 1) well (JOY, 5, 0)", expressions=["smirk", "Joy"])
    assert summary(m) == [("smirk", 20, 1.0, 0), ("joy", 5, 0.0, 4)]
    e = error("(anger, 20, 1)", expressions=["smirk", "joy"])
    assert (e.line, e.column) == (1, 2)
    assert "smirk, joy" in e.hint and "anger" not in e.hint


def test_custom_set_accepts_any_iterable_and_may_be_empty() -> None:
    assert parse_markup("(wink, 1, 1)", expressions=iter(["wink"])).tags[0].expression == "wink"
    assert parse_markup("(wink, 1, 1)", expressions=("wink", "wink")).tags[0].expression == "wink"
    e = error("(joy, 1, 1)", expressions=[])
    assert "(none)" in e.hint


def test_default_set_rejects_names_not_in_profiles() -> None:
    e = error("(smirk, 1, 1)")
    assert "joy" in e.hint and "surprise" in e.hint


# -- errors, each at its character -----------------------------------------------------------------


@pytest.mark.parametrize("source, line, column, words", [
    ("Hi (joyy, 40, 0.5)", 1, 5, "unknown expression"),
    ("(Smith, 2020, 12) wrote", 1, 2, "unknown expression"),   # the whole shape of a tag: write \( for prose
    ("(joyy, 40) hi", 1, 2, "unknown expression"),              # nearly "joy", a comma and a number
    ("(joy, 4.5, 1)", 1, 7, "not an integer"),
    ("(joy, forty, 1)", 1, 7, "not an integer"),
    ("(joy, 40 0.5)", 1, 10, "missing ',' after '40'"),
    ("(joy 40 0.5) Hello there", 1, 6, "missing ',' after 'joy'"),
    ("(joy, 40, 0.5 1)", 1, 15, "missing ',' after '0.5'"),
    ("(joy\n40, 1)", 2, 1, "missing ','"),
    ("(joy)", 1, 5, "missing intensity"),
    ("(Joy!) hi", 1, 5, "unexpected '!'"),
    ("(joy; 40; 0.5)", 1, 5, "unexpected"),
    ("(joy, ４０, 1)", 1, 7, "not an integer"),          # full-width digits are not accepted
    ("(joy, 64, 1)", 1, 7, "out of range"),
    ("(joy,  -1, 1)", 1, 8, "out of range"),
    ("(joy, 99999999999999999999999999, 1)", 1, 7, "out of range"),
    ("(joy, , 1)", 1, 7, "missing intensity"),
    ("(joy, 40, soon)", 1, 11, "not a number"),
    ("(joy, 40, 1e3)", 1, 11, "not a number"),
    ("(joy, 40, nan)", 1, 11, "not a number"),
    ("(joy, 40, 1.2.3)", 1, 11, "not a number"),
    ("(joy, 40, -0.5)", 1, 11, "negative"),
    ("(joy, 40, " + "9" * 400 + ")", 1, 11, "too large"),
    ("(joy, 40, )", 1, 11, "missing T"),
    ("(joy, 40)", 1, 9, "missing T"),
    ("(joy,)", 1, 6, "missing intensity"),
    ("(joy, 40, 0.5, 2)", 1, 14, "needs 3"),
    ("(joy, 40, 0.5,)", 1, 14, "needs 3"),
    ("Hello (joy, 40, 0.5", 1, 7, "not closed"),
    ("Hello (joy,", 1, 7, "not closed"),
    ("(joy, 40, 0.5 hi (see below)", 1, 1, "not closed"),
    ("()", 1, 1, "empty tag"),
    ("say ( \t ) now", 1, 5, "empty tag"),
])
def test_error_positions(source: str, line: int, column: int, words: str) -> None:
    e = error(source, name="script.txt")
    assert (e.line, e.column) == (line, column)
    assert words in e.message
    assert e.hint
    assert str(e).startswith(f"script.txt:{line}:{column}: ")
    assert isinstance(e, ValueError)


def test_unknown_expression_suggests_the_closest_name() -> None:
    e = error("(sadnes, 10, 1)")
    assert "did you mean 'sadness'" in e.hint
    assert "known expressions: neutral, joy, sadness, anger, fear, disgust, surprise" in e.hint
    assert r"\(" in e.hint
    assert "did you mean" not in error("(xyzzy, 1, 1)").hint


def test_the_first_mistake_from_the_left_is_reported() -> None:
    assert where("(joyy, 99)") == (1, 2)
    assert where("(joy, 99)") == (1, 7)
    assert where("(joy, 1, x, y)") == (1, 10)
    assert where("(joy, 1, 1) (fear, 1, x) (anger, 99, 1)") == (1, 23)


def test_long_parts_are_cut_short_in_messages() -> None:
    e = error("(joy, " + "x" * 1000 + ", 1)")
    assert len(str(e)) < 300


@pytest.mark.parametrize("source, line, column", [
    ("first line\nsecond (joy, 99, 1)", 2, 14),
    ("first line\r\nsecond (joy, 99, 1)", 2, 14),                 # CRLF
    ("a\r\nb\r\n\t(fear, 10, x)", 3, 13),                          # tab is one column
    ("a\r(joy,1,x)", 2, 8),                                        # lone CR
    ("a\n\n\n\t\t(joy, 1, 1)\n(joyy, 1, 1)", 5, 2),
    ("你好\n世界(joy, 99, 1)", 2, 9),                               # columns count characters
    ("ok (joy, 1,\n\n   x)", 3, 4),                                 # a tag spanning lines
    ("line\r\n  (joy, 1, 1\r\nmore", 2, 3),                         # unclosed
    ("x\n\t(joy,\t1,\t2,\t3)", 2, 12),
])
def test_positions_on_later_lines(source: str, line: int, column: int) -> None:
    assert where(source) == (line, column)


def test_tag_positions_on_later_lines() -> None:
    m = parse_markup("one\r\ntwo\r\n\t(joy, 1, 1) three\n你(fear,2,2)")
    assert [(t.line, t.column) for t in m.tags] == [(3, 2), (4, 2)]
    assert m.text == "one\r\ntwo three\n你"


def test_error_survives_pickling() -> None:
    import pickle

    e = error("x\n(joy, 99, 1)", name="a.txt")
    again = pickle.loads(pickle.dumps(e))
    assert (again.line, again.column, again.source, str(again)) == (2, 7, "a.txt", str(e))


# -- properties ------------------------------------------------------------------------------------

LINE_BREAK = re.compile(r"\r\n|\r|\n")
KNOWN = tuple(EXPRESSION_PROFILES)

FRAGMENTS = ["(", ")", ",", ", ", "\\", "\\(", " ", "\t", "\n", "\r\n", "\r", "joy", "JOY", "fear", "jo",
             "0", "40", "63", "64", "-1", "0.5", ".25", "1.", "-", ".", "e", "你好", "😀",
             "(joy, 40, 0.5)", "(joy,", "(sadness, 1, 1)", "()", "( )", "x", "a b", "\u00a0", "\u2028", "\x00"]
markup_like = st.lists(st.one_of(st.sampled_from(FRAGMENTS), st.text(max_size=4)), max_size=25).map("".join)


def index_of(source: str, line: int, column: int) -> int:
    """Independent line:column -> index, to check what the parser reports."""
    starts = [0] + [m.end() for m in LINE_BREAK.finditer(source)]
    return starts[line - 1] + column - 1


def check_parsed(source: str, m: Markup, known: tuple[str, ...]) -> None:
    assert m.text == m.text.strip()
    offsets = [t.offset for t in m.tags]
    assert offsets == sorted(offsets)
    assert all(0 <= k <= len(m.text) for k in offsets)
    for t in m.tags:
        assert source[index_of(source, t.line, t.column)] == "("
        assert t.expression in known
        assert 0 <= t.intensity <= INTENSITY_MAX
        assert t.seconds >= 0 and t.seconds != float("inf")
        # A tag is followed by the start of a word or the end, never by whitespace.
        assert t.offset == len(m.text) or not m.text[t.offset].isspace()


def check_error(source: str, e: MarkupError) -> None:
    lines = LINE_BREAK.split(source)
    assert 1 <= e.line <= len(lines)
    assert 1 <= e.column <= len(lines[e.line - 1]) + 1
    assert e.message and e.hint


@settings(max_examples=400, deadline=None, derandomize=True)
@given(st.one_of(st.text(), markup_like, st.text(st.characters(exclude_categories=()))))  # surrogates too
def test_any_text_parses_or_raises_markup_error(source: str) -> None:
    try:
        m = parse_markup(source)
    except MarkupError as e:
        check_error(source, e)
    else:
        check_parsed(source, m, KNOWN)


@settings(max_examples=200, deadline=None, derandomize=True)
@given(markup_like, st.lists(st.text(alphabet=string.ascii_letters + "_é", min_size=1, max_size=6),
                             max_size=4))
def test_any_text_with_custom_expressions(source: str, names: list[str]) -> None:
    try:
        m = parse_markup(source, expressions=names)
    except MarkupError as e:
        check_error(source, e)
    else:
        check_parsed(source, m, tuple(n.lower() for n in names))


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.text().map(lambda s: s.replace("(", "").replace("\\", "").replace("\0", "")))  # NUL: no text
def test_text_without_tags_parses_to_itself_stripped(source: str) -> None:
    m = parse_markup(source)
    assert m.text == source.strip()
    assert m.tags == ()


@settings(max_examples=300, deadline=None, derandomize=True)
@given(st.one_of(st.text(), markup_like))
def test_escaped_text_parses_to_itself(text: str) -> None:
    """Escaping every parenthesis and backslash turns any text, tags included, into plain text (NUL is no text)."""
    text = text.replace("\0", "")
    escaped = text.replace("\\", "\\\\").replace("(", "\\(").replace(")", "\\)")
    m = parse_markup(escaped)
    assert m.text == text.strip()
    assert m.tags == ()


words = st.text(alphabet=string.ascii_letters + "你好,.!)", min_size=1, max_size=6)
tags = st.tuples(st.sampled_from(KNOWN), st.integers(0, INTENSITY_MAX),
                 st.sampled_from(["0", "0.5", ".25", "1", "2.75"]))


@settings(max_examples=200, deadline=None, derandomize=True)
@given(st.lists(st.one_of(words, tags), max_size=12), st.sampled_from([" ", "  ", "\n", "\t ", "\r\n"]))
def test_words_and_tags_round_trip(items: list[str | tuple[str, int, str]], space: str) -> None:
    """Tags between words: a run of tags becomes one space, and each tag lands on the next word."""
    source = space.join(item if isinstance(item, str) else f"({item[0].upper()}, {item[1]}, {item[2]})"
                        for item in items)
    # Expected by the rule: words side by side keep the separator, a run of tags becomes one space.
    text, expected, pending, gap = "", [], [], False
    for item in items:
        if isinstance(item, tuple):
            pending.append(item)
            gap = True
            continue
        if text:
            text += " " if gap else space
        expected += [(e, a, float(t), len(text)) for e, a, t in pending]
        text, pending, gap = text + item, [], False
    expected += [(e, a, float(t), len(text)) for e, a, t in pending]
    m = parse_markup(source)
    assert m.text == text
    assert summary(m) == expected


def test_a_text_longer_than_the_bound_is_refused_before_any_work():
    from mpeg4fa.speech.markup import MAX_TEXT_CHARS

    text = "word " * (MAX_TEXT_CHARS // 5) + "\nmore"
    with pytest.raises(MarkupError) as info:
        parse_markup(text, name="long.txt")
    assert (info.value.line, info.value.column) == (1, MAX_TEXT_CHARS + 1) and "200,000" in str(info.value)
    parse_markup("word " * (MAX_TEXT_CHARS // 5))  # at the bound: read
