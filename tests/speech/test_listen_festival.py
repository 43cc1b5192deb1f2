"""Lip sync from audio alone on speech espeak-ng did not make: festival's HTS voice (slt), the most like a person
of the voices at hand, its own segments the truth (tools/bench_lipsync_festival.py measures 17 sentences in three
voices). The closure detector learned espeak-ng's speech only and finds about half of these closures: the issue's
English target is xfail here, the floor below it holds what is reached now."""
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pocketsphinx")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))

import festival_speech  # noqa: E402

if festival_speech.available() or not any(Path("/usr/share/festival/voices").glob("*/cmu_us_slt_arctic_hts")):
    pytest.skip("festival and its slt voice are not installed (apt install festival festvox-us-slt-hts)",
                allow_module_level=True)

from bench_lipsync_festival import truth_timings  # noqa: E402

from mpeg4fa.speech.align import Recording  # noqa: E402
from mpeg4fa.speech.encoder import phones  # noqa: E402
from mpeg4fa.speech.listen import listen  # noqa: E402
from mpeg4fa.speech.listen.compare import closure_onsets, onset_score  # noqa: E402

TEXTS = ("Please bring the maps back before the boat leaves.",
         "The baby played with a purple ball in the back garden.",
         "Maybe Emma will bring popcorn to the movie premiere.")


def test_festival_segments_give_the_closures_of_their_speech():
    """The truth itself: every p, b and m festival speaks is a closure onset of the reference track."""
    samples, rate, segments = festival_speech.speak(TEXTS[0], "slt")
    assert rate > 0 and len(samples) / rate > 2.0
    want = [a for name, a, _ in segments if name in festival_speech.CLOSING]
    got = closure_onsets(truth_timings(segments), shut_only=True)
    assert len(want) >= 6
    assert np.isin(np.round(got, 4), np.round(want, 4)).all()


FLOOR = 0.45
"""Closures within 40 ms reached now on these three sentences: 12 of 23 (2026-12-06; the word recogniser: 19)."""


@pytest.fixture(scope="module")
def scored():
    """Closures of the phone loop's track against festival's segments, summed over :data:`TEXTS`."""
    hits = total = found = extra = 0
    for text in TEXTS:
        samples, rate, segments = festival_speech.speak(text, "slt")
        rec = Recording(np.clip(np.rint(samples * 32768), -32768, 32767).astype(np.int16), rate, text)
        heard = phones(listen(rec, recognizer="phonetic", lang="en").utterance).timings
        s = onset_score(truth_timings(segments), heard)
        hits, total, extra = hits + s.hits, total + s.reference, extra + s.extra
        found += len(closure_onsets(heard))
    return hits, total, found, extra


def test_closures_found_on_a_voice_the_detector_never_heard(scored):
    hits, total, found, extra = scored
    assert total >= 20
    assert hits / total >= FLOOR, f"{hits} of {total} closures within 40 ms"
    assert 1 - extra / found >= 0.75, f"{extra} of {found} closures shown where festival has none"


@pytest.mark.xfail(reason="issue 28's English target (90 % within 40 ms) is reached on espeak-ng's speech only: the "
                          "closure detector learned espeak-ng's closures (12 of 23 here; "
                          "tools/bench_lipsync_festival.py: 52 % on this voice, 59-72 % on two diphone voices)",
                   strict=True)
def test_issue_target_on_speech_espeak_did_not_make(scored):
    hits, total, _, _ = scored
    assert hits / total >= 0.90


def test_either_takes_the_words_on_speech_like_a_persons():
    # festival's HTS voice, learned from a woman's recordings: the words explain it nearly as well as the free phone
    # loop (measured -19.1 to -12.0 a sentence, 2026-12-06), so ``either`` aligns them, as ``words`` would
    from mpeg4fa.speech.listen.core import WORDS_CONFIDENT

    samples, rate, segments = festival_speech.speak(TEXTS[1], "slt")
    rec = Recording(np.clip(np.rint(samples * 32768), -32768, 32767).astype(np.int16), rate, TEXTS[1])
    heard = listen(rec, recognizer="either", lang="en")
    assert heard.recognizer == "words" and heard.confidence >= WORDS_CONFIDENT + 2, heard.confidence
    words = listen(rec, recognizer="words", lang="en")
    assert [w.word for w in heard.words] == [w.word for w in words.words]
    assert onset_score(truth_timings(segments), phones(heard.utterance).timings).hits >= 5  # measured 7 of 7
