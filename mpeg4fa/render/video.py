"""Video output: H.264/AAC MP4 files or PNG sequences, written in-process, and reading MP4s back.

Everything goes through PyAV (FFmpeg's libraries), so no ``ffmpeg`` executable is
needed and no pipes or temporary files are involved.

Timing: frame k is presented at exactly ``k / rate`` where ``rate`` is the frame
rate as a fraction (see :func:`frame_rate`); the video time base is ``1/rate``.
Audio starts at sample 0 = time 0. FFmpeg's AAC encoder puts 1024 samples of
priming (encoder delay) before the first real sample and gives the first packet
pts -1024; the MP4/MOV muxer writes an edit list that skips exactly those 1024
samples, so a reader sees both streams start at 0 and the first decoded sample is
the caller's first sample. The edit list is requested explicitly
(``use_editlist=1``): without it the audio plays 1024 samples late (64 ms at
16 kHz) and the video starts at its B-frame delay.

The AAC stream ends on a 1024-sample frame boundary; decoders return the padded
tail, so decoded audio is 0..1023 samples longer than what was given.
"""
from __future__ import annotations

import math
import os
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from types import TracebackType

import numpy as np

from mpeg4fa.wav import write_pcm16
from mpeg4fa.render.audio import Audio
from mpeg4fa.render.errors import RenderError, RenderWarning

VIDEO_SUFFIXES = (".mp4", ".m4v", ".mov")
# Containers people may type that this module does not write: refuse them rather
# than silently making a PNG directory called "out.mkv".
OTHER_VIDEO_SUFFIXES = (".mkv", ".webm", ".avi", ".gif", ".wmv", ".flv", ".mpg", ".mpeg", ".ts")
_MUXER_FOR_SUFFIX = {".mp4": "mp4", ".m4v": "mp4", ".mov": "mov"}
X264_PRESETS = ("ultrafast", "superfast", "veryfast", "faster", "fast", "medium", "slow", "slower",
                "veryslow", "placebo")
# The sampling rates AAC defines (ISO/IEC 14496-3 sampling_frequency_index).
AAC_RATES = (7350, 8000, 11025, 12000, 16000, 22050, 24000, 32000, 44100, 48000, 64000, 88200, 96000)
AAC_FRAME = 1024
AUDIO_WAV = "audio.wav"
_AUDIO_CHUNK = 16 * AAC_FRAME
_MAX_DENOMINATOR = 10000


def frame_rate(fps: float | Fraction) -> Fraction:
    """The frame rate as an exact fraction, so that frame times do not drift.

    NTSC-style rates typed as decimals (29.97, 23.976, 59.94) mean N*1000/1001 and are
    taken as such; anything else is the closest fraction with a denominator <= 10000.
    """
    if isinstance(fps, Fraction):
        rate = fps
    else:
        value = float(fps)
        if not math.isfinite(value):
            raise RenderError(f"frame rate {fps!r} is not a finite number", hint="give e.g. 25 or 30000/1001")
        rate = Fraction(value).limit_denominator(_MAX_DENOMINATOR)
        n = round(value * 1001 / 1000)
        if rate.denominator != 1 and n > 0 and abs(value - n * 1000 / 1001) < 5e-3:
            rate = Fraction(n * 1000, 1001)
    if rate <= 0:
        raise RenderError(f"frame rate {fps!r} is not positive", hint="give e.g. 25 or 30000/1001")
    return rate


def _check_size(width: int, height: int, where: str) -> tuple[int, int]:
    if int(width) != width or int(height) != height or width <= 0 or height <= 0:
        raise RenderError(f"frame size {width}x{height} is not a positive whole number of pixels", where=where)
    return int(width), int(height)


