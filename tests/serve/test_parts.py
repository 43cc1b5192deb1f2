"""The server's parts without a server: sentences, client messages, binary framing, flow control, chunks."""
from __future__ import annotations

import asyncio

import numpy as np
import pytest

from mpeg4fa.serve.flow import Flow, Stalled
from mpeg4fa.serve.protocol import AUDIO_KIND, Buffer, ProtocolError, Say, pack, parse_client, unpack
from mpeg4fa.serve.segments import Segment, chunks
from mpeg4fa.serve.sentences import MAX_SENTENCE_CHARS, split_sentences
from mpeg4fa.speech.markup import MarkupError, parse_markup


def test_sentences_keep_their_tags_and_carry_raised_expressions():
    parts = split_sentences("(joy, 40, 0.5) Hello there. How are (surprise, 30, 1)you today? Fine. (joy, 0, 1) Bye!")
    assert [p.plain for p in parts] == ["Hello there.", "How are you today?", "Fine.", "Bye!"]
    first, second, third, fourth = (parse_markup(p.text) for p in parts)
    assert [(t.expression, t.intensity, t.seconds, t.offset) for t in first.tags] == [("joy", 40, 0.5, 0)]
    assert [(t.expression, t.intensity, t.seconds) for t in second.tags] == [("joy", 40, 0.0), ("surprise", 30, 1.0)]
    assert second.tags[1].offset == len("How are ")
    assert {(t.expression, t.intensity, t.seconds) for t in third.tags} == {("joy", 40, 0.0), ("surprise", 30, 0.0)}
    assert ("joy", 0, 1.0) in {(t.expression, t.intensity, t.seconds) for t in fourth.tags}
    assert [p.start for p in parts] == [0, 13, 32, 38]


def test_sentences_escape_parentheses_and_split_chinese_and_long_runs():
    parts = split_sentences(r"Fine \(really\). 你好。我很好！")
    assert [p.plain for p in parts] == ["Fine (really).", "你好。", "我很好！"]
    assert parse_markup(parts[0].text).text == "Fine (really)."
    long = split_sentences("word " * 300)
    assert len(long) > 1 and all(len(p.plain) <= MAX_SENTENCE_CHARS for p in long)
    assert " ".join(p.plain for p in long) == ("word " * 300).strip()
    assert split_sentences("  (joy, 3, 1)  ") == []


def test_a_bad_tag_anywhere_is_refused_with_its_place():
    with pytest.raises(MarkupError) as err:
        split_sentences("One. Two.\nThree (joy, 99, 1) four.", name="text")
    assert err.value.where == "text:2:13"


@pytest.mark.parametrize("raw, where", [
    ("{", "message"), ("3", "message"), ('{"type": 3}', "type"), ('{"type": "say", "text": 5}', "text"),
    ('{"type": "buffer", "received": "x", "buffered": 0}', "received"),
    ('{"type": "buffer", "received": 1e999, "buffered": 0}', "message"),  # not a double: the JSON reader's, located
    ('{"type": "say", "text": "hi", "rate": 1000}', "rate"), ('{"type": "stop", "now": true}', "now"),
    ("[" * 100_000, "message"), ('{"type": ' + "[" * 100_000, "message"),  # deep: an error, not a RecursionError
])
def test_client_messages_are_refused_with_the_field(raw, where):
    with pytest.raises(ProtocolError) as err:
        parse_client(raw)
    assert err.value.where == where


def test_client_messages_parse():
    assert parse_client('{"type": "say", "text": "hi", "id": "a", "rate": 200}') == Say(type="say", text="hi", id="a",
                                                                                       rate=200)
    assert parse_client('{"type": "buffer", "received": 2.5, "buffered": 0.5}') == Buffer(type="buffer", received=2.5,
                                                                                        buffered=0.5)
    with pytest.raises(ProtocolError, match="binary"):
        parse_client(None, b"xx")


def test_binary_framing_round_trips():
    pcm = np.arange(-5, 5, dtype="<i2").tobytes()
    assert unpack(pack(AUDIO_KIND, 1.25, pcm)) == (AUDIO_KIND, 1.25, pcm)
    with pytest.raises(ValueError):
        unpack(b"AUD1")
    with pytest.raises(ValueError):
        pack(AUDIO_KIND, float("nan"), b"")


def test_flow_sends_a_window_ahead_of_the_reported_playhead_and_detects_a_stall():
    async def scenario():
        clock = [0.0]
        flow = Flow(2.0, 1.0, clock=lambda: clock[0])
        assert flow.allows(1.9) and not flow.allows(2.0)
        waiter = asyncio.create_task(flow.wait_for(3.0))
        await asyncio.sleep(0)
        assert not waiter.done()
        flow.report(received=2.0, buffered=0.5)  # playhead 1.5: 3.0 < 3.5 may go
        await asyncio.wait_for(waiter, 1.0)
        flow.report(received=2.0, buffered=1.5)  # an older report cannot pull the playhead back
        assert flow.playhead == 1.5 and flow.waits == 1
        clock[0] = 5.0  # a second after the last report the client counts as stalled
        with pytest.raises(Stalled, match="no buffer report for 1 s"):
            await flow.wait_for(10.0)
    asyncio.run(scenario())


def test_chunks_cover_the_audio_in_time_order():
    rate = 1000
    seg = Segment(index=0, text="x", start=10.0, rate=rate, audio=np.arange(1050).astype("<i2"), fba=b"",
                  times=10.0 + np.array([0.0, 0.04, 0.08, 0.2, 0.24, 0.6, 1.0]))
    items = chunks(seg, 0.2)
    assert [t for t, _ in items] == pytest.approx([10.0, 10.2, 10.4, 10.6, 10.8, 11.0])
    assert np.array_equal(np.concatenate([a for _, a in items]), seg.audio) and all(len(a) <= 200 for _, a in items)
