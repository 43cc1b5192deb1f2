"""Playback: the presentation schedule, MP4/PNG output with audio in sync, snapshots, live frames,
and every English vector stream played with its speech."""
from __future__ import annotations

import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.fba import decode
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.render import Audio, RenderError, RenderWarning, play, play_live, snapshot
from mpeg4fa.render.renderer import Renderer
from mpeg4fa.render.timing import schedule
from mpeg4fa.render.video import probe_media

VECTORS = Path(__file__).resolve().parents[2] / ".." / "shared" / "vectors" / "fba" / "en"
SIZE = {"width": 48, "height": 48}


def _stream(skips: list[int], jaw: list[int], fps: float = 25.0) -> FapStream:
    """Frames with FAP 3 (jaw) values and skip counts; timestamps follow the skips."""
    n = len(skips)
    s = FapStream.empty(n)
    s.source_fps = fps
    s.skip[:] = skips
    s.timestamps[:] = np.r_[0.0, np.cumsum(np.asarray(skips[:-1]) + 1)] / fps
    s.fap_mask[:, 2] = True
    s.fap_values[:, 2] = jaw
    return s


def _tone(seconds: float, rate: int = 16000) -> Audio:
    t = np.arange(int(round(seconds * rate))) / rate
    return Audio((0.3 * np.sin(2 * np.pi * 220 * t)).astype(np.float32)[:, None], rate)


def test_schedule_holds_frames_over_skips_and_resamples():
    s = _stream([0, 2, 0, 1, 0, 0], [0] * 6)
    plan = schedule(s)
    assert plan.source.tolist() == [0, 1, 1, 1, 2, 3, 3, 4, 5]
    assert math.isclose(plan.duration, 0.36)
    # at 50 fps every stream frame shows for twice as many ticks
    assert schedule(s, fps=50).source.tolist() == [0, 0, 1, 1, 1, 1, 1, 1, 2, 2, 3, 3, 3, 3, 4, 4, 5, 5]
    # at 12.5 fps some frames fall between ticks and are not shown
    assert schedule(s, fps=12.5).source.tolist() == [0, 1, 2, 3, 5]


def test_schedule_errors():
    s = _stream([0, 0, 0], [0, 0, 0])
    s.timestamps[2] = 0.0
    with pytest.raises(RenderError, match="frame 2"):
        schedule(s)
    with pytest.raises(RenderError, match="no frames"):
        schedule(FapStream.empty(0))


def test_a_stream_whose_time_codes_jump_by_hours_is_refused_before_any_frame():
    """Fuzz of 2026-12-07: a 150-byte .fap whose second frame is numbered 2000000 (22 h at 25 fps) had ``play``
    render two million frames and ``export --fps 255`` fill 20 GB. The schedule now names the gap at once."""
    from mpeg4fa.render.timing import MAX_HELD_FRAMES, MAX_OUTPUT_SECONDS

    gap = _stream([1999999, 0], [0, 600])
    with pytest.raises(RenderError, match=r"span 22 h 13 min; frame 1 comes 22 h 13 min after frame 0"):
        schedule(gap)
    long = _stream([int(MAX_OUTPUT_SECONDS * 25)] * 2, [0, 0])  # evenly sparse: no one gap to blame
    with pytest.raises(RenderError, match="12 h 0 min") as caught:
        schedule(long)
    assert "probably wrong" not in str(caught.value)
    hour = _stream([49999, 49999], [0, 0])  # 4000 s: 100,000 frames at 25 fps, 1,020,000 at 255
    assert schedule(hour).n_frames == 100000 and schedule(hour, fps=255).n_frames == 1020000  # a player streams
    with pytest.raises(RenderError, match="lower --fps"):
        schedule(hour, fps=255, max_frames=MAX_HELD_FRAMES)  # an export holds them all
    absurd = _stream([0, 0], [0, 0])
    absurd.timestamps[1] = 1e300  # reachable through the API: one located error, not an OverflowError
    with pytest.raises(RenderError, match="span 1e"):
        schedule(absurd)


def test_each_frame_appears_at_its_presentation_time(procedural_face, tmp_path):
    """PNG output, frame by frame: an open jaw is drawn exactly on the ticks of its frame."""
    s = _stream([0, 2, 0, 1, 0, 0], [0, 600, 0, 600, 0, 0])
    result = play(s, tmp_path / "frames", face=procedural_face, **SIZE)
    assert result.n_frames == 9 and result.rendered == 6
    images = [np.asarray(Image.open(p)) for p in sorted((tmp_path / "frames").glob("*.png"))]
    assert len(images) == 9
    opened = [bool(np.abs(img.astype(int) - images[0]).max() > 20) for img in images]
    assert opened == [False, True, True, True, False, True, True, False, False]


def test_mp4_has_the_frames_duration_and_audio_in_sync(procedural_face, tmp_path):
    s = _stream([0] * 50, [0, 300] * 25)
    out = tmp_path / "talk.mp4"
    with warnings.catch_warnings():
        warnings.simplefilter("error", RenderWarning)  # lengths match within a frame: nothing to say
        result = play(s, out, face=procedural_face, audio=_tone(2.01), **SIZE)
    info = probe_media(out)
    assert info.n_frames == result.n_frames == 50
    assert math.isclose(info.fps, 25.0) and math.isclose(info.video_duration, 2.0)
    assert abs(info.audio_duration - 2.0) <= 1024 / 16000
    assert abs(info.av_offset) <= 0.001


