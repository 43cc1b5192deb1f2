"""Ten espeak-ng languages through the IPA route: every phoneme maps, the shapes make sense, the stream
plays and its mouth follows the speech energy; ``--lang auto`` picks the voice by script; the CLI lists
the voices and refuses an unknown code in one line.

Each sentence is spoken once per module (``spoken``, ``said``). Figures printed with ``-s``.
"""
from __future__ import annotations

import json

import numpy as np
import pytest

from mpeg4fa.fba import decode
from mpeg4fa.render.audio import Audio
from mpeg4fa.render.lipsync import lipsync_report
from mpeg4fa.render.video import probe_media
from mpeg4fa.speech import TTSError, encode_text
from mpeg4fa.speech.ipa import ipa_visemes, parse, viseme_of
from mpeg4fa.speech.tts.espeak import EspeakEngine, language_codes

SENTENCES = {
    "es": "El perro de mi vecino come pan y bebe agua todas las mañanas.",
    "fr": "Le petit garçon a vu une lune rouge au-dessus du pont.",
    "de": "Der kleine Junge möchte heute über die Brücke gehen.",
    "it": "Il ragazzo mangia una buona pizza con gli amici.",
    "pt": "O menino comeu pão com manteiga e bebeu um copo de leite.",
    "ru": "Мальчик пошёл в школу утром и купил хлеб.",
    "ja": "こんにちは、きょうはとてもいいてんきですね。",
    "hi": "मेरा नाम राम है और मैं दिल्ली में रहता हूँ।",
    "ar": "ذهب الولد إلى المدرسة في الصباح.",
    "yue": "我哋今日去飲茶，好開心。",
}
ROUNDED = {"oh", "ou"}
OPEN_VOWELS = set("aɑɐæɒ")
BILABIAL = set("pbm")


@pytest.fixture(scope="module")
def spoken() -> dict:
    """Each sentence's speech with IPA phoneme events (espeak-ng, once)."""
    engine = EspeakEngine()
    return {lang: engine.synthesize(text, voice=lang, ipa=True) for lang, text in SENTENCES.items()}


@pytest.fixture(scope="module")
def said(procedural_face, tmp_path_factory) -> dict:
    """Each sentence encoded, decoded and played (a small MP4 of the procedural head), once."""
    from mpeg4fa.say import say

    folder = tmp_path_factory.mktemp("languages")
    return {lang: (say(text, folder / f"{lang}.mp4", lang=lang, face=procedural_face, width=32, height=32,
                       samples=0), folder / f"{lang}.mp4") for lang, text in SENTENCES.items()}


@pytest.mark.parametrize("lang", SENTENCES)
def test_every_phoneme_espeak_emits_maps_to_a_viseme(spoken, lang):
    phonemes = list(spoken[lang].phonemes())
    placed = ipa_visemes(phonemes)  # raises listing any phoneme the tables lack
    names = sorted({p.text for p in phonemes if p.text.strip()})
    print(f"\n{lang}: {' '.join(names)}")
    assert len(names) >= 10 and {v for _, v, _, _ in placed} - {"none"}


@pytest.mark.parametrize("lang", SENTENCES)
def test_rounded_vowels_are_rounded_bilabials_shut_open_vowels_open(spoken, lang):
    seen = set()
    for event in spoken[lang].phonemes():
        for segment in parse(event.text)[0]:
            viseme = viseme_of(segment)
            if segment.symbol in "ouy":
                seen.add("rounded")
                assert viseme in ROUNDED, (lang, event.text)
            if segment.symbol in BILABIAL:
                seen.add("bilabial")
                assert viseme == "PP", (lang, event.text)
            if segment.symbol in OPEN_VOWELS:
                seen.add("open")
                assert viseme == "AA", (lang, event.text)
    assert {"bilabial", "open"} <= seen, (lang, seen)


def test_all_ten_languages_show_rounded_vowels_somewhere(spoken):
    with_rounding = [lang for lang, speech in spoken.items()
                     if any(s.symbol in "ouy" for e in speech.phonemes() for s in parse(e.text)[0])]
    assert len(with_rounding) >= 8, with_rounding


@pytest.mark.parametrize("lang", SENTENCES)
def test_the_stream_decodes_plays_and_the_mouth_follows_the_energy(said, procedural_face, lang):
    result, video = said[lang]
    stream = decode(result.data)
    speech = result.encoded.speech
    assert probe_media(video).n_frames == result.result.n_frames >= len(stream) > 10
    audio = Audio((speech.samples.astype(np.float32) / 32768.0)[:, None], speech.rate)
    report = lipsync_report(procedural_face, stream, audio, name=lang)
    lags = dict(zip(range(-report.max_lag, report.max_lag + 1), report.lag_correlations))
    print(f"\n{lang}: r0 {report.correlation:+.3f}, best lag {report.best_lag_frames:+d} "
          f"(r {report.best_correlation:+.3f}), {len(stream)} frames")
    assert report.correlation > 0.2, lang
    assert max(lags[-1], lags[0], lags[1]) >= report.best_correlation - 0.05, lang


