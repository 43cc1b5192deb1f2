"""MP4 and PNG-sequence output: frame counts, frame times and content, audio length and A/V sync."""
from __future__ import annotations

import wave
from fractions import Fraction

import av
import numpy as np
import pytest
from PIL import Image

from mpeg4fa.render.audio import Audio, read_audio
from mpeg4fa.render.errors import RenderError, RenderWarning
from mpeg4fa.render.video import (AAC_FRAME, MediaInfo, Mp4Writer, PngWriter, frame_rate, open_writer,
                                  probe_media)

W, H = 64, 48
STEP = 9  # grey levels between consecutive frames: far above H.264's error on a flat frame at crf 18


def grey(k: int) -> np.ndarray:
    """Frame k: a flat grey whose level encodes k."""
    return np.full((H, W, 3), 16 + STEP * k, np.uint8)


def click(n: int, rate: int, channels: int, at: int) -> Audio:
    """Silence with one short click at sample ``at``: where it decodes shows the audio's alignment."""
    samples = np.zeros((n, channels), np.float32)
    samples[at:at + 4] = 0.8
    return Audio(samples, rate)


def write_mp4(path, n_frames: int, fps, audio: Audio | None = None, **options) -> Mp4Writer:
    with Mp4Writer(path, W, H, fps, audio, **options) as writer:
        for k in range(n_frames):
            writer.write(grey(k))
            assert writer.frames_written == k + 1
    return writer


def decode_video(path) -> tuple[list[float], list[float]]:
    """Presentation times (s) and mean grey levels of the decoded frames, in order."""
    times, means = [], []
    with av.open(str(path)) as container:
        for frame in container.decode(video=0):
            times.append(float(frame.pts * frame.time_base))
            means.append(float(frame.to_ndarray(format="rgb24").mean()))
    return times, means


def click_time(channel: np.ndarray) -> float:
    """Where a click lies in samples: the centre of the signal's energy (the rest is silence)."""
    energy = channel.astype(np.float64) ** 2
    return float((np.arange(len(energy)) * energy).sum() / energy.sum())


def decode_audio(path) -> np.ndarray:
    with av.open(str(path)) as container:
        return np.concatenate([f.to_ndarray() for f in container.decode(audio=0)], axis=1).T


@pytest.mark.parametrize("fps", [25, 30, Fraction(30000, 1001), 29.97])
def test_mp4_frame_count_times_and_content(tmp_path, fps):
    path = tmp_path / "out.mp4"
    n = 20
    writer = write_mp4(path, n, fps)
    rate = frame_rate(fps)
    info = probe_media(path)
    assert (info.width, info.height, info.video_codec) == (W, H, "h264")
    assert info.n_frames == n
    assert info.fps == pytest.approx(float(rate), rel=1e-9)
    assert info.video_duration == pytest.approx(n / float(rate), abs=1e-9)
    assert info.video_start == 0.0
    assert info.audio_duration is None and info.av_offset is None
    times, means = decode_video(path)
    assert times == pytest.approx([k / float(rate) for k in range(n)], abs=1e-6)
    assert means == pytest.approx([16 + STEP * k for k in range(n)], abs=2.0)
    assert writer.frames_written == n


def test_ntsc_rates_are_exact_fractions():
    assert frame_rate(29.97) == Fraction(30000, 1001)
    assert frame_rate(30000 / 1001) == Fraction(30000, 1001)
    assert frame_rate(23.976) == Fraction(24000, 1001)
    assert frame_rate(12.5) == Fraction(25, 2)
    assert frame_rate(25) == 25
    with pytest.raises(RenderError):
        frame_rate(0)


@pytest.mark.parametrize("rate,channels,n", [(16000, 1, 16000), (16000, 2, 20 * 1024), (44100, 1, 44100),
                                             (44100, 2, 30000)])
