"""What the rendering commands share: reading images, and rendering a stream with a progress bar."""
from __future__ import annotations

import sys
import warnings
from pathlib import Path

import numpy as np

from ..errors import MpegFaWarning
from ..render import RenderError
from .progress import ProgressBar


def read_image(path: Path, what: str) -> np.ndarray:
    """An image file as (H, W, 3) uint8 RGB; RenderError naming the file otherwise."""
    from PIL import Image, UnidentifiedImageError
    try:
        with Image.open(path) as img:
            return np.asarray(img.convert("RGB"))
    except FileNotFoundError:
        raise RenderError(f"no such {what}", where=str(path)) from None
    except (OSError, UnidentifiedImageError) as exc:
        raise RenderError(f"cannot read the {what} ({exc})", where=str(path)) from None


def render_with_progress(command: str, stream, output: Path, **play_options):
    """:func:`mpeg4fa.render.play` with a progress bar; its warnings become ``command: warning:`` lines."""
    from ..render import play

    bar = ProgressBar(f"rendering {output.name}")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", MpegFaWarning)
        try:
            result = play(stream, output, progress=bar, **play_options)
        finally:
            bar.close()
    for w in caught:
        print(f"mpeg4fa {command}: warning: {w.message}", file=sys.stderr)
    return result
