"""Reading an image file (a texture, a photo) for the renderer: one RGB array or one located error."""
from __future__ import annotations

import os

import numpy as np

from mpeg4fa.render.errors import RenderError


def read_image(path: str | os.PathLike, what: str) -> np.ndarray:
    """An image file as (H, W, 3) uint8 RGB; RenderError naming the file (and ``what`` it was for) otherwise."""
    from PIL import Image, UnidentifiedImageError
    try:
        with Image.open(path) as img:
            return np.asarray(img.convert("RGB"))
    except FileNotFoundError:
        raise RenderError(f"no such {what}", where=str(path)) from None
    except (OSError, UnidentifiedImageError, ValueError) as exc:
        raise RenderError(f"cannot read the {what} ({exc})", where=str(path)) from None