def _check_audio(audio: Audio, where: str) -> np.ndarray:
    """The samples as a (n, channels) float32 array clipped to [-1, 1]."""
    samples = np.asarray(audio.samples, dtype=np.float32)
    if samples.ndim == 1:
        samples = samples[:, None]
    if samples.ndim != 2 or samples.shape[1] not in (1, 2):
        raise RenderError(f"audio of shape {samples.shape} is not mono or stereo", where=where,
                          hint="give samples shaped (n, 1) or (n, 2)")
    if len(samples) == 0:
        raise RenderError("the audio holds no samples", where=where, hint="pass audio=None for a silent video")
    if int(audio.rate) != audio.rate or audio.rate <= 0:
        raise RenderError(f"audio rate {audio.rate!r} is not a positive whole number", where=where)
    return np.clip(samples, -1.0, 1.0)


def _check_image(image: np.ndarray, width: int, height: int, where: str) -> np.ndarray:
    array = np.asarray(image)
    if array.dtype != np.uint8 or array.shape != (height, width, 3):
        raise RenderError(f"frame is {array.dtype} {array.shape}, expected uint8 ({height}, {width}, 3) RGB",
                          where=where, hint="the writer's size is fixed when it is opened")
    return np.ascontiguousarray(array)


def _aac_rate(rate: int) -> int:
    """The AAC rate to encode ``rate`` at: itself when AAC has it, else the next higher one."""
    if rate in AAC_RATES:
        return rate
    return next((r for r in AAC_RATES if r >= rate), AAC_RATES[-1])


def _resample(samples: np.ndarray, rate: int, target: int) -> np.ndarray:
    """``samples`` at ``target`` Hz (libswresample), for rates the AAC encoder refuses."""
    import av

    layout = "mono" if samples.shape[1] == 1 else "stereo"
    resampler = av.AudioResampler(format="fltp", layout=layout, rate=target)
    frame = av.AudioFrame.from_ndarray(np.ascontiguousarray(samples.T), format="fltp", layout=layout)
    frame.sample_rate = rate
    frame.pts = 0
    frame.time_base = Fraction(1, rate)
    chunks = [out.to_ndarray() for out in resampler.resample(frame)]
    chunks += [out.to_ndarray() for out in resampler.resample(None)]
    return np.concatenate(chunks, axis=1).T.astype(np.float32)


