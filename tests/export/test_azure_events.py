"""Azure-style viseme events from streams (mpeg4fa.export.events) and the round trips through FBA."""
import json

import numpy as np
import pytest

from mpeg4fa.export import azure_events, viseme_changes, write_azure_json
from mpeg4fa.fba import decode, encode
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.spec.avatars import AZURE_VISEMES, from_azure, viseme_target
from mpeg4fa.speech.viseme_events import encode_viseme_events, parse_viseme_events

FRAME = 1 / 25
# Polly-like marks, 60-180 ms apart as Polly's are for ordinary speech ("Mary had a little lamb" pace); like
# Polly's, the first comes a few ms into the audio (a first frame shows it: the mouth moves ahead of the sound)
MARKS = [(6, "p"), (120, "E"), (210, "r"), (300, "i"), (380, "k"), (470, "a"), (560, "t"),
         (640, "sil"), (820, "f"), (900, "O"), (1010, "s"), (1100, "u"), (1200, "T"), (1290, "a"), (1400, "sil")]


def _polly(marks) -> str:
    return "\n".join(json.dumps({"time": t, "type": "viseme", "value": v}) for t, v in marks) + "\n"


def _through_fba(events, level: str) -> FapStream:
    encoded = encode_viseme_events(events, fps=25, level=level)
    return decode(encode(encoded.stream, encoded.coding()))


def _shown(changes):
    """(time, viseme) pairs with runs of one viseme merged."""
    out = []
    for c in changes:
        if not out or out[-1][1] != c.viseme:
            out.append((c.time, c.viseme))
    return out


@pytest.mark.parametrize("level", ["high", "low"])
def test_polly_marks_through_fba_come_back_in_order_and_within_a_frame(level):
    _, events = parse_viseme_events(_polly(MARKS))
    sent = _shown(events)
    back = _shown(viseme_changes(_through_fba(events, level)))
    assert [v for _, v in back] == [v for _, v in sent]
    early_or_late = np.array([b - s for (b, _), (s, _) in zip(back, sent)])
    assert np.abs(early_or_late).max() <= FRAME + 1e-9, early_or_late


def test_azure_events_through_fba_keep_their_ids_and_times():
    """Azure ID -> MPEG-4 viseme -> Azure ID is the identity for the IDs our visemes go out as."""
    canonical = [viseme_target(v.mpeg4).azure for v in AZURE_VISEMES]
    invertible = sorted({i for i in range(len(AZURE_VISEMES)) if canonical[i] == i})
    assert len(invertible) == 15  # one ID per MPEG-4 viseme
    ids = [0] + [i for i in invertible if i] + [0]
    events = [{"AudioOffset": 400_000 + 900_000 * k, "VisemeId": vid} for k, vid in enumerate(ids)]
    _, parsed = parse_viseme_events(json.dumps(events))
    out = azure_events(_through_fba(parsed, "high"))
    assert [e["VisemeId"] for e in out] == ids
    sent = np.array([e["AudioOffset"] for e in events[1:]])
    got = np.array([e["AudioOffset"] for e in out[1:]])
    assert np.abs(got - sent).max() <= FRAME * 1e7


def test_a_diphthong_comes_back_as_its_two_visemes():
    """11 (aɪ) is shown as its nucleus AA, then its offglide ih: it goes out as their IDs, 2 then 6."""
    assert from_azure(11) == "AA" and AZURE_VISEMES[11].offglide == "ih"
    _, parsed = parse_viseme_events(json.dumps([{"AudioOffset": 0, "VisemeId": 11},
                                                {"AudioOffset": 3_000_000, "VisemeId": 0}]))
    out = azure_events(_through_fba(parsed, "high"))
    assert [e["VisemeId"] for e in out] == [2, 6, 0]
    assert abs(out[1]["AudioOffset"] - 0.7 * 3_000_000) <= FRAME * 1e7


def test_the_events_end_at_rest_and_an_empty_stream_has_none():
    _, events = parse_viseme_events(_polly([(0, "a")]))
    stream = _through_fba(events, "high")
    out = azure_events(stream)
    assert out[0] == {"AudioOffset": 0, "VisemeId": 2} and out[-1]["VisemeId"] == 0
    assert azure_events(FapStream.empty(0)) == []


def test_azure_json_reads_back(tmp_path):
    _, events = parse_viseme_events(_polly(MARKS))
    stream = _through_fba(events, "high")
    path = tmp_path / "events.json"
    n = write_azure_json(stream, path)
    doc = json.loads(path.read_text(encoding="utf-8"))
    assert len(doc) == n and set(doc[0]) == {"AudioOffset", "VisemeId"}
    kind, again = parse_viseme_events(path.read_text(encoding="utf-8"), str(path))
    assert kind == "azure" and [e.viseme for e in again] == [c.viseme for c in viseme_changes(stream)]


def test_export_azure_json_on_the_command_line(cli, tmp_path):
    marks = tmp_path / "marks.json"
    marks.write_text(_polly(MARKS))
    fba, out = tmp_path / "talk.fba", tmp_path / "talk.azure.json"
    assert cli("encode", "--visemes", marks, "-o", fba)[0] == 0
    code, printed, err = cli("export", fba, "--format", "azure-json", "-o", out)
    assert code == 0, err
    assert "Azure viseme events" in printed
    assert [from_azure(e["VisemeId"]) for e in json.loads(out.read_text())][:3] == ["PP", "E", "RR"]
