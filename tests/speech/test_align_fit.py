"""The fit check: a transcript of about the right length but other words than the recording's is refused.

The recording is espeak-ng speech (en-us+f3 at 140 wpm, not the aligner's en-us reference at 175). The wrong
transcript is one pocketsphinx still finds a path through (most wrong ones it does not: that is the
"found no path" error), so only the fit score (forced alignment against a free phone decoding, per
frame) tells: about -15 for the right words, about -49 for these, against the limit of -40
(tools/bench_align.py measures the margin on more speech).
"""
import math
import wave

import numpy as np
import pytest

from mpeg4fa.speech.align import AlignError, Recording, align_recording
from mpeg4fa.speech.align.core import FIT_LIMITS
from mpeg4fa.speech.encoder import encode_recording
from mpeg4fa.speech.tts.espeak import EspeakEngine

TEXT = "Please bring the maps back before the boat leaves."
WRONG = "Bring me some bread and butter for the boat."
WRONG_SAME_SPAN = "Fetch me the bread and butter before the boat leaves."
"""Other words that DTW warps over the whole recording (100 % of its speech). WRONG spans 80-84 % of it,
depending on what espeak-ng spoke before in the process: on the coverage rule's edge (MIN_COVERAGE 0.8)."""


@pytest.fixture(scope="module")
def rec():
    speech = EspeakEngine().synthesize(TEXT, voice="en-us+f3", rate=140)
    return Recording(speech.samples, speech.rate, "please.wav")


def test_the_right_transcript_fits(rec):
    al = align_recording(rec, TEXT, lang="en", method="pocketsphinx")
    assert FIT_LIMITS["pocketsphinx"] + 10 < al.fit < 0


def test_a_wrong_transcript_is_refused_with_its_location(rec):
    with pytest.raises(AlignError, match="does not fit") as exc:
        align_recording(rec, WRONG, lang="en", method="pocketsphinx", name="wrong.txt")
    assert exc.value.where == "please.wav / wrong.txt"
    assert "--no-fit-check" in exc.value.hint
    with pytest.raises(AlignError, match="does not fit"):  # auto picks pocketsphinx for English
        encode_recording(rec, WRONG, lang="en")


@pytest.fixture
def coverage_off_the_edge(monkeypatch):
    """WRONG spans 79-84 % of the recording once aligned, by what espeak-ng spoke before in the process: on the
    edge of the coverage rule (MIN_COVERAGE 0.8), which the tests using this are not about."""
    import mpeg4fa.speech.align.core as core

    monkeypatch.setattr(core, "MIN_COVERAGE", 0.7)


def test_no_fit_check_aligns_anyway(rec, coverage_off_the_edge):
    al = align_recording(rec, WRONG, lang="en", method="pocketsphinx", fit_check=False)
    assert al.fit < FIT_LIMITS["pocketsphinx"]
    assert encode_recording(rec, WRONG, lang="en", fit_check=False).speech.duration == pytest.approx(rec.duration)


def test_dtw_reports_its_path_cost_but_does_not_judge_it(rec):
    """No limit for DTW: on real speech the right transcript's cost overlaps a wrong one's (bench_align)."""
    assert FIT_LIMITS["dtw"] is None
    al = align_recording(rec, WRONG_SAME_SPAN, lang="en", method="dtw")
    assert math.isfinite(al.fit) and al.fit > 0


def _write(path, samples, rate):
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        w.writeframes(np.asarray(samples).astype("<i2").tobytes())
    return path


def test_cli_exit_1_with_one_line_and_no_fit_check(cli, tmp_path, rec, coverage_off_the_edge):
    wav = _write(tmp_path / "please.wav", rec.samples, rec.rate)
    out = tmp_path / "talk.fba"
    code, _, err = cli("encode", "--speech", wav, "--transcript", WRONG, "-o", out)
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert "does not fit" in err and "please.wav" in err and "--no-fit-check" in err
    assert not out.exists()
    code, _, err = cli("encode", "--speech", wav, "--transcript", WRONG, "--no-fit-check", "-o", out)
    assert code == 0, err
    assert out.stat().st_size > 0
    code, _, err = cli("encode", "Hello.", "--text", "--no-fit-check", "-o", out)
    assert code == 2 and "--no-fit-check goes with --speech" in err
