"""Azure and Polly viseme events read into the encoder's timeline (mpeg4fa.speech.viseme_events, encode --visemes)."""
import json

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mpeg4fa.fba import decode
from mpeg4fa.formats import FormatError
from mpeg4fa.speech.viseme_events import (LAST_VISEME, TAIL, encode_viseme_events, events_utterance,
                                          parse_viseme_events, read_viseme_events)

POLLY = "\n".join(json.dumps(m) for m in [
    {"time": 0, "type": "sentence", "start": 0, "end": 9, "value": "Big fish."},
    {"time": 0, "type": "word", "start": 0, "end": 3, "value": "Big"},
    {"time": 20, "type": "viseme", "value": "p"},
    {"time": 110, "type": "viseme", "value": "i"},
    {"time": 190, "type": "viseme", "value": "k"},
    {"time": 270, "type": "word", "start": 4, "end": 8, "value": "fish"},
    {"time": 270, "type": "viseme", "value": "f"},
    {"time": 360, "type": "viseme", "value": "i"},
    {"time": 430, "type": "viseme", "value": "S"},
    {"time": 560, "type": "viseme", "value": "sil"},
]) + "\n"
AZURE = [{"AudioOffset": 0, "VisemeId": 0}, {"AudioOffset": 500_000, "VisemeId": 21},
         {"AudioOffset": 1_400_000, "VisemeId": 2}, {"AudioOffset": 2_600_000, "VisemeId": 15},
         {"AudioOffset": 3_500_000, "VisemeId": 0}]


def test_polly_marks_become_visemes_at_their_times():
    kind, events = parse_viseme_events(POLLY, "marks.json")
    assert kind == "polly"
    assert [(e.time, e.viseme) for e in events] == [
        (0.02, "PP"), (0.11, "ih"), (0.19, "kk"), (0.27, "FF"), (0.36, "ih"), (0.43, "CH"), (0.56, "none")]
    assert events[0].line == 3 and events[0].index == 2 and events[0].source == "p"


def test_azure_events_in_each_sdk_spelling():
    spellings = [("AudioOffset", "VisemeId"), ("audioOffset", "visemeId"), ("audio_offset", "viseme_id"),
                 ("privAudioOffset", "privVisemeId")]
    for offset, vid in spellings:
        text = json.dumps([{offset: e["AudioOffset"], vid: e["VisemeId"], "Animation": ""} for e in AZURE])
        kind, events = parse_viseme_events(text)
        assert kind == "azure"
        assert [(e.time, e.viseme) for e in events] == [(0.0, "none"), (0.05, "PP"), (0.14, "AA"), (0.26, "SS"),
                                                         (0.35, "none")]
    for key in ("visemes", "events"):
        assert parse_viseme_events(json.dumps({key: AZURE}))[0] == "azure"


def test_a_polly_array_and_a_forced_format():
    marks = [json.loads(line) for line in POLLY.splitlines()]
    assert parse_viseme_events(json.dumps(marks), format="polly")[1][0].viseme == "PP"
    with pytest.raises(FormatError, match="no audio offset and viseme ID"):
        parse_viseme_events(POLLY, "m.json", format="azure")


def test_the_utterance_holds_each_viseme_until_the_next_event():
    _, events = parse_viseme_events(POLLY)
    u = events_utterance(events)
    assert [(t.viseme, t.start, t.end) for t in u.timings] == [
        ("PP", 0.02, 0.11), ("ih", 0.11, 0.19), ("kk", 0.19, 0.27), ("FF", 0.27, 0.36), ("ih", 0.36, 0.43),
        ("CH", 0.43, 0.56)]  # the closing silence ends the last viseme and is no span
    assert u.speech.duration == pytest.approx(0.56 + TAIL, abs=1e-4)
    _, open_end = parse_viseme_events('{"time": 0, "type": "viseme", "value": "a"}')
    assert events_utterance(open_end).timings[-1].end == pytest.approx(LAST_VISEME)


def test_azure_diphthongs_split_as_the_ipa_route_splits_them():
    from mpeg4fa.speech.ipa import FIRST_SHARE

    _, events = parse_viseme_events(json.dumps([{"AudioOffset": 1_000_000, "VisemeId": 9},
                                                {"AudioOffset": 3_000_000, "VisemeId": 0}]))
    assert events[0].viseme == "AA" and events[0].offglide == "ou"
    split = 0.1 + FIRST_SHARE * 0.2
    assert [(t.viseme, t.start, t.end) for t in events_utterance(events).timings] == [
        ("AA", 0.1, pytest.approx(split)), ("ou", pytest.approx(split), 0.3)]


def test_events_encode_with_the_text_encoders_transitions():
    _, events = parse_viseme_events(POLLY)
    encoded = encode_viseme_events(events, fps=25)
    stream = encoded.stream
    assert stream.fap_mask[:, 0].any()  # FAP 1 names the visemes
    blend = stream.viseme[stream.fap_mask[:, 0], 2]
    assert ((blend > 0) & (blend < 63)).any()  # Hermite moves between shapes, not steps
    jaw = encoded.values[:, 2]  # open_jaw follows the spans: a closed PP, an open ih...
    assert np.abs(np.diff(jaw)).max() < np.abs(jaw).max()  # smooth: no frame jumps the whole way
    low = encode_viseme_events(events, level="low").stream
    assert not low.fap_mask[:, 0].any() and low.fap_mask[:, 2:].any()


