"""Every phoneme has a mouth (issue 26, item 1): whatever espeak-ng says, in any voice, maps to a viseme
with no error, and every phoneme maps exactly (no character of the tables guessed, so no warning).

* every installed voice speaks a sample in its language or script (``data/voice_samples.csv``, keyed by
  the voice's file; ``@Script`` rows are one sample for the voices of a script), through
  :func:`~mpeg4fa.speech.utterance.speak`, the route a user's text takes;
* English words: a fixed random sample of the CMU dictionary that pocketsphinx ships (126,052 words;
  ``tools/every_phoneme.py`` speaks all of them and reports the figures), in chunks of 500 words a
  synthesis, on the American and the British voice;
* the reproducer: ``say "Hello Bokhl"`` exits 0, ``l#`` showing the viseme of ``l``.
"""
from __future__ import annotations

import csv
import random
import warnings
from pathlib import Path

import pytest

from mpeg4fa.speech.errors import PhonemeWarning, TTSError
from mpeg4fa.speech.ipa import phoneme_fallbacks
from mpeg4fa.speech.markup import parse_markup
from mpeg4fa.speech.tts.espeak import EspeakEngine, voices
from mpeg4fa.speech.utterance import speak
from mpeg4fa.speech.visemes import english_table, english_visemes

SAMPLES = Path(__file__).parent / "data" / "voice_samples.csv"
WORDS_SAMPLE = 4000
CHUNK = 500


def samples() -> dict[str, str]:
    """Voice file -> its sample text (``@Script`` resolved)."""
    with SAMPLES.open(encoding="utf-8", newline="") as handle:
        rows = {r["voice"]: r["text"] for r in csv.DictReader(handle)}
    return {voice: rows[text] if text.startswith("@") else text for voice, text in rows.items()
            if not voice.startswith("@")}


def dictionary_missing(identifier: str) -> bool:
    """Whether the wheel lacks the voice's dictionary (espeak-ng then speaks nothing: fo, kaa, xex in 1.52)."""
    import espeakng_loader

    data = Path(espeakng_loader.get_data_path())
    name = identifier.rsplit("/", 1)[-1].split("-")[0].lower()
    for line in (data / "lang" / identifier).read_text("utf-8", "replace").splitlines():
        if line.split()[:1] == ["dictionary"]:
            name = line.split()[1]
    return not (data / f"{name}_dict").exists()


@pytest.fixture(scope="module")
def engine() -> EspeakEngine:
    return EspeakEngine()


ALL_VOICES = voices()


def test_every_voice_has_a_sample():
    assert {v.identifier for v in ALL_VOICES} <= set(samples()), "add a row to tests/speech/data/voice_samples.csv"


@pytest.mark.parametrize("voice", ALL_VOICES, ids=lambda v: v.identifier)
def test_every_voice_speaks_its_sample_and_every_phoneme_maps(engine, voice):
    text = samples()[voice.identifier]
    assert voice.speaks is not dictionary_missing(voice.identifier)
    if dictionary_missing(voice.identifier):  # the voice cannot speak: refused in one line, no traceback
        with pytest.raises(TTSError, match=f"no dictionary for {voice.identifier} in this installation"):
            speak(parse_markup(text), engine, lang=voice.language, voice=voice.identifier)
        return
    with phoneme_fallbacks(voice.identifier) as log:
        said = speak(parse_markup(text), engine, lang=voice.language, voice=voice.identifier)
    assert not log.seen, log.message()
    shown = {t.viseme for t in said.timings} - {"none"}
    assert len(shown) >= 5, (voice.identifier, shown)


def cmu_words() -> list[str]:
    """The headwords of the CMU dictionary pocketsphinx ships (no alternate pronunciations)."""
    pocketsphinx = pytest.importorskip("pocketsphinx")
    path = Path(pocketsphinx.__file__).parent / "model" / "en-us" / "cmudict-en-us.dict"
    with path.open(encoding="utf-8") as handle:
        return [line.split(" ", 1)[0] for line in handle if line.strip() and "(" not in line.split(" ", 1)[0]]


@pytest.mark.parametrize("voice", ["en-us", "en-gb"])
def test_english_words_all_map(engine, voice):
    words = random.Random(26).sample(cmu_words(), WORDS_SAMPLE)
    mnemonics: set[str] = set()
    with phoneme_fallbacks(voice) as log:
        for k in range(0, len(words), CHUNK):
            phonemes = list(engine.synthesize(" ".join(words[k:k + CHUNK]), voice=voice).phonemes())
            pairs = english_visemes(phonemes)
            assert len(pairs) >= len(phonemes)
            mnemonics |= {p.text.lstrip("',") for p in phonemes}
    assert not log.seen, log.message()
    beyond = sorted(m for m in mnemonics - set(english_table()) if not m.startswith("_"))
    print(f"\n{voice}: {len(mnemonics)} mnemonics in {WORDS_SAMPLE} words; beyond the English table: {beyond}")


def test_hello_bokhl_encodes_with_l_hash_shown_as_l(engine):
    from mpeg4fa.speech.encoder import encode_text

    with warnings.catch_warnings():
        warnings.simplefilter("error", PhonemeWarning)  # l# is a known phoneme (ɬ): no guess, no warning
        encoded = encode_text("Hello Bokhl", engine=engine)
    timings = encoded.utterance.timings
    by_phoneme = {t.phoneme.lstrip("',"): t.viseme for t in timings}
    assert by_phoneme["l#"] == by_phoneme["l"] == "nn"
    assert [t.viseme for t in timings if t.viseme != "none"] == ["kk", "E", "nn", "oh", "PP", "oh", "kk", "nn"]
    assert len(encoded.stream) > 10


def test_cli_encode_hello_bokhl_exits_0(tmp_path, capsys):
    from mpeg4fa.cli import main

    assert main(["encode", "Hello Bokhl", "-o", str(tmp_path / "w.fba")]) == 0
    err = capsys.readouterr().err
    assert "error" not in err and (tmp_path / "w.fba").stat().st_size > 0


def test_a_phoneme_no_table_knows_is_one_warning_line_at_the_end(tmp_path, capsys, monkeypatch):
    """Were l# in neither English table, Bokhl would still encode: l# read as IPA letters (l), one warning line
    for the whole text, though its two English runs (around the Chinese one) are mapped apart."""
    from mpeg4fa.cli import main
    from mpeg4fa.speech import visemes

    lacking = {k: v for k, v in visemes.english_ipa().items() if k != "l#"}
    monkeypatch.setattr(visemes, "english_ipa", lambda: lacking)
    assert main(["encode", "Hello Bokhl, 你好, Bokhl!", "-o", str(tmp_path / "w.fba")]) == 0
    warned = [line for line in capsys.readouterr().err.splitlines() if "warning" in line]
    assert len(warned) == 1 and warned[0].startswith("mpeg4fa encode: warning: <text>: 2 phonemes")
    assert "'l#' x2 (a mnemonic of no English phoneme table; read as l)" in warned[0]
