"""IPA -> MPEG-4 visemes by articulatory features (mpeg4fa.speech.ipa, spec/ipa_*.csv): the tables, the
parser, the split of diphthongs and affricates, loud failures, the IPA phoneme events of the engine,
script runs for ``--lang auto``, and agreement with the English table (the reference) on English speech.
"""
from __future__ import annotations

import pytest

from mpeg4fa.speech import MarkupError, TTSError
from mpeg4fa.speech import ipa
from mpeg4fa.speech.errors import PhonemeWarning
from mpeg4fa.speech.markup import parse_markup
from mpeg4fa.speech.script import check_speakable, runs
from mpeg4fa.speech.tts.base import Event
from mpeg4fa.speech.tts.espeak import EspeakEngine, phoneme_name
from mpeg4fa.speech.utterance import speak

ENGLISH = [
    "Would you want me to tell you the latest info about hotels and book reservations?",
    "(joy, 30, 0.6) Good morning, and welcome to the central station on this bright spring day.",
    "The next train to the harbour leaves from platform four in about ten minutes.",
    "(surprise, 35, 0.3) Oh, the bridge is closed today because of the strong wind!",
    "It stops near the old market, the museum and the public library.",
    "My grandmother grew tomatoes, beans and sweet peppers behind her little yellow house.",
    "Could you send me the report by Friday afternoon, so that I can read it over the weekend?",
    "When the rain finally stopped, the children ran outside to jump in every puddle they could find.",
    "A cup of hot tea and a good book make a cold winter evening feel much shorter.",
    "Turn left at the second traffic light, then follow the river until you see the blue bridge.",
    "Our team finished the project two weeks early, and the client was very pleased with it.",
    "He packed a sandwich, an apple and a bottle of water for the long walk over the hills.",
]


def parts(text: str) -> list[tuple[str, str]]:
    found, unknown = ipa.phoneme_visemes(text)
    assert not unknown, unknown
    return found


def visemes(text: str) -> list[str]:
    return [v for _, v in parts(text)]


# ---- the tables --------------------------------------------------------------------------------------------

def test_the_tables_load_and_every_segment_reaches_a_viseme():
    table = ipa.features()
    assert len(table) > 100 and len(ipa.rules()) > 10 and len(ipa.marks()) > 50 and ipa.aliases()
    assert {ipa.viseme_of(s) for s in table.values()} == {"PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR",
                                                          "AA", "E", "ih", "oh", "ou"}


@pytest.mark.parametrize("segment, viseme", [
    ("p", "PP"), ("b", "PP"), ("m", "PP"), ("β", "PP"), ("f", "FF"), ("v", "FF"), ("θ", "TH"), ("ð", "TH"),
    ("t", "DD"), ("d", "DD"), ("ɾ", "DD"), ("ʈ", "DD"), ("k", "kk"), ("ɡ", "kk"), ("ŋ", "kk"), ("ʁ", "kk"),
    ("h", "kk"), ("ʃ", "CH"), ("ʒ", "CH"), ("ɕ", "CH"), ("ç", "CH"), ("s", "SS"), ("z", "SS"), ("n", "nn"),
    ("l", "nn"), ("ɲ", "nn"), ("ʎ", "nn"), ("r", "RR"), ("ɹ", "RR"), ("j", "ih"), ("w", "ou"), ("ɥ", "ou"),
    ("a", "AA"), ("ɑ", "AA"), ("æ", "AA"), ("ɐ", "AA"), ("ʌ", "AA"), ("e", "E"), ("ɛ", "E"), ("ə", "E"),
    ("i", "ih"), ("ɪ", "ih"), ("ɨ", "ih"), ("o", "oh"), ("ɔ", "oh"), ("ø", "oh"), ("œ", "oh"), ("u", "ou"),
    ("y", "ou"), ("ʊ", "ou"), ("ʏ", "ou")])
def test_segments_map_by_their_features(segment, viseme):
    assert ipa.viseme_of(ipa.features()[segment]) == viseme