@pytest.mark.parametrize("text, where, what", [
    ("", "f.json", "empty"),
    ('[{"AudioOffset": 0, "VisemeId": 1},\n {"AudioOffset": 5 "VisemeId": 2}]', "f.json:2:20", "invalid JSON"),
    ('{"time":0,"type":"viseme","value":"p"}\n{"time":5,"type":"viseme",,}\n', "f.json:2:", "invalid JSON"),
    ('[{"AudioOffset": 0, "VisemeId": 1},\n {"AudioOffset": 5, "VisemeId": 22}]', "f.json:2: event 1", "0..21"),
    ('[{"AudioOffset": 0, "VisemeId": 1},\n {"AudioOffset": -5, "VisemeId": 2}]', "f.json:2: event 1", "ticks"),
    ('[{"AudioOffset": 0, "VisemeId": 1},\n {"AudioOffset": "5", "VisemeId": 2}]', "f.json:2: event 1", "ticks"),
    ('[{"AudioOffset": 0, "VisemeId": 1},\n {"AudioOffset": 5, "VisemeId": 2.0}]', "f.json:2: event 1", "0..21"),
    ('{"time":9,"type":"viseme","value":"p"}\n{"time":5,"type":"viseme","value":"a"}\n', "f.json:2: event 1",
     "before the previous"),
    ('{"time":0,"type":"viseme","value":"p"}\n{"time":5,"type":"viseme","value":"B"}\n', "f.json:2: event 1",
     "Polly viseme 'B'"),
    ('{"time":0,"type":"viseme","value":"p"}\n{"time":NaN,"type":"viseme","value":"a"}\n', "f.json:2:9",
     "NaN is not a number"),
    ('{"time":0,"type":"viseme","value":"p"}\n{"time":1e12,"type":"viseme","value":"a"}\n', "f.json:2: event 1",
     "not a time"),
    ('[{"AudioOffset": 1e300, "VisemeId": 1}]', "f.json:1: event 0", "ticks"),
    ('{"time":0,"type":"word","value":"hi"}\n', "f.json", "no polly viseme events"),
    ('[1, 2]', "f.json", "cannot tell"),
    ('[{"AudioOffset": 0, "VisemeId": 1}, 7]', "f.json:1: event 1", "not an event"),
    ('"text"', "f.json:1:1", "JSON str"),
])
def test_bad_files_fail_at_their_place(text, where, what):
    with pytest.raises(FormatError) as err:
        parse_viseme_events(text, "f.json")
    assert str(err.value).startswith(where) and what in str(err.value)


def test_a_missing_or_binary_file(tmp_path):
    with pytest.raises(FormatError, match="no such file"):
        read_viseme_events(tmp_path / "none.json")
    (tmp_path / "b.json").write_bytes(b"\xff\xfe\x00")
    with pytest.raises(FormatError, match="not UTF-8"):
        read_viseme_events(tmp_path / "b.json")


def test_encode_visemes_on_the_command_line(cli, tmp_path):
    marks = tmp_path / "marks.json"
    marks.write_text(POLLY, encoding="utf-8")
    out, timings = tmp_path / "talk.fba", tmp_path / "t.json"
    code, _, err = cli("encode", "--visemes", marks, "-o", out, "--timings", timings)
    assert code == 0, err
    assert "7 polly viseme events" in err
    stream = decode(out.read_bytes())
    assert stream.duration == pytest.approx(0.56 + TAIL, abs=1 / 25) and stream.fap_mask[:, 0].any()
    assert [t["viseme"] for t in json.loads(timings.read_text())][:3] == ["PP", "ih", "kk"]
    azure = tmp_path / "azure.json"
    azure.write_text(json.dumps(AZURE))
    assert cli("encode", "--visemes", azure, "--format", "azure", "--level", "low", "-o", out)[0] == 0


def test_encode_visemes_usage_and_file_errors(cli, tmp_path):
    marks = tmp_path / "marks.json"
    marks.write_text(POLLY, encoding="utf-8")
    out = tmp_path / "o.fba"
    assert cli("encode", "hello", "--visemes", marks, "-o", out)[0] == 2
    assert cli("encode", "--visemes", marks, "--audio", tmp_path / "a.wav", "-o", out)[0] == 2
    assert cli("encode", "hello", "--format", "polly", "-o", out)[0] == 2
    assert cli("encode", "--visemes", marks, "-o", marks)[0] != 0 and marks.read_text() == POLLY
    bad = tmp_path / "bad.json"
    bad.write_text('[{"AudioOffset": 0, "VisemeId": 0},\n{"AudioOffset": 1, "VisemeId": 99}]')
    code, _, err = cli("encode", "--visemes", bad, "-o", out)
    assert code == 1 and err.count("\n") == 1 and f"{bad}:2: event 1" in err and "Traceback" not in err
    assert not out.exists()


_JSON = st.recursive(st.none() | st.booleans() | st.integers(-10**12, 10**12) | st.floats(allow_nan=True)
                     | st.text(max_size=4),
                     lambda inner: st.lists(inner, max_size=4) | st.dictionaries(
                         st.sampled_from(["AudioOffset", "VisemeId", "time", "type", "value", "visemes", "x"]),
                         inner, max_size=4), max_leaves=12)


@settings(max_examples=300, deadline=None)
@given(st.one_of(_JSON.map(json.dumps), st.lists(_JSON.map(json.dumps), max_size=4).map("\n".join),
                 st.text(max_size=40)))
def test_any_text_gives_events_or_one_located_error(text):
    """Bad input never escapes as anything but FormatError; what parses is in time order with known visemes."""
    try:
        kind, events = parse_viseme_events(text, "f.json")
    except FormatError as exc:
        assert str(exc).startswith("f.json")
        return
    assert kind in ("azure", "polly") and events
    assert all(a.time <= b.time for a, b in zip(events, events[1:]))
    assert all(np.isfinite(e.time) and e.time >= 0 for e in events)
