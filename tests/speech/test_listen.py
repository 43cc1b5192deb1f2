"""Lip sync from a recording alone (mpeg4fa.speech.listen): espeak-ng speech with known phone times, and
noise, silence and music that must leave the mouth at rest. The English figure the issue asks for (closures
within 40 ms for >= 90 %) is not reached by pocketsphinx's English phone loop and the closure detector on
espeak-ng's voices: that check is xfail with the measured figure; the rest hold what is reached now
(tools/bench_lipsync_audio.py measures more sentences)."""
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pocketsphinx")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))

import espeak_fresh  # noqa: E402

from mpeg4fa.speech.align import Recording  # noqa: E402
from mpeg4fa.speech.encoder import encode_utterance, phones  # noqa: E402
from mpeg4fa.speech.listen import (ENGLISH_DEFAULT, Phone, choose_recognizer, listen, phone_events,  # noqa: E402
                                   phone_timings, recognize_phones, voice_activity)
from mpeg4fa.speech.listen.closures import (closure_probability, closure_spans,  # noqa: E402
                                            refine_closures)
from mpeg4fa.speech.listen.compare import agreement, closure_onsets, onset_score, rest_share, shuts  # noqa: E402
from mpeg4fa.speech.listen.phones import speech_share  # noqa: E402
from mpeg4fa.speech.listen.signals import music, white_noise  # noqa: E402
from mpeg4fa.speech.utterance import Timing  # noqa: E402

EN = ["Please bring the maps back before the boat leaves.",
      "Peter picked a peck of pickled peppers, and my mother baked bread."]
ES = ["Mi madre compró pan y manzanas en el mercado.", "Pablo bebe un poco de vino blanco por la mañana."]


def spoken(text, lang):
    """The transcript path's utterance of espeak-ng speech (its phone times are the truth) and the recording, the
    same every run (tools/espeak_fresh.py: one fresh process a sentence)."""
    utt = phones(espeak_fresh.spoken(text, lang=lang, rate=160))
    return utt, Recording(utt.speech.samples, utt.speech.rate, text[:20])


def as_recording(x, rate=16000):
    return Recording(np.clip(np.rint(np.asarray(x) * 32768), -32768, 32767).astype(np.int16), rate, "signal")


@pytest.fixture(scope="module")
def scores():
    out = {}
    for lang, texts in (("en", EN), ("es", ES)):
        hits = total = 0
        agree = []
        for text in texts:
            ref, rec = spoken(text, lang)
            heard = listen(rec, recognizer="phonetic", lang=lang)
            got = phones(heard.utterance).timings
            s = onset_score(ref.timings, got)
            hits, total = hits + s.hits, total + s.reference
            agree.append(agreement(ref.timings, got, rec.duration)[0])
        out[lang] = (hits / total, float(np.mean(agree)), total)
    return out


def test_english_closures_and_frames_follow_the_transcript_path(scores):
    share, agree, total = scores["en"]
    assert total >= 10
    assert share >= 0.75, share  # measured 0.94 on these two, 16 of 17, with the span scorer as before it (0.88
    # before the detector's labials were confirmed, 0.76 with the detector trained on fewer voices; 52-65 % without
    # it, mpeg4fa.speech.listen.closures)
    assert agree >= 0.5, agree  # measured 0.63 (0.62 before the span scorer, 0.56 before the detector)


def test_spanish_frames_follow_the_transcript_path(scores):
    share, agree, total = scores["es"]
    assert agree >= 0.42, agree  # measured 0.55 (0.44 before the detector)
    assert share >= 0.6, share  # measured 0.90, 9 of 10 ([β] no longer counted: 0.60, 9 of 15, before; 0.27 before
    # the detector)


TARGET_EN = EN + ["Bring me the blue bucket from the boat, please.", "Pam and Bob swam past the small bamboo pier.",
                  "My mom put maple butter on both pancakes.", "The puppy jumped up and bumped the lamp."]
TARGET_ES = ES + ["Mi papá compra pimientos en el mercado.", "Pepe pinta un mapa para Marta."]