def test_a_bad_rule_is_refused_with_its_line(monkeypatch):
    rows = [{"kind": "vowel", "place": "", "manner": "", "height": "", "backness": "", "rounded": "",
             "viseme": "XX", "note": ""}]
    monkeypatch.setattr(ipa, "read_table", lambda name, columns: rows)
    ipa.rules.cache_clear()
    try:
        with pytest.raises(ValueError, match=r"spec/ipa_visemes.csv:2: unknown viseme 'XX'"):
            ipa.rules()
    finally:
        monkeypatch.undo()
        ipa.rules.cache_clear()
    assert ipa.rules()


# ---- the parser --------------------------------------------------------------------------------------------

@pytest.mark.parametrize("text, expected", [
    ("ˈa", ["AA"]), ("aː", ["AA"]), ("aa", ["AA"]), ("ä", ["AA"]), ("ˌo̞", ["oh"]), ("ɐ̃", ["AA"]),
    ("ẽ", ["E"]), ("s̪", ["SS"]), ("bʰ", ["PP"]), ("tʃʲ", ["DD", "CH"]), ("ts", ["DD", "SS"]),
    ("ʦ", ["DD", "SS"]), ("ˈaɪ", ["AA", "ih"]), ("oʊ", ["oh", "ou"]), ("eoi", ["E", "oh", "ih"]),
    ("ɯ", ["ih"]), ("ɯᵝ", ["ou"]), ("ɑːɹ", ["AA"]), ("ɛɹ", ["E"]), ("ɹ", ["RR"]), ("ç", ["CH"]),
    ("tS", ["DD", "CH"]), ("y-", ["ou"]), ("", ["none"]), ("(en)", ["="]), ("ʲ", ["="]), ("ʷ", ["ou"])])
def test_phonemes_parse_into_segments(text, expected):
    assert visemes(text) == expected


def test_unknown_characters_are_reported_and_read_as_the_nearest():
    found, unknown = ipa.phoneme_visemes("a\u2603")
    assert found == [("a", "AA")] and unknown == ["\u2603"]


@pytest.mark.parametrize("char, read_as", [
    ("\u1d4a", "ə"),   # MODIFIER LETTER SMALL SCHWA: its compatibility form
    ("\u029e", "k"),   # LATIN SMALL LETTER TURNED K: the base letter of its name
    ("\u1d00", "a"),   # LATIN LETTER SMALL CAPITAL A
    ("\u03b1", "ɑ"),   # GREEK SMALL LETTER ALPHA: Latin alpha is an IPA letter
    ("B", "b"),         # a capital: its lower case
    ("\u0436", "ə"),   # CYRILLIC SMALL LETTER ZHE: a letter nothing identifies
    ("\u20d0", ""),    # COMBINING LEFT HARPOON ABOVE: a mark, dropped
    ("\u2603", ""),    # a symbol, dropped
    ("§", "")])
def test_nearest_reads_an_unknown_character_by_its_base_letter_or_class(char, read_as):
    assert char not in ipa.features() and char not in ipa.aliases() and char not in ipa.marks()
    assert ipa.nearest(char) == read_as


def test_a_phoneme_of_nothing_but_unknown_marks_continues_the_one_before():
    with pytest.warns(PhonemeWarning):
        placed = ipa.ipa_visemes(events(("p", 0.0, 0.1), ("\u20d0", 0.1, 0.2)))
    assert [v for _, v, _, _ in placed] == ["PP", "PP"]


def test_shares_split_diphthongs_and_affricates():
    f = ipa.features()
    assert ipa.shares(f["a"], f["ɪ"], 2) == [ipa.FIRST_SHARE, 1 - ipa.FIRST_SHARE]
    assert ipa.shares(f["t"], f["ʃ"], 2) == [ipa.AFFRICATE_STOP_SHARE, 1 - ipa.AFFRICATE_STOP_SHARE]
    three = ipa.shares(f["e"], f["o"], 3)
    assert three[0] == ipa.FIRST_SHARE and three[1] == pytest.approx(three[2]) and sum(three) == pytest.approx(1)