@pytest.mark.parametrize("fit,audio_s,frames,said", [
    ("pad", 2.5, 63, "video padded with 13 frames"),
    ("pad", 1.5, 50, "audio padded with 0.500 s of silence"),
    ("trim", 2.5, 50, "audio trimmed by 0.500 s"),
    ("trim", 1.5, 38, "video trimmed by 12 frames"),
])
def test_length_mismatch_is_fixed_and_said(procedural_face, tmp_path, fit, audio_s, frames, said):
    s = _stream([0] * 50, [0] * 50)
    with pytest.warns(RenderWarning, match=said):
        result = play(s, tmp_path / "f.mp4", face=procedural_face, audio=_tone(audio_s), fit=fit, **SIZE)
    info = probe_media(tmp_path / "f.mp4")
    assert info.n_frames == result.n_frames == frames
    assert abs(info.audio_duration - frames / 25) <= 1024 / 16000
    assert result.adjustments and said in result.adjustments[0]


def test_png_sequence_with_audio_and_snapshot_matches(procedural_face, tmp_path):
    s = _stream([0] * 8, [0, 100, 200, 300, 400, 500, 600, 700])
    play(s, tmp_path / "seq", face=procedural_face, audio=_tone(0.32), **SIZE)
    frames = sorted((tmp_path / "seq").glob("*.png"))
    assert len(frames) == 8 and (tmp_path / "seq" / "audio.wav").is_file()
    shot = snapshot(s, frame=5, face=procedural_face, **SIZE)
    np.testing.assert_array_equal(shot, np.asarray(Image.open(frames[5])))
    np.testing.assert_array_equal(snapshot(s, seconds=0.21, face=procedural_face, **SIZE), shot)
    np.testing.assert_array_equal(snapshot(s, frame=-1, face=procedural_face, **SIZE),
                                  np.asarray(Image.open(frames[7])))


def test_snapshot_and_play_errors(procedural_face, tmp_path):
    s = _stream([0] * 4, [0] * 4)
    with pytest.raises(RenderError, match="outside the stream"):
        snapshot(s, frame=4, face=procedural_face, **SIZE)
    with pytest.raises(RenderError, match="outside the stream"):
        snapshot(s, seconds=9.0, face=procedural_face, **SIZE)
    bad = tmp_path / "noise.wav"
    bad.write_bytes(b"RIFF\x00\x00\x00\x00WAVEjunkjunk")
    with pytest.raises(RenderError, match="noise.wav"):
        play(s, tmp_path / "x.mp4", face=procedural_face, audio=bad, **SIZE)
    with pytest.raises(RenderError, match="no such audio file"):
        play(s, tmp_path / "x.mp4", face=procedural_face, audio=tmp_path / "missing.wav", **SIZE)
    with pytest.raises(RenderError, match="fit"):
        play(s, tmp_path / "x.mp4", face=procedural_face, audio=_tone(0.16), fit="stretch", **SIZE)


def test_play_live_paces_to_the_wall_clock(procedural_face):
    s = _stream([0] * 10, [0, 500] * 5, fps=100.0)
    with Renderer(procedural_face, **SIZE) as renderer:
        shown = list(play_live(iter(s), renderer))
    assert [f.index for f in shown][0] == 0 and len(shown) >= 5
    assert all(f.image.shape == (48, 48, 3) for f in shown)
    assert shown[-1].shown_at >= 0.085  # 10 frames at 100 fps: the last is due at 0.09 s


def _en_pairs():
    if not VECTORS.is_dir():
        return []
    return sorted(p for p in VECTORS.glob("*.FBA") if p.with_suffix(".wav").is_file())


@pytest.mark.skipif(not VECTORS.is_dir(), reason="../shared/vectors not present: real-stream playback not checked")
@pytest.mark.parametrize("path", _en_pairs(), ids=lambda p: p.stem)
def test_every_en_vector_plays_with_its_speech(generic_face, tmp_path, path):
    stream = decode(path)
    audio_path = path.with_suffix(".wav")
    out = tmp_path / f"{path.stem}.mp4"
    with warnings.catch_warnings(record=True):
        warnings.simplefilter("always", RenderWarning)
        result = play(stream, out, face=generic_face, audio=audio_path, **SIZE)
    info = probe_media(out)
    longest = max(schedule(stream).duration, _audio_seconds(audio_path))
    assert info.n_frames == result.n_frames == math.ceil(longest * 25 - 1e-6)
    assert abs(info.audio_duration - info.video_duration) <= 1024 / info.audio_rate
    assert abs(info.av_offset) <= 0.001


def _audio_seconds(path: Path) -> float:
    from mpeg4fa.render import read_audio
    return read_audio(path).duration


def test_a_renderer_without_a_face_poses_its_own_face(procedural_face):
    """play/snapshot given only a renderer pose the head it draws (not the generic head)."""
    stream = _stream([0, 0, 0], [0, 300, 600])
    with Renderer(procedural_face, **SIZE) as renderer:
        alone = snapshot(stream, frame=2, renderer=renderer)
        explicit = snapshot(stream, frame=2, renderer=renderer, face=procedural_face)
        assert np.array_equal(alone, explicit)
        assert not np.array_equal(alone, snapshot(stream, frame=0, renderer=renderer))