def test_mp4_audio_length_sync_and_layout(tmp_path, rate, channels, n):
    path = tmp_path / "speech.mp4"
    at = 5000
    write_mp4(path, 10, 25, click(n, rate, channels, at))
    info = probe_media(path)
    assert (info.audio_codec, info.audio_rate, info.audio_channels) == ("aac", rate, channels)
    # AAC ends on a whole 1024-sample frame and decoders keep the padded tail.
    extra = info.audio_samples - n
    assert 0 <= extra < AAC_FRAME, extra
    assert info.audio_duration == pytest.approx(info.audio_samples / rate)
    assert info.audio_start == 0.0 and info.video_start == 0.0
    assert abs(info.av_offset) <= 1e-3
    # The encoder's 1024 priming samples are skipped exactly: the click decodes where it was written.
    decoded = decode_audio(path)
    assert decoded.shape[1] == channels
    assert click_time(decoded[:, 0]) == pytest.approx(at + 1.5, abs=1.0)


def test_unsupported_audio_rate_is_resampled_in_sync(tmp_path):
    path = tmp_path / "odd_rate.mp4"
    with pytest.warns(RenderWarning, match="22050"):
        write_mp4(path, 5, 25, click(22000, 22000, 1, 4000))
    info = probe_media(path)
    assert info.audio_rate == 22050
    assert 0 <= info.audio_samples - 22050 < AAC_FRAME
    assert click_time(decode_audio(path)[:, 0]) == pytest.approx((4000 + 1.5) * 22050 / 22000, abs=1.0)


@pytest.mark.parametrize("suffix", [".m4v", ".MOV"])
def test_other_mp4_suffixes(tmp_path, suffix):
    path = tmp_path / f"out{suffix}"
    write_mp4(path, 4, 30, click(8000, 16000, 1, 100))
    info = probe_media(path)
    assert info.n_frames == 4 and info.audio_samples >= 8000 and abs(info.av_offset) <= 1e-3


def test_odd_size_raises(tmp_path):
    with pytest.raises(RenderError) as err:
        Mp4Writer(tmp_path / "odd.mp4", 63, 48, 25)
    assert err.value.hint and "64x48" in err.value.hint
    with pytest.raises(RenderError):
        Mp4Writer(tmp_path / "odd.mp4", 64, 47, 25)


def test_unwritable_path_raises(tmp_path):
    blocker = tmp_path / "a_file"
    blocker.write_text("not a directory")
    target = blocker / "out.mp4"
    with pytest.raises(RenderError) as err:
        Mp4Writer(target, W, H, 25)
    assert err.value.where == str(target)
    with pytest.raises(RenderError):
        PngWriter(blocker / "frames", W, H, 25)


def test_bad_frames_and_options_raise(tmp_path):
    with Mp4Writer(tmp_path / "x.mp4", W, H, 25) as writer:
        with pytest.raises(RenderError):
            writer.write(np.zeros((H, W, 3), np.float32))
        with pytest.raises(RenderError):
            writer.write(np.zeros((W, H, 3), np.uint8))
        writer.write(grey(0))
    with pytest.raises(RenderError):
        writer.write(grey(1))
    with pytest.raises(RenderError):
        Mp4Writer(tmp_path / "y.mp4", W, H, 25, preset="warp")
    with pytest.raises(RenderError):
        Mp4Writer(tmp_path / "y.mp4", W, H, 25, Audio(np.zeros((10, 3), np.float32), 16000))


def test_exception_in_block_is_not_masked_and_file_is_kept(tmp_path):
    path = tmp_path / "aborted.mp4"
    with pytest.raises(KeyError, match="boom"):
        with Mp4Writer(path, W, H, 25, click(16000, 16000, 1, 0)) as writer:
            for k in range(3):
                writer.write(grey(k))
            raise KeyError("boom")
    info = probe_media(path)
    # the frames written so far, with the audio muxed alongside them (up to the encoder's delay)
    assert info.n_frames == 3
    assert info.audio_duration is None or info.audio_duration <= 3 / 25 + 0.07


def test_audio_is_interleaved_with_the_video(tmp_path):
    """Audio packets go out alongside the frames they belong with, not all after the video."""
    import av

    path = tmp_path / "interleaved.mp4"
    with Mp4Writer(path, W, H, 25, click(16000, 4 * 16000, 1, 0)) as writer:
        for k in range(100):
            writer.write(grey(k % 10))
    with av.open(str(path)) as container:
        order = [p.stream.type for p in container.demux() if p.size]
    first_audio, last_video = order.index("audio"), len(order) - 1 - order[::-1].index("video")
    assert first_audio < last_video / 2, order[:20]


