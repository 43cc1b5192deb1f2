"""English phonemes -> MPEG-4 visemes: the table covers what espeak-ng says, unknown phonemes fail loudly."""
import pytest

from mpeg4fa.spec import VISEME_PROFILES
from mpeg4fa.speech.errors import TTSError
from mpeg4fa.speech.tts.base import Event
from mpeg4fa.speech.tts.espeak import EspeakEngine
from mpeg4fa.speech.visemes import english_table, english_viseme, english_visemes

PARAGRAPH = ("The quick brown fox jumps over the lazy dog. Sphinx of black quartz, judge my vow! "
             "How vexingly quick daft zebras jump; the five boxing wizards jump quickly. "
             "Measure the thickness of the azure hour at 7 p.m., little button, fire and cure, "
             "near the north shore: which way, Bob? Uh-oh, rhythm and choice, the thought of loch water.")


def test_table_is_valid_and_covers_the_fourteen_visemes():
    table = english_table()
    assert set(table.values()) - {"="} == set(VISEME_PROFILES["mpeg4"]) - {"none"}


@pytest.mark.parametrize("voice", ["en-us", "en-gb"])
def test_every_phoneme_espeak_says_has_a_viseme(voice):
    speech = EspeakEngine(voice=voice).synthesize(PARAGRAPH)
    pairs = english_visemes(list(speech.phonemes()))
    assert len(pairs) == len(speech.phonemes())
    spoken = {v for v, _ in pairs}
    assert {"PP", "FF", "TH", "DD", "kk", "CH", "SS", "nn", "RR", "AA", "E", "ih", "oh", "ou", "none"} <= spoken


def test_stress_marks_and_pauses():
    assert english_viseme("'oU") == english_viseme(",oU") == "oh"
    assert english_viseme("_:") == english_viseme("_|") == "none"


def test_unknown_phonemes_fail_loudly_naming_them():
    events = [Event("phoneme", 0.0, 0.1, "p", 0), Event("phoneme", 0.1, 0.2, "Q!", 1),
              Event("phoneme", 0.2, 0.3, "zz", 2)]
    with pytest.raises(TTSError, match=r"'Q!' \(first at 0.100 s\), 'zz'"):
        english_visemes(events)


def test_modifier_continues_the_previous_viseme():
    events = [Event("phoneme", 0.0, 0.1, "I2", 0), Event("phoneme", 0.1, 0.12, ";", 0)]
    assert [v for v, _ in english_visemes(events)] == ["ih", "ih"]