@pytest.mark.xfail(reason="issue 28's English target, on 8 English sentences in two voices (96 closures): measured "
                          "86 of 96, 0.896, every run since each sentence is spoken by a fresh process with "
                          "espeak-ng's random seed set (tools/espeak_fresh.py; 84-86 before: espeak-ng's audio "
                          "changed with what it spoke before and, in its +f voices, with the time); Spanish 22 of "
                          "24; tools/bench_lipsync_audio.py's enlarged set: English 92.2 % (2026-12-06): at the "
                          "target there, not here. Strict: the figure no longer varies, so a pass means the "
                          "recogniser got better and this mark should go",
                   strict=True)
def test_closure_onsets_reach_the_issue_targets():
    share = {}
    for lang, texts, voices in (("en", TARGET_EN, ("en-gb-x-rp+f3", "en-us")), ("es", TARGET_ES, ("es",))):
        hits = total = 0
        for text in texts:
            for voice in voices:
                utt = phones(espeak_fresh.spoken(text, lang=lang, voice=voice, rate=160))
                rec = Recording(utt.speech.samples, utt.speech.rate, text[:20])
                s = onset_score(utt.timings, phones(listen(rec, recognizer="phonetic", lang=lang).utterance).timings)
                hits, total = hits + s.hits, total + s.reference
        share[lang] = (hits / total, hits, total)
    assert share["en"][0] >= 0.9 and share["es"][0] >= 0.75, share


@pytest.mark.parametrize("name, signal", [
    ("white noise at -30 dBFS", lambda: white_noise(6.0, dbfs=-30.0)),
    ("music", lambda: music(6.0)),
    ("digital silence", lambda: np.zeros(16000 * 3)),
    ("a 440 Hz tone", lambda: 0.3 * np.sin(2 * np.pi * 440 * np.arange(16000 * 3) / 16000)),
])
def test_noise_music_and_silence_leave_the_mouth_at_rest(name, signal):
    rec = as_recording(signal())
    heard = listen(rec, recognizer="phonetic")
    assert rest_share(heard.utterance.timings, rec.duration) >= 0.95, name
    encoded = encode_utterance(heard.utterance, level="low")
    mouth = np.abs(encoded.values[:, 2:17]).max(axis=1)  # FAPs 3-17: jaw and lips
    assert (mouth <= 1).mean() >= 0.95, name


def test_speech_is_voice_active_and_noise_is_not():
    ref, rec = spoken(EN[0], "en")
    active = voice_activity(rec.floats(), rec.rate)
    assert active.mean() >= 0.8
    noisy = rec.floats()[: len(rec.samples)]
    mixed = np.r_[white_noise(2.0, rec.rate, -30.0), noisy]
    a = voice_activity(mixed, rec.rate)
    assert a[:190].mean() <= 0.05 and a[200:].mean() >= 0.7


def test_phones_map_through_ipa_features_and_silence_is_a_pause():
    events = phone_events([Phone("SIL", 0.0, 0.1), Phone("M", 0.1, 0.2), Phone("AY", 0.2, 0.4), Phone("+NSN+", 0.4, 0.5)])
    timings = phone_timings(events)
    assert [t.viseme for t in timings] == ["none", "PP", "AA", "ih", "none"]  # AY split as a diphthong is
    assert timings[2].start == pytest.approx(0.2) and timings[3].end == pytest.approx(0.4)


def test_recognised_phones_are_timed_inside_the_recording():
    ref, rec = spoken(EN[0], "en")
    found = recognize_phones(rec)
    assert found and all(0 <= p.start < p.end <= rec.duration + 1e-9 for p in found)
    assert {"P", "B", "M"} & {p.name for p in found}
    assert len(closure_onsets(ref.timings)) >= 5


def test_auto_takes_the_measured_default_for_english_and_phones_for_the_rest():
    assert choose_recognizer("auto", "auto") == ENGLISH_DEFAULT
    assert choose_recognizer("auto", "en-gb") == ENGLISH_DEFAULT
    assert choose_recognizer("auto", "es") == "phonetic"
    assert choose_recognizer("words", "es") == "words"
    assert choose_recognizer("either", "en-us") == "either" and choose_recognizer("either", "fr") == "phonetic"
    with pytest.raises(ValueError):
        choose_recognizer("nonsense", "en")


