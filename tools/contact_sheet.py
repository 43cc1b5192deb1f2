#!/usr/bin/env python3
"""Contact sheet of the face's looks: the 14 MPEG-4 visemes, the 15 Chinese visemes and the 6
expressions at full intensity, front and three-quarter, plus the blink and brow poses people
notice first. Writes PNGs under out/contact/ (not committed) for looking at.

    .venv/bin/python tools/contact_sheet.py [--deformer NAME (see --help)] [--size 256] [--out out/contact]
                                            [--crop face|mouth|eyes] [--only visemes|chinese|expressions|extras]
    .venv/bin/python tools/contact_sheet.py --compare [--view front|three-quarter] ...
    .venv/bin/python tools/contact_sheet.py --docs [--size 160] [--out docs/pictures]

``--compare`` puts every registered deformer side by side: one row per deformer, the looks in columns.
``--docs`` writes the sheets of the docs (JPEG): every group, front and three-quarter, on the generic
head and on the head calibrated to a photo (scikit-image's astronaut through ``mpeg4fa fdp``'s
:func:`mpeg4fa.tracking.photo.fdp_from_photo`, wearing the photo), plus the deformer comparisons.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.face import FaceModel  # noqa: E402
from mpeg4fa.render.camera import frame_points  # noqa: E402
from mpeg4fa.render.renderer import Renderer  # noqa: E402
from mpeg4fa.spec import EXPRESSIONS, VISEMES  # noqa: E402
from mpeg4fa.spec.profiles import CHINESE_VISEMES, EXPRESSION_PROFILES, VISEME_PROFILES  # noqa: E402

CROPS = {  # feature points the camera frames
    "face": None,
    "mouth": ("2.1", "8.1", "8.3", "8.4", "9.15", "2.10"),
    "eyes": ("3.7", "3.8", "4.5", "4.6", "3.3", "3.4", "3.1", "3.2"),
}
EXTRAS = {
    "blink (19/20 to 3.3)": "blink",
    "half blink": "half",
    "lower lids 21/22=300": {21: 300, 22: 300},
    "brows up 31-36=200": {31: 200, 32: 200, 33: 200, 34: 200, 35: 200, 36: 200},
    "brows up x2 (400)": {31: 400, 32: 400, 33: 400, 34: 400, 35: 400, 36: 400},
    "squeeze 37/38=200": {37: 200, 38: 200},
    "cheeks 41/42=600": {41: 600, 42: 600},
    "jaw 3=1024": {3: 1024},
}


def poses(face: FaceModel, only: str | None) -> list[tuple[str, np.ndarray]]:
    """(label, 68 FAP values) for every look on the sheet."""
    out = []
    if only in (None, "visemes"):
        out += [(f"{v.number} {v.name}", VISEME_PROFILES["mpeg4"][v.name]) for v in VISEMES if v.number]
    if only in (None, "chinese"):
        out += [(f"zh {v.name}", VISEME_PROFILES["zh"][v.name]) for v in CHINESE_VISEMES]
    if only in (None, "expressions"):
        out += [(e.name, EXPRESSION_PROFILES[e.name]) for e in EXPRESSIONS if e.number]
    if only in (None, "extras"):
        fp = face.feature_points()
        closing = (fp["3.1"][1] - fp["3.3"][1]) / face.fapu.unit("IRISD")
        for label, spec in EXTRAS.items():
            v = np.zeros(68)
            if spec in ("blink", "half"):
                v[18] = v[19] = closing * (1.0 if spec == "blink" else 0.5)
            else:
                for fap, value in spec.items():
                    v[fap - 1] = value
            out.append((label, v))
    return out


def sheet(face: FaceModel, looks, size: int, crop: str, views=("front", "three-quarter"), cols: int = 8,
          texture: np.ndarray | None = None) -> Image.Image:
    tiles = []
    points = face.mesh.feature_points()
    if CROPS[crop]:
        points = np.array([face.mesh.fp(label) for label in CROPS[crop]])
    renderers = []
    for view in views:
        camera = frame_points(points, size, size, view=view)
        renderers.append(Renderer(face, width=size, height=size, samples=4, camera=camera, texture=texture))
    try:
        for label, values in looks:
            v = np.asarray(values, float).copy()
            v[:2] = 0
            pose = face.pose_values(v)
            for view, r in zip(views, renderers):
                img = Image.fromarray(r.render(pose))
                ImageDraw.Draw(img).text((4, 4), f"{label} [{view}]", fill=(255, 255, 0))
                tiles.append(img)
    finally:
        for r in renderers:
            r.release()
    rows = (len(tiles) + cols - 1) // cols
    board = Image.new("RGB", (cols * size, rows * size), (30, 30, 30))
    for i, tile in enumerate(tiles):
        board.paste(tile, ((i % cols) * size, (i // cols) * size))
    return board


def compare_sheet(names, looks, size: int, crop: str, view: str) -> Image.Image:
    """One row per deformer, the same looks in the same columns, one view."""
    rows = []
    for name in names:
        face = FaceModel.default().with_deformer(name)
        row = sheet(face, [(f"{name}: {label}", v) for label, v in looks], size, crop, views=(view,), cols=len(looks))
        rows.append(row)
    board = Image.new("RGB", (rows[0].width, sum(r.height for r in rows)), (30, 30, 30))
    for i, row in enumerate(rows):
        board.paste(row, (0, i * rows[0].height))
    return board


GROUP_CROP = {"visemes": "mouth", "chinese": "mouth", "expressions": "face", "extras": "face"}


def photo_head():
    """The generic head calibrated to the astronaut's photo, and the texture it wears."""
    from skimage import data

    from mpeg4fa.tracking.photo import fdp_from_photo, textured_head

    return textured_head(fdp_from_photo(data.astronaut(), where="astronaut"))


