"""English phonemes -> MPEG-4 visemes: the table covers what espeak-ng says; a mnemonic it lacks goes by its IPA
features (spec/english_ipa.csv), one in no table by the nearest viseme and one warning."""
import pytest

from mpeg4fa.spec import VISEME_PROFILES
from mpeg4fa.speech.errors import PhonemeWarning
from mpeg4fa.speech.tts.base import Event
from mpeg4fa.speech.tts.espeak import EspeakEngine
from mpeg4fa.speech.visemes import english_ipa, english_table, english_viseme, english_visemes

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


def test_a_mnemonic_the_table_lacks_goes_by_its_ipa_without_a_warning(recwarn):
    events = [Event("phoneme", 0.0, 0.1, "l#", 0), Event("phoneme", 0.1, 0.2, "'O", 1),
              Event("phoneme", 0.2, 0.3, "dZ;", 2)]
    assert "l#" not in english_table() and english_ipa()["l#"] == "ɬ"
    pairs = english_visemes(events)
    assert [(v, e.text) for v, e in pairs] == [("nn", "l#"), ("oh", "'O"), ("DD", "dZ;:d"), ("CH", "dZ;:ʑ")]
    assert pairs[2][1].end == pytest.approx(0.23) and pairs[3][1].start == pytest.approx(0.23)
    assert english_viseme("l#") == english_viseme("l") == "nn"
    assert not [w for w in recwarn if issubclass(w.category, PhonemeWarning)]


def test_a_mnemonic_in_no_table_shows_the_nearest_viseme_and_one_warning():
    events = [Event("phoneme", 0.0, 0.1, "p", 0), Event("phoneme", 0.1, 0.2, "Q!", 1),
              Event("phoneme", 0.2, 0.3, "zz", 2), Event("phoneme", 0.3, 0.4, "zz", 3)]
    with pytest.warns(PhonemeWarning) as caught:
        pairs = english_visemes(events)
    assert [v for v, _ in pairs] == ["PP", "kk", "SS", "SS"]
    assert len(caught) == 1
    assert "3 phonemes" in str(caught[0].message) and "'zz' x2" in str(caught[0].message)


def test_every_row_of_the_ipa_table_maps_without_a_guess():
    for mnemonic, ipa_name in english_ipa().items():
        assert english_viseme(mnemonic), mnemonic
        from mpeg4fa.speech.ipa import phoneme_visemes
        assert not phoneme_visemes(ipa_name)[1], (mnemonic, ipa_name)


def test_modifier_continues_the_previous_viseme():
    events = [Event("phoneme", 0.0, 0.1, "I2", 0), Event("phoneme", 0.1, 0.12, ";", 0)]
    assert [v for v, _ in english_visemes(events)] == ["ih", "ih"]
