"""A sound track that opens and then breaks is damage (cut short), not a file of the wrong type."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.render import RenderError
from mpeg4fa.render.audio import read_audio


def _m4a(path, seconds: float = 3.0, rate: int = 16000) -> None:
    import av

    with av.open(str(path), "w", format="mp4") as container:
        stream = container.add_stream("aac", rate=rate)
        stream.layout = "mono"
        t = np.arange(int(seconds * rate)) / rate
        samples = (0.3 * np.sin(2 * np.pi * 220 * t)).astype(np.float32)
        for start in range(0, len(samples), 1024):
            frame = av.AudioFrame.from_ndarray(samples[None, start:start + 1024], format="fltp", layout="mono")
            frame.sample_rate = rate
            for packet in stream.encode(frame):
                container.mux(packet)
        for packet in stream.encode(None):
            container.mux(packet)


def test_a_sound_track_cut_short_is_named_as_damage(tmp_path):
    whole = tmp_path / "whole.m4a"
    _m4a(whole)
    assert read_audio(whole).duration == pytest.approx(3.0, abs=0.1)
    data = bytearray(whole.read_bytes())
    middle = len(data) // 2
    data[middle:middle + 400] = b"\xff" * 400           # packets broken half-way through the sound
    broken = tmp_path / "broken.m4a"
    broken.write_bytes(bytes(data))
    with pytest.raises(RenderError, match="damaged or cut short after 1.[0-9]+ s") as info:
        read_audio(broken)
    assert info.value.where == str(broken) and "expected" not in info.value.hint
