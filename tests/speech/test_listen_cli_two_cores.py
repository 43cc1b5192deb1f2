"""A long recording is heard two blocks at a time, one in a helper process (pocketsphinx holds the GIL while
it decodes, so only a second process uses a second core): the stream is the one a single process writes, in
the same order and on the same clock (byte for byte on the phones path; the words path's alignment hears
espeak-ng's rendering of the words, whose audio depends on what the process spoke before, and the aligner's decoder
carries its state from one alignment to the next). Speed itself is measured by tools/bench_lipsync_audio.py, not here."""
import io
import json
import os
import resource

import numpy as np
import pytest

pytest.importorskip("pocketsphinx")

from mpeg4fa.fba import decode  # noqa: E402
from mpeg4fa.speech.listen.stream import Source, stream_listened  # noqa: E402
from mpeg4fa.speech.tts.espeak import EspeakEngine  # noqa: E402
from mpeg4fa.speech.utterance import Timing  # noqa: E402

TEXTS = ["Please bring the maps back before the boat leaves.", "My mother baked bread for the whole family.",
         "Peter picked a peck of pickled peppers."]


@pytest.fixture(scope="module")
def long_speech():
    engine = EspeakEngine()
    parts = []
    for text in TEXTS * 2:
        s = engine.synthesize(text, voice="en-us", rate=170)
        parts += [s.samples, np.zeros(int(0.5 * s.rate), np.int16)]
    return np.concatenate(parts), s.rate


def _helper_cpu() -> float:
    r = resource.getrusage(resource.RUSAGE_CHILDREN)
    return r.ru_utime + r.ru_stime


def _heard(x, rate, two_cores):
    out, timings = io.BytesIO(), io.StringIO()
    heard = stream_listened(Source("long", rate, len(x) / rate, iter(np.array_split(x, 5))), out, timings=timings,
                            block_seconds=4.0, two_cores=two_cores, level="low")
    items = json.loads(timings.getvalue())
    return heard, out.getvalue(), [Timing(i["phoneme"], i["viseme"], i["start"], i["end"]) for i in items]


@pytest.mark.skipif((os.cpu_count() or 1) < 2 or os.name != "posix", reason="one core, or no fork")
def test_two_blocks_at_once_give_the_stream_of_one_process(long_speech):
    x, rate = long_speech
    one, one_bytes, one_timings = _heard(x, rate, False)
    before = _helper_cpu()
    two, two_bytes, two_timings = _heard(x, rate, True)
    assert _helper_cpu() > before  # a helper process did part of the hearing
    assert one.blocks == two.blocks >= 4 and one.frames == two.frames == int(np.ceil(len(x) / rate * 25))
    assert [t.start for t in two_timings] == sorted(t.start for t in two_timings)
    assert two_timings[-1].end > len(x) / rate - 2  # every block's timings, on the recording's clock
    # each utterance decoded from a fresh decoder's state (phones.decode_pcm; 0.95 of frames agreed when each
    # block leaned on the state the last one left): the phones path's stream is the same, byte for byte
    assert one.recognizer == two.recognizer == "phonetic"
    assert one_bytes == two_bytes and one_timings == two_timings
    for data in (one_bytes, two_bytes):
        stream = decode(data)
        assert int(np.sum(stream.skip + 1)) == one.frames  # each a whole stream on the frame grid


def test_one_block_of_phones_starts_no_helper(long_speech):
    x, rate = long_speech
    short = x[:3 * rate]
    before = _helper_cpu()
    out = io.BytesIO()
    heard = stream_listened(Source("short", rate, 3.0, iter([short])), out, recognizer="phonetic", level="low")
    assert heard.blocks == 1 and _helper_cpu() == before


def _forked(fn):
    """``fn()`` in a process forked from this one (pocketsphinx's decoders carry state from one utterance to the
    next, so two runs in one process differ a little; forked, each starts from the same state)."""
    import pickle

    read, write = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read)
        with os.fdopen(write, "wb") as fh:
            fh.write(pickle.dumps(fn()))
        os._exit(0)
    os.close(write)
    with os.fdopen(read, "rb") as fh:
        data = fh.read()
    os.waitpid(pid, 0)
    return pickle.loads(data)