def test_words_are_recognised_and_aligned_as_a_transcript():
    ref, rec = spoken(EN[0], "en")
    heard = listen(rec, recognizer="words", lang="en")
    assert heard.recognizer == "words" and len(heard.words) >= 5
    assert "please" in [w.word for w in heard.words]
    assert heard.utterance.markup.text.split()[0] == "please"
    s = onset_score(ref.timings, phones(heard.utterance).timings)
    # measured 3 of the 7 closures within 40 ms (the word recogniser misreads espeak-ng's voice: the accuracy target
    # itself is test_closure_onsets_reach_the_issue_targets'); none at all would be a broken path
    assert s.hits >= 2, s


def test_either_takes_the_phones_on_espeak_ngs_voice():
    # the word recogniser bends espeak-ng's formant voice into words that fit it far worse than the free phone loop
    # (measured -72 to -27 a sentence, 2026-12-06): ``either`` keeps the phones path, closures and all
    from mpeg4fa.speech.listen.core import WORDS_CONFIDENT

    ref, rec = spoken(EN[1], "en")
    heard = listen(rec, recognizer="either", lang="en")
    assert heard.recognizer == "phonetic" and heard.confidence < WORDS_CONFIDENT - 2, heard.confidence
    assert heard.words == () and heard.utterance.timings == listen(rec, recognizer="phonetic").utterance.timings
    assert listen(rec, recognizer="either", lang="es").recognizer == "phonetic"  # English only: no word decoding
    assert np.isnan(listen(rec, recognizer="phonetic").confidence)


def test_either_settles_a_recordings_recogniser_on_the_first_block_it_judges():
    from mpeg4fa.speech.listen.core import WORDS_CONFIDENT, Listened, settled

    def block(confidence):
        return Listened(None, "phonetic", confidence=confidence)

    assert settled("either", block(WORDS_CONFIDENT + 1)) == "words"
    assert settled("either", block(WORDS_CONFIDENT - 1)) == "phonetic"
    assert settled("either", block(float("nan"))) == "either"  # a silent block judged nothing
    assert settled("either", block(float("-inf"))) == "either"  # speech, but no word heard in it: not judged
    assert settled("phonetic", block(WORDS_CONFIDENT + 1)) == "phonetic"  # only either is settled


def test_an_empty_recording_is_silent():
    heard = listen(Recording(np.zeros(0, np.int16), 16000, "empty"))
    assert heard.silent and heard.utterance.timings == ()
    assert len(encode_utterance(heard.utterance).stream) == 1


def test_expression_for_the_whole_clip():
    heard = listen(as_recording(np.zeros(16000)), expression=("joy", 30))
    (cue,) = heard.utterance.cues
    assert (cue.expression, cue.intensity, cue.start) == ("joy", 30, 0.0)


def test_a_long_recording_is_heard_in_blocks_cut_between_words():
    import io

    from mpeg4fa.speech.align.recording import frame_levels
    from mpeg4fa.speech.listen.stream import Source, blocks, stream_listened

    parts = [spoken(t, "en")[1].samples for t in EN * 3]
    x = np.concatenate(parts)
    rate = 22050
    cuts = list(blocks(Source("long", rate, len(x) / rate, iter(np.array_split(x, 7))), block_seconds=5.0))
    assert len(cuts) >= 3 and sum(len(r.samples) for _, r in cuts) == len(x)
    for offset, rec in cuts[:-1]:
        end = int(round((offset + rec.duration) * rate))
        around = frame_levels(x[end - 220:end + 220] / 32768.0, rate)
        assert around.min() <= frame_levels(x / 32768.0, rate).max() - 30  # a quiet moment, not mid-vowel
    out, timings = io.BytesIO(), io.StringIO()
    heard = stream_listened(Source("long", rate, len(x) / rate, iter([x])), out, timings=timings, block_seconds=5.0)
    assert heard.blocks == len(cuts) and heard.frames == int(np.ceil(len(x) / rate * 25))
    import json

    starts = [t["start"] for t in json.loads(timings.getvalue())]
    assert starts == sorted(starts) and starts[-1] > len(x) / rate - 3