def docs(out: Path, size: int) -> list[Path]:
    """Every sheet of the docs, as JPEG under ``out``."""
    out.mkdir(parents=True, exist_ok=True)
    written = []
    generic = FaceModel.default()
    photo, texture = photo_head()
    for head, face, tex in (("generic", generic, None), ("photo", photo, texture)):
        for group, crop in GROUP_CROP.items():
            board = sheet(face, poses(face, group), size, crop, texture=tex)
            written.append(out / f"looks-{group}-{head}.jpg")
            board.save(written[-1], quality=85)
    for group, crop in (("visemes", "mouth"), ("expressions", "face")):
        board = compare_sheet(FaceModel.DEFORMERS, poses(generic, group), size, crop, "front")
        written.append(out / f"deformers-{group}-front-{crop}.jpg")
        board.save(written[-1], quality=85)
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--deformer", default="fap", choices=FaceModel.DEFORMERS)
    parser.add_argument("--size", type=int, default=256)
    parser.add_argument("--crop", default="face", choices=list(CROPS))
    parser.add_argument("--only", choices=["visemes", "chinese", "expressions", "extras"])
    parser.add_argument("--out", type=Path, default=Path("out/contact"))
    parser.add_argument("--compare", action="store_true", help="every deformer side by side (one row each)")
    parser.add_argument("--view", default="front", choices=["front", "three-quarter"], help="view for --compare")
    parser.add_argument("--docs", action="store_true", help="write the docs' sheets (JPEG) into --out "
                        "(default docs/pictures)")
    args = parser.parse_args(argv)
    if args.docs:
        out = args.out if args.out != Path("out/contact") else Path("docs/pictures")
        for path in docs(out, args.size):
            print(path)
        return 0
    if args.compare:
        args.out.mkdir(parents=True, exist_ok=True)
        for group in [args.only] if args.only else ["visemes", "expressions"]:
            board = compare_sheet(FaceModel.DEFORMERS, poses(FaceModel.default(), group), args.size, args.crop,
                                  args.view)
            path = args.out / f"compare-{group}-{args.view}-{args.crop}.png"
            board.save(path)
            print(path)
        return 0
    face = FaceModel.default().with_deformer(args.deformer)
    args.out.mkdir(parents=True, exist_ok=True)
    groups = [args.only] if args.only else ["visemes", "chinese", "expressions", "extras"]
    for group in groups:
        board = sheet(face, poses(face, group), args.size, args.crop)
        path = args.out / f"{group}-{args.deformer}-{args.crop}.png"
        board.save(path)
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())