@pytest.mark.skipif((os.cpu_count() or 1) < 2 or os.name != "posix", reason="one core, or no fork")
def test_a_lone_block_under_either_hears_its_phone_loop_in_the_helper(long_speech):
    # a clip too short to be cut in two (under SPLIT_SECONDS) would use one core: the helper decodes its phone
    # loop while the words are decoded here, and the stream is the one a single process writes
    x, rate = long_speech
    short = x[:int(3.5 * rate)]

    def heard(two_cores):
        before = _helper_cpu()
        out, timings = io.BytesIO(), io.StringIO()
        got = stream_listened(Source("short", rate, 3.5, iter([short])), out, timings=timings, recognizer="either",
                              lang="en", two_cores=two_cores, level="low")
        return got.blocks, got.recognizer, out.getvalue(), timings.getvalue(), _helper_cpu() > before

    one, two = _forked(lambda: heard(False)), _forked(lambda: heard(True))
    assert one[0] == two[0] == 1 and one[1] == two[1] == "phonetic"
    assert not one[4] and two[4]  # a helper process did part of the hearing only when asked to
    assert one[2] == two[2] and one[3] == two[3] and len(one[2]) > 100


def _speech_with_pauses(rate, seconds, pauses):
    """``seconds`` of a voiced buzz whose loudness swells like syllables, with silences at ``pauses`` (start s,
    length s): a pause is where nothing sounds."""
    rng = np.random.default_rng(3)
    n = int(seconds * rate)
    t = np.arange(n) / rate
    x = 8000 * np.sin(2 * np.pi * 140 * t) * (0.6 + 0.4 * np.sin(2 * np.pi * 5.5 * t) ** 2)
    x += 300 * rng.standard_normal(n)
    for start, length in pauses:
        a, b = int(round(start * rate)), int(round((start + length) * rate))
        x[a:b] = rng.normal(0, 3, b - a)
    return x.astype(np.int16)


def test_a_clip_shorter_than_a_block_is_cut_in_two_at_the_pause_nearest_its_middle():
    from mpeg4fa.speech.listen.stream import SPLIT_SECONDS, blocks

    rate = 16000
    # 11.7 s: pauses at 2 s (long), 5.5 s (the nearest the middle, 5.85), 6.6 s and 9 s; a 60 ms gap at 5.8 s is
    # a stop's closure, not a pause
    x = _speech_with_pauses(rate, 11.7, [(2.0, 0.5), (5.5, 0.12), (5.8, 0.06), (6.6, 0.2), (9.0, 0.3)])
    got = list(blocks(Source("clip", rate, len(x) / rate, iter(np.array_split(x, 3)))))
    assert [round(o, 2) for o, _ in got] == [0.0, 5.56] and sum(len(r.samples) for _, r in got) == len(x)
    # too short to be worth two: whole
    short = x[:int((SPLIT_SECONDS - 0.5) * rate)]
    assert len(list(blocks(Source("short", rate, len(short) / rate, iter([short]))))) == 1
    # no pause in its middle half (a 60 ms gap is a stop's closure): whole, not cut inside a closure
    plain = _speech_with_pauses(rate, 8.0, [(0.5, 0.3), (4.0, 0.06)])
    assert [round(o, 2) for o, _ in blocks(Source("plain", rate, 8.0, iter([plain])))] == [0.0]
    # a last block after an odd number of blocks pairs with the one before it, whole; after an even number, in two
    for seconds, count in ((15.0, 4), (19.0, 6)):
        long = np.concatenate([x, x])[:int(seconds * rate)]
        assert len(list(blocks(Source("long", rate, seconds, iter([long])), block_seconds=5.0))) == count