def test_either_hears_a_long_recording_of_espeak_ngs_voice_by_its_phones():
    import io

    from mpeg4fa.speech.listen.stream import Source, stream_listened

    x = np.concatenate([spoken(t, "en")[1].samples for t in EN * 2])
    rate = 22050
    heard = stream_listened(Source("long", rate, len(x) / rate, iter([x])), io.BytesIO(), recognizer="either",
                            block_seconds=4.0, two_cores=False)
    assert heard.blocks >= 3 and heard.recognizer == "phonetic" and heard.words == 0


def test_refine_snaps_a_heard_labial_to_the_closure_and_adds_a_sure_one():
    heard = [Phone("AA", 0.0, 0.20), Phone("M", 0.20, 0.30), Phone("AA", 0.30, 0.50), Phone("G", 0.50, 0.56),
             Phone("IY", 0.56, 0.80), Phone("AE", 0.80, 1.00), Phone("B", 1.00, 1.05), Phone("AA", 1.05, 1.20)]
    spans = [(0.16, 0.26, 0.5),   # 40 ms before the heard M: the M starts there
             (0.49, 0.56, 0.95),  # sure, under a G: shut (B)
             (0.85, 0.95, 0.95)]  # sure, under an open vowel: shut too, unless the open-phone veto is on
    # and the B at 1.00 has no closure near it: not shut (read as D)
    out = refine_closures(heard, spans)
    names = [(p.name, round(p.start, 2), round(p.end, 2)) for p in out]
    assert ("M", 0.16, 0.30) in names and ("AA", 0.0, 0.16) in names
    assert ("B", 0.49, 0.56) in names and not any(p.name == "G" for p in out)
    assert ("B", 0.85, 0.95) in names and ("AE", 0.80, 0.85) in names
    assert ("D", 1.00, 1.05) in names
    assert all(a.end <= b.start + 1e-9 for a, b in zip(out, out[1:]))
    names = [(p.name, round(p.start, 2), round(p.end, 2))
             for p in refine_closures(heard, spans, open_veto=True, confirm=False)]
    assert ("AE", 0.80, 1.00) in names and ("B", 1.00, 1.05) in names


def test_a_closure_is_speech_until_its_release():
    # a p after s lies in a voiceless stretch: voice activity only at its release still keeps it shut
    active = np.r_[np.zeros(30, dtype=bool), np.ones(20, dtype=bool)]
    assert speech_share(0.20, 0.29, active, closure=True) >= 0.5
    assert speech_share(0.20, 0.29, active) < 0.5
    assert speech_share(0.05, 0.14, active, closure=True) == 0.0  # no release after it: not speech


def test_the_detector_shuts_the_lips_where_the_transcript_path_does():
    # a sentence it was not trained on: frames inside the transcript path's closures against the rest
    ref, rec = spoken("Bob might move the piano before the bus comes by.", "en")
    p = closure_probability(rec.floats(), rec.rate)
    centre = 0.0125 + 0.01 * np.arange(len(p))
    inside = np.zeros(len(p), dtype=bool)
    for t in ref.timings:
        if t.viseme == "PP":
            inside |= (centre >= t.start) & (centre < t.end)
    assert inside.sum() >= 30
    assert p[inside].mean() >= 0.4 and p[~inside].mean() <= 0.1, (p[inside].mean(), p[~inside].mean())
    onsets = closure_onsets(ref.timings)
    found = [a for a, _, _ in closure_spans(p)]
    # measured: 0.64 inside, 0.05 outside; every closure onset of the transcript path within 40 ms of a detected span
    assert np.mean([np.min(np.abs(np.array(found) - o)) <= 0.04 for o in onsets]) >= 0.8