def events(*items: tuple[str, float, float]) -> list[Event]:
    return [Event("phoneme", a, b, text) for text, a, b in items]


def test_ipa_visemes_time_the_parts_and_carry_pauses_and_switches():
    placed = ipa.ipa_visemes(events(("m", 0.0, 0.1), ("ˈaɪ", 0.1, 0.3), ("(en)", 0.3, 0.3), ("tʃ", 0.3, 0.4),
                                    ("", 0.4, 0.6)))
    assert [(label, v) for label, v, _, _ in placed] == [
        ("m", "PP"), ("ˈaɪ:a", "AA"), ("ˈaɪ:ɪ", "ih"), ("(en)", "ih"), ("tʃ:t", "DD"), ("tʃ:ʃ", "CH"),
        ("", "none")]
    assert placed[1][2:] == (0.1, pytest.approx(0.1 + 0.2 * ipa.FIRST_SHARE))
    assert placed[2][3] == pytest.approx(0.3) and placed[4][3] == pytest.approx(0.3 + 0.1 * ipa.AFFRICATE_STOP_SHARE)


def test_a_sounding_unnamed_phoneme_continues_the_one_before():
    placed = ipa.ipa_visemes(events(("p", 0.0, 0.1), ("", 0.1, 0.15), ("r", 0.15, 0.2)), is_sound=lambda e: True)
    assert [v for _, v, _, _ in placed] == ["PP", "PP", "RR"]


def test_unknown_segments_are_counted_in_one_warning_never_an_error():
    with pytest.warns(PhonemeWarning) as caught:
        placed = ipa.ipa_visemes(events(("a", 0, 0.1), ("x\u2603", 0.1, 0.2), ("\u2604", 0.25, 0.3),
                                        ("x\u2603", 0.3, 0.4)))
    assert len(caught) == 1
    message = str(caught[0].message)
    assert "3 phonemes" in message and "'x\u2603' x2 (U+2603; read as x)" in message and "U+2604" in message
    assert [v for _, v, _, _ in placed] == ["AA", "kk", "kk", "kk"]


def test_nested_calls_share_one_warning():
    with pytest.warns(PhonemeWarning) as caught:
        with ipa.phoneme_fallbacks("test") as log:
            ipa.ipa_visemes(events(("\u029e", 0, 0.1)))
            ipa.ipa_visemes(events(("\u029e", 0, 0.1), ("\u1d00", 0.1, 0.2)))
    assert len(caught) == 1 and len(log) == 3
    assert str(caught[0].message).startswith("test: 3 phonemes") and "'\u029e' x2" in str(caught[0].message)


def test_no_warning_when_every_character_is_known(recwarn):
    ipa.ipa_visemes(events(("ˈaɪ", 0, 0.1), ("tʃ", 0.1, 0.2)))
    assert not [w for w in recwarn if issubclass(w.category, PhonemeWarning)]


def test_an_ipa_name_cut_at_8_bytes_loses_only_the_broken_character():
    full = "ˈɐ̃ʊ̃".encode()
    assert len(full) > 8
    assert phoneme_name(full[:8]) == "ˈɐ̃ʊ" and phoneme_name(b"t\0\0\0\0\0\0\0") == "t"


# ---- the engine's IPA events ---------------------------------------------------------------------------------

def test_the_engine_names_phonemes_in_ipa_on_request_at_the_same_times():
    engine = EspeakEngine()
    text = "Church bells chime at noon."
    mnemonic, in_ipa = engine.synthesize(text), engine.synthesize(text, ipa=True)
    assert len(mnemonic.phonemes()) == len(in_ipa.phonemes())
    assert "tS" in {p.text for p in mnemonic.phonemes()} and "tʃ" in {p.text for p in in_ipa.phonemes()}
    for a, b in zip(mnemonic.phonemes(), in_ipa.phonemes()):
        assert abs(a.start - b.start) < 0.02
    assert "tʃ" not in {p.text for p in engine.synthesize(text).phonemes()}  # the mode does not stick