class _Writer:
    """The context-manager protocol shared by both writers."""

    def __enter__(self):
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        if exc_type is None:
            self.close()
        else:
            self._abort()

    def close(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError

    def _abort(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError


class Mp4Writer(_Writer):
    """H.264 (libx264, yuv420p) video with optional AAC audio in an MP4/MOV file.

    Frames are encoded as they are written; the audio, given whole up front, is
    encoded alongside, up to each frame's end, so the file interleaves sound and
    pictures (and ``+faststart`` puts the index first) for players that stream it.
    Leaving a ``with`` block through an exception finishes the file with the frames
    written so far and no audio, and lets the exception through.
    """

    def __init__(self, path: str | os.PathLike, width: int, height: int, fps: float | Fraction,
                 audio: Audio | None = None, *, crf: float = 18, preset: str = "veryfast") -> None:
        import av

        self.path = Path(path)
        where = str(self.path)
        self.width, self.height = _check_size(width, height, where)
        if self.width % 2 or self.height % 2:
            raise RenderError(f"frame size {self.width}x{self.height} is odd; H.264 yuv420p needs even sizes",
                              where=where,
                              hint=f"use {self.width + self.width % 2}x{self.height + self.height % 2} "
                                   "or crop a pixel")
        if not 0 <= crf <= 51:
            raise RenderError(f"crf {crf} is outside 0..51", where=where, hint="18 is visually lossless")
        if preset not in X264_PRESETS:
            raise RenderError(f"unknown x264 preset {preset!r}", where=where, hint=", ".join(X264_PRESETS))
        self.rate = frame_rate(fps)
        self.audio = audio
        self._samples = _check_audio(audio, where) if audio is not None else None
        self._frames = 0
        self._audio_pos = 0
        self._closed = False
        self._time_base = 1 / self.rate
        muxer = _MUXER_FOR_SUFFIX.get(self.path.suffix.lower(), "mp4")
        self._container = None
        try:
            # FFmpeg opens the file only when the header is written (at the first frame):
            # create it now so that a bad path fails here, not after rendering.
            with open(self.path, "wb"):
                pass
            self._container = av.open(where, "w", format=muxer,
                                      options={"use_editlist": "1", "movflags": "+faststart"})
            self._video = self._container.add_stream("libx264", rate=self.rate)
            self._video.width, self._video.height = self.width, self.height
            self._video.pix_fmt = "yuv420p"
            self._video.time_base = self._time_base
            self._video.codec_context.time_base = self._time_base
            self._video.options = {"crf": f"{crf:g}", "preset": preset}
            self._audio = None
            if self._samples is not None:
                rate = _aac_rate(int(audio.rate))
                if rate != audio.rate:
                    import warnings

                    warnings.warn(f"AAC has no {audio.rate} Hz: audio resampled to {rate} Hz",
                                  RenderWarning, stacklevel=2)
                    self._samples = _resample(self._samples, int(audio.rate), rate)
                self._audio_rate = rate
                self._layout = "mono" if self._samples.shape[1] == 1 else "stereo"
                self._audio = self._container.add_stream("aac", rate=rate, layout=self._layout)
                self._audio.time_base = Fraction(1, rate)
        except (av.FFmpegError, OSError) as exc:
            self._discard()
            raise RenderError(f"cannot open the video for writing: {exc}", where=where,
                              hint="check that the directory exists and is writable") from None

    @property
    def frames_written(self) -> int:
        """How many frames have been written (the next frame's index)."""
        return self._frames

    def write(self, image: np.ndarray) -> None:
        """Encode one (H, W, 3) uint8 RGB frame, presented at frames_written / rate."""
        import av

        where = str(self.path)
        if self._closed:
            raise RenderError("the writer is closed", where=where)
        array = _check_image(image, self.width, self.height, f"{where} (frame {self._frames})")
        frame = av.VideoFrame.from_ndarray(array, format="rgb24")
        frame.pts = self._frames
        frame.time_base = self._time_base
        try:
            self._container.mux(self._video.encode(frame))
            if self._audio is not None:
                self._write_audio(until=int(math.ceil((self._frames + 1) / self.rate * self._audio_rate)))
        except (av.FFmpegError, OSError) as exc:
            raise RenderError(f"cannot encode frame {self._frames}: {exc}", where=where) from None
        self._frames += 1

    def close(self) -> None:
        """Flush the video encoder, encode and mux the audio, and finish the file."""
        import av

        if self._closed:
            return
        self._closed = True
        try:
            self._container.mux(self._video.encode(None))
            if self._audio is not None:
                self._write_audio(until=len(self._samples))
                self._container.mux(self._audio.encode(None))
            self._container.close()
        except (av.FFmpegError, OSError) as exc:
            self._discard()
            raise RenderError(f"cannot finish the video: {exc}", where=str(self.path)) from None

    def _write_audio(self, until: int) -> None:
        """Encode and mux the audio from where it stopped up to sample ``until`` (in whole chunks)."""
        import av

        until = min(until, len(self._samples))
        while self._audio_pos < until:
            start = self._audio_pos
            chunk = np.ascontiguousarray(self._samples[start:min(start + _AUDIO_CHUNK, until)].T)
            frame = av.AudioFrame.from_ndarray(chunk, format="fltp", layout=self._layout)
            frame.sample_rate = self._audio_rate
            frame.time_base = Fraction(1, self._audio_rate)
            frame.pts = start
            self._container.mux(self._audio.encode(frame))
            self._audio_pos = start + chunk.shape[1]

    def _abort(self) -> None:
        """Finish the file with what was written (no audio), swallowing errors: another is on its way."""
        import av

        if self._closed:
            return
        self._closed = True
        try:
            self._container.mux(self._video.encode(None))
            self._container.close()
        except (av.FFmpegError, OSError, ValueError):
            self._discard()

    def _discard(self) -> None:
        if self._container is not None:
            try:
                self._container.close()
            except Exception:  # already failing: the first error is the one to report
                pass


class PngWriter(_Writer):
    """Frames as numbered PNG files in a directory, with the audio beside them as audio.wav.

    For lossless output or editing tools that take image sequences. ``fps`` is kept
    only so the writer has the same shape as :class:`Mp4Writer`.
    """

    def __init__(self, directory: str | os.PathLike, width: int, height: int, fps: float | Fraction | None = None,
                 audio: Audio | None = None, *, pattern: str = "frame_{:06d}.png", compress_level: int = 1) -> None:
        self.directory = Path(directory)
        where = str(self.directory)
        self.width, self.height = _check_size(width, height, where)
        self.rate = frame_rate(fps) if fps is not None else None
        try:
            first, second = pattern.format(0), pattern.format(1)
        except (IndexError, KeyError, ValueError) as exc:
            raise RenderError(f"bad file name pattern {pattern!r}: {exc}", where=where,
                              hint="one integer field, e.g. 'frame_{:06d}.png'") from None
        if first == second or os.sep in first or (os.altsep and os.altsep in first):
            raise RenderError(f"file name pattern {pattern!r} does not number plain file names", where=where,
                              hint="one integer field, e.g. 'frame_{:06d}.png'")
        if not 0 <= compress_level <= 9:
            raise RenderError(f"compress_level {compress_level} is outside 0..9", where=where)
        self.pattern = pattern
        self.compress_level = int(compress_level)
        self.audio = audio
        self._samples = _check_audio(audio, where) if audio is not None else None
        self.paths: list[Path] = []
        self.audio_path: Path | None = None
        self._closed = False
        if self.directory.exists() and not self.directory.is_dir():
            raise RenderError("exists and is not a directory", where=where,
                              hint="PNG frames go into a directory; give a new name or a .mp4 file")
        try:
            self.directory.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise RenderError(f"cannot create the frame directory: {exc}", where=where,
                              hint="check that the parent is a writable directory") from None

    @property
    def frames_written(self) -> int:
        """How many frames have been written."""
        return len(self.paths)

    def write(self, image: np.ndarray) -> None:
        """Save one (H, W, 3) uint8 RGB frame as the next numbered PNG."""
        from PIL import Image

        if self._closed:
            raise RenderError("the writer is closed", where=str(self.directory))
        path = self.directory / self.pattern.format(len(self.paths))
        array = _check_image(image, self.width, self.height, str(path))
        try:
            Image.fromarray(array).save(path, format="PNG", compress_level=self.compress_level)
        except OSError as exc:
            raise RenderError(f"cannot write the frame: {exc}", where=str(path)) from None
        self.paths.append(path)

    def close(self) -> None:
        """Write audio.wav (16-bit PCM) when there is audio; the frames are already on disk."""
        if self._closed:
            return
        self._closed = True
        if self._samples is not None:
            self.audio_path = self.directory / AUDIO_WAV
            write_wav(self.audio_path, Audio(self._samples, int(self.audio.rate)))

    def _abort(self) -> None:
        self._closed = True


def write_wav(path: str | os.PathLike, audio: Audio) -> None:
    """Save audio as a 16-bit PCM WAV (stdlib ``wave``), the format every tool reads."""
    samples = _check_audio(audio, str(path))
    pcm = np.round(samples * 32767.0).astype("<i2")
    try:
        write_pcm16(path, pcm, audio.rate)
    except OSError as exc:
        raise RenderError(f"cannot write the audio: {exc}", where=str(path)) from None


_MP4_OPTIONS = {"crf", "preset"}
_PNG_OPTIONS = {"pattern", "compress_level"}


def writes_folder(target: str | os.PathLike) -> bool:
    """Whether ``target`` names a PNG folder (else an MP4 file); RenderError for a name that can be neither."""
    path = Path(target)
    suffix = path.suffix.lower()
    if suffix in VIDEO_SUFFIXES:
        return False
    if suffix in OTHER_VIDEO_SUFFIXES:
        raise RenderError(f"{suffix} video is not supported", where=str(path),
                          hint="write .mp4, .m4v or .mov, or give a directory for PNG frames")
    if path.exists() and not path.is_dir():
        raise RenderError("exists and is a file, not a directory or a video name", where=str(path),
                          hint="give a .mp4/.m4v/.mov file, or a directory for PNG frames")
    return True


def open_writer(target: str | os.PathLike, width: int, height: int, fps: float | Fraction,
                audio: Audio | None = None, **options) -> Mp4Writer | PngWriter:
    """A writer chosen by the target's name: .mp4/.m4v/.mov -> MP4 file, anything else -> PNG directory."""
    path = Path(target)
    kind, allowed = (PngWriter, _PNG_OPTIONS) if writes_folder(path) else (Mp4Writer, _MP4_OPTIONS)
    unknown = sorted(set(options) - allowed)
    if unknown:
        raise RenderError(f"option(s) {', '.join(unknown)} do not apply to {kind.__name__}", where=str(path),
                          hint=f"{kind.__name__} takes {', '.join(sorted(allowed))}")
    return kind(path, width, height, fps, audio, **options)


@dataclass(frozen=True)
class MediaInfo:
    """What an MP4 holds, measured by decoding it (not from header guesses)."""

    path: str
    width: int
    height: int
    n_frames: int
    fps: float
    video_duration: float  # n_frames / fps
    video_start: float
    video_codec: str
    audio_codec: str | None = None
    audio_rate: int | None = None
    audio_channels: int | None = None
    audio_samples: int | None = None
    audio_duration: float | None = None  # audio_samples / audio_rate
    audio_start: float | None = None

    @property
    def av_offset(self) -> float | None:
        """Audio start minus video start in seconds (None without audio): 0 when in sync."""
        if self.audio_start is None:
            return None
        return self.audio_start - self.video_start


def _start_seconds(stream, first: float | None) -> float:
    if stream.start_time is not None:
        return float(stream.start_time * stream.time_base)
    return first if first is not None else 0.0


def probe_media(path: str | os.PathLike) -> MediaInfo:
    """Decode a video file's first video and audio streams and report counts, rates and start times."""
    import av

    path = Path(path)
    where = str(path)
    if not path.is_file():
        raise RenderError("no such video file" if not path.exists() else "not a file", where=where)
    try:
        with av.open(where) as container:
            if not container.streams.video:
                raise RenderError("the file has no video stream", where=where)
            video = container.streams.video[0]
            audio = container.streams.audio[0] if container.streams.audio else None
            rate = video.average_rate or video.guessed_rate or video.base_rate
            if not rate:
                raise RenderError("the video stream has no frame rate", where=where)
            streams = [video] if audio is None else [video, audio]
            n_frames = 0
            n_samples = 0
            first_video = first_audio = None
            for packet in container.demux(*streams):
                for frame in packet.decode():
                    if packet.stream is video:
                        if first_video is None and frame.pts is not None:
                            first_video = float(frame.pts * frame.time_base)
                        n_frames += 1
                    else:
                        if first_audio is None and frame.pts is not None:
                            first_audio = float(frame.pts * frame.time_base)
                        n_samples += frame.samples
            fps = float(rate)
            info = dict(path=where, width=video.codec_context.width, height=video.codec_context.height,
                        n_frames=n_frames, fps=fps, video_duration=n_frames / fps,
                        video_start=_start_seconds(video, first_video), video_codec=video.codec_context.name)
            if audio is not None:
                audio_rate = int(audio.codec_context.sample_rate or audio.rate)
                info.update(audio_codec=audio.codec_context.name, audio_rate=audio_rate,
                            audio_channels=audio.codec_context.channels, audio_samples=n_samples,
                            audio_duration=n_samples / audio_rate,
                            audio_start=_start_seconds(audio, first_audio))
    except RenderError:
        raise
    except (av.FFmpegError, OSError) as exc:
        raise RenderError(f"cannot read the video: {exc}", where=where) from None
    return MediaInfo(**info)