def test_the_detector_finds_no_closure_in_noise_or_music():
    for x in (white_noise(5.0, dbfs=-30.0), music(5.0)):
        spans = closure_spans(closure_probability(x, 16000))
        assert sum(b - a for a, b, _ in spans) <= 0.25, spans  # measured 0 s (noise), 0.07 s (music)


def test_a_bilabial_approximant_is_no_closure_to_find():
    # espeak-ng's Spanish b/v between vowels is [β]: the lips near, not shut; shown as PP, found or not
    assert shuts("p") and shuts("m") and shuts("ph:p") and shuts("bʰ") and not shuts("β")
    ref = [Timing("a", "AA", 0.0, 0.1), Timing("β", "PP", 0.1, 0.15), Timing("e", "E", 0.15, 0.3),
           Timing("p", "PP", 0.3, 0.35), Timing("a", "AA", 0.35, 0.5)]
    s = onset_score(ref, [Timing("b", "PP", 0.1, 0.15), Timing("p", "PP", 0.31, 0.35)])
    assert (s.reference, s.hits, s.extra) == (1, 1, 0)
    assert onset_score(ref, [Timing("p", "PP", 0.31, 0.35)]).share == 1.0
    assert onset_score(ref, [Timing("b", "PP", 0.2, 0.25)]).hits == 0


def test_a_closure_from_rest_is_found_where_the_other_track_rests_or_shuts():
    # the reference's b starts the file (rest before it: the neutral face's lips are already in contact), its p
    # follows a pause; its m follows a vowel, so only a closure onset within 40 ms finds it
    ref = [Timing("b", "PP", 0.0, 0.05), Timing("a", "AA", 0.05, 0.2), Timing("", "none", 0.2, 0.25),
           Timing("p", "PP", 0.25, 0.3), Timing("a", "AA", 0.3, 0.5), Timing("m", "PP", 0.5, 0.55),
           Timing("a", "AA", 0.55, 0.7)]
    other = [Timing("", "none", 0.0, 0.04), Timing("a", "AA", 0.04, 0.2), Timing("b", "PP", 0.2, 0.3),
             Timing("a", "AA", 0.3, 0.7)]
    assert onset_score(ref, other).hits == 0  # 50 ms and more from every onset of the other track
    s = onset_score(ref, other, from_rest=True)
    assert (s.reference, s.hits) == (3, 2)  # b: at rest there; p: shut from 0.20; m: the lips open
    opened = [Timing("a", "AA", 0.0, 0.2), Timing("t", "DD", 0.2, 0.3), Timing("a", "AA", 0.3, 0.7)]
    assert onset_score(ref, opened, from_rest=True).hits == 0  # open at both onsets from rest


def test_the_span_scorer_tells_closures_from_other_silences():
    # sentences it was not trained on: the detector's spans that overlap a transcript-path closure score higher
    # than those that do not (a t, k or pause), judged with what the phone loop heard
    from mpeg4fa.speech.align.recording import resample
    from mpeg4fa.speech.listen.closures import (RATE, features, log_mel, predict, span_scores, span_weights,
                                                weights)

    if span_weights() is None:
        pytest.skip("no span scorer in closure_weights (tools/train_listen_closures.py --spans)")
    closed, other = [], []
    for text in EN + ["Mark put the empty box beside the map on my desk."]:
        ref, rec = spoken(text, "en")
        levels = log_mel(resample(rec.floats(), rec.rate, RATE))
        p = predict(features(levels), *weights())
        spans = closure_spans(p)
        scores = span_scores(levels, p, recognize_phones(rec, closures=False), spans)
        truth = [(t.start, t.end) for t in ref.timings if t.viseme == "PP" and shuts(t.phoneme)]
        for (a, b, _), score in zip(spans, scores):
            (closed if any(min(b, d) - max(a, c) >= 0.01 for c, d in truth) else other).append(score)
    assert len(closed) >= 10 and len(other) >= 3, (len(closed), len(other))
    # measured: 25 closure spans at 0.91 on average, 10 others (t, d, k, pauses) at 0.08
    assert np.mean(closed) >= 0.7 and np.mean(other) <= 0.3, (len(closed), len(other), np.mean(closed), np.mean(other))
