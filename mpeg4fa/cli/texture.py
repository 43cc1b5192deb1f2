"""``mpeg4fa texture``: bake the skin's UV texture from a front photo (and a side photo)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ..atomic import atomic_outputs
from ..fdp.build import read_points_json
from ..render import RenderError
from . import options
from .errors import UsageError
from ..render.images import read_image
from .model import face_from_args, face_options
from .options import Commands
from .paths import refuse_overlaps


def register(commands: Commands) -> None:
    p = commands.add_parser(
        "texture", help="texture the head from a front photo (and a side photo) with annotated feature points",
        description="Align the head's bounding box to each photo through its annotated feature points, project "
                    "the skin orthographically, blend front and side colours by the surface normal "
                    "(k = |Nz| / (|Nx| + |Nz|)), and write the result as a UV texture image that "
                    "'mpeg4fa play --texture' (or any renderer using the head's UVs) can use. Points files are "
                    'JSON objects of feature point label -> [x, y] pixels (x right, y down), e.g. '
                    '{"3.5": [246, 102], "3.6": [203, 100], "9.3": [223, 126], "2.1": [224, 170]}.',
        epilog="examples:\n  mpeg4fa texture me-front.jpg -o skin.png --preview check.png   # points found in the photo\n"
               "  mpeg4fa texture me-front.jpg --points me-front.json --side me-left.jpg "
               "--side-points me-left.json --side-view left -o skin.png --preview check.png",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("front", type=Path, help="the front photo")
    p.add_argument("--points", type=Path,
                   help="JSON: the front photo's feature points (default: the face is found in the photo, "
                        "mpeg4fa.tracking; the 'photo' extra)")
    p.add_argument("--side", type=Path, help="a side photo (optional; without it: front-only mode)")
    p.add_argument("--side-points", type=Path, help="JSON: the side photo's feature points")
    p.add_argument("--side-view", choices=("left", "right"), default="left",
                   help="which side of the face the side photo shows (default left)")
    p.add_argument("--size", type=options.side, default=1024, help="texture size in pixels, 16 to 8192 (default 1024)")
    p.add_argument("-o", "--output", type=Path, required=True, help="the texture image (.png)")
    p.add_argument("--preview", type=Path, help="also render the textured head (front and three-quarter) here")
    face_options(p)
    p.set_defaults(run=run_texture)


def _points(path: Path) -> dict[str, tuple[float, float]]:
    points = read_points_json(path)  # the one points reader: labels, numbers, nesting, bytes checked and located
    for label, value in points.items():
        if not (isinstance(value, tuple) and len(value) == 2):
            raise RenderError(f"point {label} is not photo pixels [x, y]", where=str(path),
                              hint='a JSON object like {"3.5": [246, 102], ...}')
    return points  # type: ignore[return-value]


def _found(image: np.ndarray, path: Path, face) -> dict[str, tuple[float, float]]:
    """The feature points the landmark model finds on the photo, where an FDP from it has them on ``face``
    (:func:`mpeg4fa.tracking.photo_points`; one error naming the photo when there is no face)."""
    from ..tracking import find_landmarks, photo_points

    found, _, _ = photo_points(find_landmarks(image, str(path)), face.feature_points())
    print(f"{path}: face found, {len(found)} feature points", file=sys.stderr)
    return {label: (float(p[0]), float(p[1])) for label, p in found.items()}


def _photo_view(image: np.ndarray, points: dict, view: str, path: Path):
    """:class:`~mpeg4fa.render.texture.PhotoView` of the photo at ``path``: what it refuses names that file (a 1x1
    side photo was "photo: the photo is only 1x1 pixels", the front or the side)."""
    from ..render.texture import PhotoView

    try:
        return PhotoView(image, points, view)
    except RenderError as exc:
        if exc.where == "photo":
            exc.where = str(path)
        raise


def run_texture(args: argparse.Namespace) -> int:
    from PIL import Image

    from ..render import Renderer
    from ..render.texture import bake_texture

    if (args.side is None) != (args.side_points is None):
        raise UsageError("--side and --side-points go together", hint="give both, or neither for front-only")
    refuse_overlaps({"front photo": args.front, "--points": args.points, "--side": args.side,
                     "--side-points": args.side_points, "--fdp": args.fdp},
                    {"-o": args.output, "--preview": args.preview})
    face = face_from_args(args)
    image = read_image(args.front, "photo", turn=True)
    points = _points(args.points) if args.points is not None else _found(image, args.front, face)
    front = _photo_view(image, points, "front", args.front)
    side = (_photo_view(read_image(args.side, "photo", turn=True), _points(args.side_points), args.side_view, args.side)
            if args.side else None)
    baked = bake_texture(face.mesh, front, side, size=args.size)
    preview = None
    if args.preview is not None:
        images = []
        for view in ("front", "three-quarter"):
            with Renderer(face, width=384, height=384, samples=4, view=view, texture=baked.image) as r:
                images.append(r.render(face.neutral()))
        preview = np.concatenate(images, axis=1)
    try:  # the texture and its preview appear together, or neither
        with atomic_outputs(args.output, args.preview) as (out, check):
            Image.fromarray(baked.image).save(out)
            if check is not None:
                Image.fromarray(preview).save(check)
    except ValueError as exc:  # no image format for the name (an OS error names its file itself)
        raise RenderError(f"cannot write the image ({exc})", where=str(args.output),
                          hint="name it .png, .jpg, .bmp or .tif") from None
    for view, align in baked.alignments.items():
        print(f"{view} photo: {len(align.labels)} points, alignment residual {align.residual:.1f} px",
              file=sys.stderr)
    print(f"{args.output}: {args.size}x{args.size}, {baked.coverage[baked.skin].mean():.0%} of the skin seen "
          f"in a photo")
    if args.preview is not None:
        print(f"{args.preview}: preview")
    return 0