# ---- agreement with the English table ------------------------------------------------------------------------

def test_the_ipa_route_agrees_with_the_english_table_on_90_percent_of_frames():
    share, frames = ipa.english_agreement(EspeakEngine(), [parse_markup(s).text for s in ENGLISH])
    print(f"\nIPA route vs spec/english_visemes.csv: {share:.1%} of {frames} frames (25 fps)")
    assert share >= 0.90 and frames > 1000


def test_speak_can_send_english_through_the_ipa_route():
    engine = EspeakEngine()
    markup = parse_markup(ENGLISH[1])
    reference, through_ipa = speak(markup, engine, route="reference"), speak(markup, engine, route="ipa")
    assert {t.set for t in through_ipa.timings} == {"mpeg4"} and through_ipa.cues[0].start >= 0
    assert any(t.phoneme.endswith(":ɪ") for t in through_ipa.timings)  # split diphthongs (eɪ, aɪ)
    ipa_letters = set("əɪʊɛɔæɹ")
    assert any(ipa_letters & set(t.phoneme) for t in through_ipa.timings)
    assert not any(ipa_letters & set(t.phoneme) for t in reference.timings)  # mnemonics
    share, _ = ipa.frame_agreement(reference.timings, through_ipa.timings,
                                   min(reference.speech.duration, through_ipa.speech.duration))
    assert share > 0.8  # two syntheses: espeak's timing wanders a few ms between them


# ---- script runs for --lang auto -----------------------------------------------------------------------------

@pytest.mark.parametrize("text, expected", [
    ("Hello 你好, world", [("en", "Hello "), ("zh", "你好"), ("en", ", world")]),
    ("Привет, мир! Hello", [("ru", "Привет, мир! "), ("en", "Hello")]),
    ("«Привет»", [("ru", "«Привет»")]),
    ("مرحبا بك. Hi", [("ar", "مرحبا بك. "), ("en", "Hi")]),
    ("नमस्ते। hi", [("hi", "नमस्ते। "), ("en", "hi")]),
    ("こんにちは、今日は。我喜欢寿司。すし", [("ja", "こんにちは、今日は。"), ("zh", "我喜欢寿司。"), ("ja", "すし")]),
    ("ｶﾀｶﾅ and ラーメン", [("ja", "ｶﾀｶﾅ "), ("en", "and "), ("ja", "ラーメン")]),
])
def test_auto_runs_by_script(text, expected):
    assert [(k, text[a:b]) for k, a, b in runs(text, "auto", languages=True)] == expected


def test_runs_without_ipa_or_with_a_code_stay_as_they_were():
    assert runs("Hello 你好", "auto") == [("en", 0, 6), ("zh", 6, 8)]
    assert runs("Hola 你好 мир", "es") == [("es", 0, 11)]


def test_check_speakable_with_languages():
    check_speakable("Привет 你好 こんにちは नमस्ते مرحبا", "auto", languages=True)
    check_speakable("Γειά σου", "el", languages=True)
    check_speakable("我哋去飲茶", "yue", languages=True)
    with pytest.raises(MarkupError, match="cannot speak Hebrew text") as info:
        check_speakable("Hi שלום", "auto", languages=True)
    assert "mpeg4fa voices" in info.value.hint and (info.value.line, info.value.column) == (1, 4)
    with pytest.raises(MarkupError, match="Chinese, which the es voice does not read"):
        check_speakable("Hola 你好", "es", languages=True)
    with pytest.raises(MarkupError, match="kana, which the ru voice does not read"):
        check_speakable("Привет すし", "ru", languages=True)
    with pytest.raises(MarkupError, match="cannot speak Cyrillic"):
        check_speakable("Привет", "auto")  # an engine without IPA phonemes: English and Mandarin only
