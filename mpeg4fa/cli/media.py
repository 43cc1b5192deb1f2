"""What the rendering commands share: the skin texture and speech they find, checking video sizes, and rendering
with a progress bar."""
from __future__ import annotations

import argparse
import contextlib
import sys
import warnings
from pathlib import Path
from typing import Iterator

from ..errors import MpegFaWarning
from .errors import UsageError
from .progress import ProgressBar


NOT_FRAMES: dict[str, tuple[str, ...]] = {
    "audio": (".wav", ".mp3", ".flac", ".ogg", ".opus", ".m4a", ".aac"),
    "stream": (".fba", ".fap", ".bap", ".fdp"),
    "image": (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".webp"),
    "text": (".json", ".txt", ".csv"),
}
"""Kind -> suffixes that name a file, not a folder of PNG frames: ``say -o s.wav`` would otherwise write a folder
of PNGs called s.wav (any name that is not a video is a frames folder)."""

_INSTEAD = {  # (command, kind) -> what to run for that file instead ({stem}, {name}: the -o name's)
    ("say", "audio"): "for the speech alone: mpeg4fa encode TEXT -o {stem}.fba --audio {name}",
    ("say", "stream"): "for the stream alone: mpeg4fa encode TEXT -o {stem}.fba",
    ("say", "text"): "for the viseme timings: mpeg4fa encode TEXT -o {stem}.fba --timings {stem}.json",
    ("play", "image"): "for one frame: mpeg4fa snapshot STREAM -o {name}",
    ("play", "stream"): "for the stream as text: mpeg4fa decode STREAM -o {stem}.fap",
}


def check_frames_output(command: str, output: Path, size: tuple[int, int]) -> None:
    """Refuse, before any work, an ``-o`` that ``command`` cannot render to: a name of another kind of file
    (s.wav, s.fba, s.png, s.json: it would become a folder of PNGs so named; an existing folder is taken as
    it is), a video container not written (.mkv...), or odd sides for an MP4 (H.264 yuv420p needs even ones)."""
    from ..render import RenderError
    from ..render.video import VIDEO_SUFFIXES, writes_folder

    suffix = output.suffix.lower()
    kind = next((k for k, suffixes in NOT_FRAMES.items() if suffix in suffixes), None)
    if kind is not None and not output.is_dir():
        stem = output.with_suffix("")
        instead = _INSTEAD.get((command, kind), "").format(stem=stem, name=output)
        raise UsageError(f"-o {output}: {command} renders video, not {'an' if kind[0] in 'aei' else 'a'} {kind} "
                         f"file ({suffix})", hint=f"use -o {stem}.mp4, or -o {stem}/ for a folder of PNG frames"
                                                   + (f"; {instead}" if instead else ""))
    try:
        writes_folder(output)
    except RenderError as exc:
        raise UsageError(f"-o {output}: {exc.message}", hint=exc.hint) from None
    width, height = size
    if suffix in VIDEO_SUFFIXES and (width % 2 or height % 2):
        raise UsageError(f"--size {width}x{height} is odd; an MP4 (H.264) needs even sizes",
                         hint=f"use {width + width % 2}x{height + height % 2}, or a folder for PNG frames")


@contextlib.contextmanager
def rendering(command: str, output: Path) -> Iterator[ProgressBar]:
    """A progress bar for rendering ``output``; the layers' warnings become ``command: warning:`` lines after it."""
    bar = ProgressBar(f"rendering {output.name or output}")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", MpegFaWarning)
        try:
            yield bar
        finally:
            bar.close()
            for w in caught:
                print(f"mpeg4fa {command}: warning: {one_line(w.message)}", file=sys.stderr)


def render_with_progress(command: str, stream, output: Path, **play_options):
    """:func:`mpeg4fa.render.play` with a progress bar; its warnings become ``command: warning:`` lines."""
    from ..render import play

    with rendering(command, output) as bar:
        return play(stream, output, progress=bar, **play_options)


def one_line(message: object) -> str:
    """A warning's text on one line (some libraries' warnings span several)."""
    return " ".join(str(message).split())


def image_format(command: str, output: Path) -> str:
    """The PIL format ``output``'s name asks for; UsageError, before any rendering, for a name no image format
    has (``snapshot -o f.mp4``: one frame is an image; a video is what play makes)."""
    from PIL import Image

    suffix = output.suffix.lower()
    chosen = Image.registered_extensions().get(suffix)
    if chosen in Image.SAVE:
        return chosen
    from ..render.video import OTHER_VIDEO_SUFFIXES, VIDEO_SUFFIXES

    video = suffix in VIDEO_SUFFIXES + OTHER_VIDEO_SUFFIXES
    named = f"{suffix} is no image format" if suffix else "its name has no image suffix"
    raise UsageError(f"-o {output}: {command} writes one image, and {named}",
                     hint=f"name it {output.with_suffix('.png')}, or .jpg, .bmp, .tif"
                          + ("; for video: mpeg4fa play STREAM -o " + str(output) if video else ""))


def save_image(image, path: Path, command: str) -> None:
    """Save a PIL image whole or not at all, in the format its name asks for (:func:`image_format`); an OS
    error names the file itself (:func:`mpeg4fa.atomic.atomic_output`)."""
    from ..atomic import atomic_output
    from ..render import RenderError

    chosen = image_format(command, path)
    try:
        with atomic_output(path) as partial:
            image.save(partial, format=chosen)
    except ValueError as exc:  # the format refuses this image (its mode, its size)
        raise RenderError(f"cannot write the image as {chosen} ({exc})", where=str(path),
                          hint=f"name it {path.with_suffix('.png')}") from None


AUDIO_SUFFIXES = (".wav", ".WAV", ".Wav")


def skin_texture(args: argparse.Namespace, face):
    """--texture, else the texture the FDP carries (mapped through its points' texture coordinates), else None."""
    from ..render.images import read_image

    if args.texture is not None:
        return read_image(args.texture, "texture image")
    if args.fdp is None or args.no_fdp_texture:
        return None
    from ..fdp import load_fdp
    from ..render.fdp_texture import fdp_skin_texture

    sent = fdp_skin_texture(face.mesh, load_fdp(args.fdp), source=str(args.fdp))
    if sent is None:
        return None
    width, height = sent.map.size
    print(f"texture: {sent.name} ({width}x{height}) from {args.fdp}, mapped through {len(sent.map.labels)} feature "
          f"points onto {sent.coverage:.0%} of the skin (--no-fdp-texture to leave it out)", file=sys.stderr)
    return sent.image


def audio_beside(args: argparse.Namespace) -> Path | None:
    """--audio, else nothing with --no-audio, else a WAV beside the stream (said on stderr), else None."""
    if args.audio is not None or args.no_audio:
        return args.audio
    for suffix in AUDIO_SUFFIXES:
        candidate = args.stream.with_suffix(suffix)
        if candidate.is_file():
            print(f"audio: {candidate} (found beside the stream; --no-audio to leave it out)", file=sys.stderr)
            return candidate
    return None