@pytest.mark.skipif((os.cpu_count() or 1) < 2 or os.name != "posix", reason="one core, or no fork")
def test_each_block_takes_the_same_recogniser_on_one_core_or_two(monkeypatch):
    # either judges the first pair together, on one core as on two, and that recogniser serves the whole
    # recording: here the first block alone sounds synthetic (phones), the second like a person (words), and
    # together like a person (their mean confidence, weighed by voice, above WORDS_CONFIDENT)
    from mpeg4fa.speech.listen import stream
    from mpeg4fa.speech.listen.core import WORDS_CONFIDENT, Listened
    from mpeg4fa.speech.listen.stream import heard_blocks
    from mpeg4fa.speech.utterance import Utterance

    heard_by = []

    def judged(rec, recognizer, lang):
        person = rec.samples.mean() > 0  # the fake's judgement: by the block's sign
        confidence = WORDS_CONFIDENT + (8.0 if person else -2.0)
        took = recognizer if recognizer != "either" else ("words" if confidence >= WORDS_CONFIDENT else "phonetic")
        heard_by.append(recognizer)
        return Listened(Utterance(None, (), (), None), took, voiced=rec.duration,
                        confidence=confidence if recognizer == "either" else float("nan"))

    monkeypatch.setattr(stream, "listen", judged)
    rate = 16000
    parts = []
    for sign in (-1, 1, 1, -1, 1):  # 6 s blocks, each ending in a 50 ms gap that the block before is cut at
        part = np.full(6 * rate, 1000 * sign, np.int16)
        part[int(5.9 * rate):int(5.95 * rate)] = 0
        parts.append(part)
    x = np.concatenate(parts)
    seen = []
    for helper in (False, True):
        heard_by.clear()
        with stream._helper(helper) as pool:
            got = [heard.recognizer for _, _, heard in heard_blocks(Source("x", rate, 30.0, iter([x])), 6.0, "either",
                                                                     "en", pool, None)]
        seen.append(got)
        if not helper:  # the pair heard by either, the first block again by words, the rest by words alone
            assert heard_by[:3] == ["either", "either", "words"] and set(heard_by[3:]) == {"words"}, heard_by
    assert seen[0] == seen[1] and len(seen[0]) >= 4 and set(seen[0]) == {"words"}, seen


def test_a_pair_is_judged_by_its_voice_and_a_half_without_words_keeps_its_phones():
    from mpeg4fa.speech.listen.core import WORDS_CONFIDENT, Listened, settled
    from mpeg4fa.speech.listen.stream import _heard_as
    from mpeg4fa.speech.utterance import Utterance

    def heard(confidence, voiced, took="phonetic"):
        return Listened(Utterance(None, (), (), None), took, voiced=voiced, confidence=confidence)

    synthetic, person = heard(WORDS_CONFIDENT - 3, 6.0), heard(WORDS_CONFIDENT + 8, 1.2, "words")
    assert settled("either", synthetic, person) == "phonetic"  # weighed by voice (a plain mean would take words)
    assert settled("either", synthetic, heard(WORDS_CONFIDENT + 8, 6.0, "words")) == "words"
    assert settled("phonetic", person) == "phonetic" and settled("either", heard(float("nan"), 0.0)) == "either"
    # voice in which the word decoder heard no word: the words path has nothing to show, the phones are kept
    wordless = heard(float("-inf"), 5.0)
    assert _heard_as(None, wordless, "words", "en") is wordless
    assert _heard_as(None, synthetic, "phonetic", "en") is synthetic


def test_say_hears_a_clip_as_encode_does(long_speech):
    # say renders the recording in memory, encode streams it: the same blocks, the same visemes on the same clock
    from mpeg4fa.speech.encoder import phones
    from mpeg4fa.speech.listen.stream import listened_whole

    x, rate = long_speech
    clip = x[:int(12 * rate)]
    out, timings = io.BytesIO(), io.StringIO()
    streamed = stream_listened(Source("clip", rate, 12.0, iter([clip])), out, timings=timings, level="low",
                               expression=("joy", 30))
    whole = listened_whole(Source("clip", rate, 12.0, iter([clip])), expression=("joy", 30))
    assert streamed.blocks == 2 and whole.recognizer == streamed.recognizer == "phonetic"
    written = [(i["viseme"], i["start"], i["end"]) for i in json.loads(timings.getvalue())]
    said = [(t.viseme, round(t.start, 6), round(t.end, 6)) for t in phones(whole.utterance).timings]
    assert said == written and len(said) > 50
    assert np.array_equal(whole.utterance.speech.samples, clip) and whole.voiced == streamed.voiced
    (cue,) = whole.utterance.cues
    assert (cue.expression, cue.intensity) == ("joy", 30)
