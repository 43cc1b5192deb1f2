"""Azure-style viseme events from a stream: one event each time the viseme the face shows changes.

The viseme a frame shows is the one of largest weight (:func:`.weights.viseme_weights`: FAP 1's
fields, or the mouth FAPs fitted to the viseme profiles), so with FAP 1 an event comes at the first
frame where the new viseme outweighs the old one (the middle of the Hermite move our encoder makes
across each boundary). Each MPEG-4 viseme goes out as its Azure ID (``spec/viseme_targets.csv``:
``none`` 0, ``PP`` 21, ``AA`` 2...); the last event is silence (0) at the end of the stream when the
face is not already at rest, as Azure ends its own.

JSON written by :func:`write_azure_json` (UTF-8, atomic): the events as Azure's ``VisemeReceived``
carries them, in time order::

    [{"AudioOffset": 0, "VisemeId": 0}, {"AudioOffset": 1200000, "VisemeId": 21}, ...]

``AudioOffset`` is in ticks of 100 ns from the first frame (Azure's unit); ``VisemeId`` is 0..21.
:mod:`mpeg4fa.speech.viseme_events` reads this form back (``mpeg4fa encode --visemes``).
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mpeg4fa.atomic import atomic_output
from mpeg4fa.export.weights import viseme_weights
from mpeg4fa.render.timing import presentation_times
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.spec import VISEMES
from mpeg4fa.spec.avatars import viseme_target

__all__ = ["VisemeChange", "viseme_changes", "azure_events", "write_azure_json", "TICKS_PER_SECOND"]

TICKS_PER_SECOND = 10_000_000
"""Azure's ticks (100 ns) per second."""
_AZURE_ID = np.array([viseme_target(v.name).azure for v in VISEMES])


@dataclass(frozen=True)
class VisemeChange:
    """From ``time`` seconds (from the first frame) the face shows MPEG-4 ``viseme``."""

    time: float
    viseme: str


def viseme_changes(stream: FapStream) -> list[VisemeChange]:
    """The shown viseme at the first frame and at every frame where it changes; silence at the end."""
    if not len(stream):
        return []
    shown = viseme_weights(stream).argmax(axis=1)
    times = presentation_times(stream)
    starts = np.r_[0, np.flatnonzero(np.diff(shown)) + 1]
    changes = [VisemeChange(float(times[k]), VISEMES[int(shown[k])].name) for k in starts]
    if shown[-1] != 0:
        end = float(times[-1]) + (int(stream.skip[-1]) + 1) / stream.fps
        changes.append(VisemeChange(end, VISEMES[0].name))
    return changes


def azure_events(stream: FapStream) -> list[dict]:
    """The changes as Azure ``VisemeReceived`` events: ``{"AudioOffset": ticks, "VisemeId": id}``."""
    return [{"AudioOffset": int(round(c.time * TICKS_PER_SECOND)),
             "VisemeId": int(_AZURE_ID[[v.name for v in VISEMES].index(c.viseme)])}
            for c in viseme_changes(stream)]


def write_azure_json(stream: FapStream, path: str | os.PathLike) -> int:
    """Write :func:`azure_events` as a JSON array (schema in the module docstring), atomically; the count."""
    events = azure_events(stream)
    text = "[\n" + ",\n".join(json.dumps(e) for e in events) + "\n]\n"
    with atomic_output(path) as partial:
        Path(partial).write_text(text, encoding="utf-8")
    return len(events)