@pytest.mark.parametrize("text, voice", [("Привет, как дела?", "ru"), ("مرحبا بك في البيت", "ar"),
                                         ("नमस्ते, आप कैसे हैं?", "hi"), ("こんにちは、げんきですか。", "ja"),
                                         ("カタカナのテスト", "ja")])
def test_auto_picks_the_voice_by_script(text, voice):
    enc = encode_text(f"Hello. {text}", lang="auto", level="high")
    assert enc.speech.voice == f"en-us+{voice}"
    assert {t.viseme for t in enc.utterance.timings} - {"none"}


def test_auto_keeps_latin_english_and_lone_han_mandarin():
    enc = encode_text("Hello 你好", lang="auto")
    assert enc.speech.voice == "en-us" and {t.set for t in enc.utterance.timings} == {"mpeg4", "zh"}


def test_kanji_in_japanese_text_are_refused_where_they_are():
    from mpeg4fa.speech import MarkupError

    with pytest.raises(MarkupError, match="reads kana, not kanji: '今日'") as info:
        encode_text("こんにちは、\n今日はいいてんきです。", lang="auto")
    assert (info.value.line, info.value.column) == (2, 1)
    with pytest.raises(MarkupError, match="not kanji"):
        encode_text("きょうは天気", lang="ja")


def test_an_explicit_language_code_takes_the_whole_text():
    enc = encode_text("(joy, 40, 0.5) Hola, ¿qué tal? Muy bien.", lang="es")
    assert enc.speech.voice == "es" and enc.utterance.cues[0].start >= 0
    assert "es" in language_codes() and "yue" in language_codes()


def test_english_codes_keep_the_english_table():
    for code in ("en-gb", "EN-GB"):
        enc = encode_text("Hello there, how are you?", lang=code)
        assert enc.speech.voice == code
        assert "oU" in {t.phoneme for t in enc.utterance.timings} or "@U" in {t.phoneme for t in enc.utterance.timings}


def test_unknown_languages_and_engines_without_ipa_are_refused():
    with pytest.raises(TTSError, match="unknown language 'xx'") as info:
        encode_text("Hola", lang="xx")
    assert "mpeg4fa voices" in info.value.hint
    with pytest.raises(TTSError, match="no IPA phonemes"):
        encode_text("Hola", lang="es", engine="estimate")


def test_voices_cli_lists_codes_and_json(cli):
    code, out, _ = cli("voices")
    assert code == 0 and any(line.split()[0] == "es" for line in out.splitlines())
    code, out, _ = cli("voices", "--json")
    rows = json.loads(out)
    assert code == 0 and len(rows) > 50
    by_code = {r["language"]: r for r in rows}
    assert by_code["es"]["visemes"] == "IPA features" and by_code["en-us"]["visemes"] == "English table"
    assert {"language", "name", "identifier", "languages"} <= set(rows[0])


def test_encode_cli_with_an_unknown_language_is_one_line_exit_1(cli, tmp_path):
    code, _, err = cli("encode", "Hola", "-o", tmp_path / "a.fba", "--lang", "xx")
    assert code == 1 and "unknown language 'xx'" in err and "mpeg4fa voices" in err
    assert len(err.strip().splitlines()) == 1 and not (tmp_path / "a.fba").exists()


def test_encode_cli_speaks_spanish(cli, tmp_path):
    out, timings = tmp_path / "a.fba", tmp_path / "t.json"
    code, _, err = cli("encode", "Hola, ¿qué tal?", "-o", out, "--lang", "es", "--timings", timings)
    assert code == 0, err
    assert {row["viseme"] for row in json.loads(timings.read_text(encoding="utf-8"))} >= {"oh", "AA"}


def test_each_mouth_follows_its_own_speech_better_than_the_next_languages(said, procedural_face):
    """A control for the correlation above (short clips that start in silence share an onset that alone
    gives some r): paired with another language's audio the same mouth correlates less."""
    langs = list(SENTENCES)
    own, other = [], []
    for k, lang in enumerate(langs):
        result, _ = said[lang]
        stream = decode(result.data)
        for speech, into in ((result.encoded.speech, own), (said[langs[(k + 1) % len(langs)]][0].encoded.speech,
                                                           other)):
            audio = Audio((speech.samples.astype(np.float32) / 32768.0)[:, None], speech.rate)
            into.append(lipsync_report(procedural_face, stream, audio).correlation)
    print(f"\nr0 own speech {np.mean(own):+.3f}, the next language's {np.nanmean(other):+.3f}")
    assert np.mean(own) > np.nanmean(other) + 0.2
