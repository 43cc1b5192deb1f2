#!/usr/bin/env python3
"""The picture of photo -> FDP for the docs (issue 27): a photo, the feature points found on it, the head
calibrated to them and wearing the photo (front and three-quarter), and a frame of that face talking.

    .venv/bin/python tools/photo_sheet.py [PHOTO] [--out docs/pictures/photo-to-fdp.png] [--size 384]

Without PHOTO: scikit-image's astronaut. Also prints the time each step took (landmarks, FDP, calibration,
bake, renders). The talking frame is the widest-open mouth of "Hello, I am an astronaut." (the estimate
engine: no TTS needed).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.render import Renderer  # noqa: E402
from mpeg4fa.tracking.photo import fdp_from_photo, preview, textured_head  # noqa: E402

TEXT = "Hello, I am an astronaut."
CAPTIONS = ("photo: the points found", "calibrated head, front", "three-quarter", "talking")


def talking_frame(face, texture, size: int) -> np.ndarray:
    """The face saying TEXT at the frame where its jaw opens most (FAP 3), three-quarter view."""
    from mpeg4fa.decoded import resolve
    from mpeg4fa.speech.encoder import encode_text

    stream = encode_text(TEXT, engine="estimate").stream
    values = resolve(stream)
    k = int(np.argmax(values[:, 2]))
    with Renderer(face, width=size, height=size, samples=4, view=(20.0, 3.0), texture=texture) as renderer:
        return renderer.render(face.pose_values(values[k]))


def caption(picture: np.ndarray, size: int) -> np.ndarray:
    """A strip of captions under the panels."""
    strip = Image.new("RGB", (picture.shape[1], 24), (30, 33, 40))
    draw = ImageDraw.Draw(strip)
    x = 0
    widths = [picture.shape[1] - 3 * size] + [size] * 3
    for text, width in zip(CAPTIONS, widths):
        draw.text((x + 8, 6), text, fill=(230, 230, 230))
        x += width
    return np.concatenate([picture, np.asarray(strip)], axis=0)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("photo", nargs="?", type=Path, help="a front photo (default: scikit-image's astronaut)")
    p.add_argument("--out", type=Path, default=Path("docs/pictures/photo-to-fdp.png"))
    p.add_argument("--size", type=int, default=384)
    args = p.parse_args(argv)
    if args.photo is None:
        from skimage import data
        source, where = data.astronaut(), "astronaut"
    else:
        source, where = args.photo, str(args.photo)
    t0 = time.perf_counter()
    made = fdp_from_photo(source, where=where)
    t1 = time.perf_counter()
    face, texture = textured_head(made)
    t2 = time.perf_counter()
    talking = talking_frame(face, texture, args.size)
    picture = caption(preview(made, extra=talking, size=args.size), args.size)
    t3 = time.perf_counter()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    Image.fromarray(picture).save(args.out)
    print(f"{args.out}: {picture.shape[1]}x{picture.shape[0]}; FDP from the photo {t1 - t0:.2f} s, calibration + "
          f"texture {t2 - t1:.2f} s, renders {t3 - t2:.2f} s; {len(made.fdp.labels)} points")
    return 0


if __name__ == "__main__":
    sys.exit(main())