def test_crf_changes_quality(tmp_path):
    rng = np.random.default_rng(0)
    noise = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
    sizes = {}
    for crf in (0, 40):
        path = tmp_path / f"crf{crf}.mp4"
        with Mp4Writer(path, W, H, 25, crf=crf, preset="ultrafast") as writer:
            writer.write(noise)
        sizes[crf] = path.stat().st_size
    assert sizes[0] > 2 * sizes[40]


def test_png_writer_frames_and_audio(tmp_path):
    directory = tmp_path / "seq" / "frames"
    audio = Audio(np.linspace(-1, 1, 2 * 12345, dtype=np.float32).reshape(-1, 2), 16000)
    with PngWriter(directory, W, H, 25, audio) as writer:
        for k in range(5):
            image = grey(k)
            image[0, 0] = (255, 0, k)
            writer.write(image)
    assert writer.frames_written == 5
    assert [p.name for p in writer.paths] == [f"frame_{k:06d}.png" for k in range(5)]
    for k, path in enumerate(writer.paths):
        expected = grey(k)
        expected[0, 0] = (255, 0, k)
        assert np.array_equal(np.asarray(Image.open(path).convert("RGB")), expected)
    with wave.open(str(directory / "audio.wav")) as wav:
        assert (wav.getnframes(), wav.getnchannels(), wav.getsampwidth(), wav.getframerate()) == (12345, 2, 2, 16000)
    back = read_audio(directory / "audio.wav")
    assert back.samples.shape == (12345, 2)
    assert np.allclose(back.samples, audio.samples, atol=1 / 16000)


def test_png_writer_pattern_and_no_audio(tmp_path):
    with PngWriter(tmp_path / "p", W, H, pattern="img{:03d}.png") as writer:
        writer.write(grey(1))
    assert [p.name for p in (tmp_path / "p").iterdir()] == ["img000.png"]
    with pytest.raises(RenderError):
        PngWriter(tmp_path / "q", W, H, pattern="fixed.png")


def test_open_writer_dispatch(tmp_path):
    for name in ("a.mp4", "b.M4V", "c.mov"):
        writer = open_writer(tmp_path / name, W, H, 25, crf=23)
        assert isinstance(writer, Mp4Writer)
        writer.close()
    writer = open_writer(tmp_path / "frames", W, H, 25, compress_level=0)
    assert isinstance(writer, PngWriter) and (tmp_path / "frames").is_dir()
    writer.close()
    existing = tmp_path / "notes.txt"
    existing.write_text("x")
    with pytest.raises(RenderError) as err:
        open_writer(existing, W, H, 25)
    assert err.value.hint
    with pytest.raises(RenderError):
        open_writer(tmp_path / "out.mkv", W, H, 25)
    with pytest.raises(RenderError):
        open_writer(tmp_path / "d.mp4", W, H, 25, pattern="x{}.png")


def test_probe_media_missing_file(tmp_path):
    with pytest.raises(RenderError):
        probe_media(tmp_path / "none.mp4")
    assert MediaInfo("x", 2, 2, 0, 25.0, 0.0, 0.0, "h264", audio_start=0.5).av_offset == 0.5


def test_audio_longer_than_the_ceiling_is_refused_naming_the_file(tmp_path):
    """Issue 26: a small file must not ask for unbounded memory; the header's duration is checked first, and a
    file whose header says nothing is stopped while decoding."""
    from mpeg4fa.wav import write_pcm16

    path = tmp_path / "long.wav"
    write_pcm16(path, np.zeros(8000 * 3, np.int16), 8000)
    assert read_audio(path, max_seconds=5).duration == pytest.approx(3.0)
    with pytest.raises(RenderError, match="more than 2 s") as info:
        read_audio(path, max_seconds=2)
    assert info.value.where == str(path)
