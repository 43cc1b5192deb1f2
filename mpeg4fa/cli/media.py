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


def check_video_size(output: Path, size: tuple[int, int]) -> None:
    """An MP4 needs even sides (H.264 yuv420p): say so before any work, not after the speech and the render."""
    from ..render.video import VIDEO_SUFFIXES

    width, height = size
    if output.suffix.lower() in VIDEO_SUFFIXES and (width % 2 or height % 2):
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


def save_image(image, path: Path) -> None:
    """Save a PIL image whole or not at all (format from the name); RenderError for a name PIL has no format for
    (an OS error names the file itself: :func:`mpeg4fa.atomic.atomic_output`)."""
    from ..atomic import atomic_output
    from ..render import RenderError

    try:
        with atomic_output(path) as partial:
            image.save(partial)
    except ValueError as exc:
        raise RenderError(f"cannot write the image ({exc})", where=str(path),
                          hint="name it .png, .jpg, .bmp or .tif") from None


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
