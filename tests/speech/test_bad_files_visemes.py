"""Viseme event files that ask for too much, or are damaged, are one located error before any work
(issue 26: an 81-byte file with an event at 6 h took 58 s and 3.19 GB; 100,000 '[' a RecursionError;
105k events were quadratic in their line numbers)."""
from __future__ import annotations

import json

import pytest

from mpeg4fa.formats import FormatError
from mpeg4fa.speech import viseme_events as ve


def test_an_event_past_the_ceiling_is_refused_before_encoding(tmp_path):
    path = tmp_path / "late.json"
    path.write_text('[{"AudioOffset": 0, "VisemeId": 1},\n{"AudioOffset": 215999990000, "VisemeId": 2}]')
    with pytest.raises(FormatError) as info:
        ve.read_viseme_events(path)
    assert info.value.line == 2 and "event 1" in str(info.value) and f"{ve.MAX_SECONDS:g} s" in str(info.value)


@pytest.mark.parametrize("data, place, words", [
    (b"[" * 100_000, (1, 65), "nested more than"),
    (b'{"time":0,"type":"viseme","value":"p"}\n' + b"[" * 100_000, (2, 65), "nested more than"),
    (b'[{"AudioOffset": 0,\n "VisemeId": 1e999}]', (2, 14), "beyond what a double"),
    (b'[{"AudioOffset": 0, "VisemeId": "\xc3("}]', (1, 34), "not UTF-8"),
    (b"\x89PNG\r\n\x1a\n" + bytes(20), (None, None), "(a PNG image)"),
])
def test_damage_is_one_located_error(tmp_path, data, place, words):
    path = tmp_path / "bad.json"
    path.write_bytes(data)
    with pytest.raises(FormatError) as info:
        ve.read_viseme_events(path)
    assert (info.value.line, info.value.column) == place and words in str(info.value)


def test_too_many_events_are_refused(monkeypatch):
    monkeypatch.setattr(ve, "MAX_EVENTS", 10)
    marks = "\n".join(json.dumps({"time": k, "type": "viseme", "value": "p"}) for k in range(11))
    with pytest.raises(FormatError, match="11 events, more than the 10 read"):
        ve.parse_viseme_events(marks, "m.json")


def test_every_event_keeps_its_line_in_a_long_array():
    n = 20_000
    text = "[\n" + ",\n\n".join(json.dumps({"AudioOffset": 10_000 * k, "VisemeId": 1 + k % 20}) for k in range(n)) + "\n]"
    _, events = ve.parse_viseme_events(text, "a.json")
    assert [e.line for e in events[:3]] == [2, 4, 6] and events[-1].line == 2 + 2 * (n - 1)
