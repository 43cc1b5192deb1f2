"""A long recording is heard two blocks at a time, one in a helper process (pocketsphinx holds the GIL while
it decodes, so only a second process uses a second core): the stream is the one a single process writes, up
to the decoder's state carried from one utterance to the next (a few timings of hundreds), in the same order
and on the same clock. Speed itself is measured by tools/bench_lipsync_audio.py, not here."""
import io
import json
import os
import resource

import numpy as np
import pytest

pytest.importorskip("pocketsphinx")

from mpeg4fa.fba import decode  # noqa: E402
from mpeg4fa.speech.listen.compare import agreement  # noqa: E402
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
    share, frames = agreement(one_timings, two_timings, len(x) / rate)
    # measured 0.95: with 4 s blocks each decoding leans on the state the last one left
    assert frames >= 200 and share >= 0.9, share
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
    # a clip shorter than a block would use one core: the helper decodes its phone loop while the words are
    # decoded here, and the stream is the one a single process writes
    x, rate = long_speech
    short = x[:6 * rate]

    def heard(two_cores):
        before = _helper_cpu()
        out, timings = io.BytesIO(), io.StringIO()
        got = stream_listened(Source("short", rate, 6.0, iter([short])), out, timings=timings, recognizer="either",
                              lang="en", two_cores=two_cores, level="low")
        return got.blocks, got.recognizer, out.getvalue(), timings.getvalue(), _helper_cpu() > before

    one, two = _forked(lambda: heard(False)), _forked(lambda: heard(True))
    assert one[0] == two[0] == 1 and one[1] == two[1] == "phonetic"
    assert not one[4] and two[4]  # a helper process did part of the hearing only when asked to
    assert one[2] == two[2] and one[3] == two[3] and len(one[2]) > 100
