"""``mpeg4fa fdp``: one photo of a face -> an FDP (its feature points in 3D and the photo as its texture)."""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ..atomic import atomic_outputs
from ..face.calibrate import METHODS
from .errors import located
from .options import Commands
from .paths import refuse_overlaps


def register(commands: Commands) -> None:
    p = commands.add_parser(
        "fdp", help="make an FDP (feature points + texture) from a photo of a face",
        description="Find the face in a photo (MediaPipe Face Mesh: 478 landmarks, offline; the 'photo' extra), "
                    "map its landmarks to the MPEG-4 feature points a photo shows (59 of 84, table "
                    "spec/landmark_points.csv; tongue, teeth, ears and skull come from the receiver's head), take "
                    "their depth from the landmark model, turn them upright into the generic head's frame (mm), and "
                    "write the FDP with the photo as its texture (each point's texture coordinate into it). An FDP "
                    "is the neutral face: a smile or open lips in the photo are closed and levelled in the points "
                    "(the photo's lips painted onto them), said in one line each; a neutral face, mouth closed, "
                    "gives the truest head. 'mpeg4fa play --fdp' then shows that face, wearing the photo. Several "
                    "faces: the largest, said in a warning.",
        epilog="examples:\n  mpeg4fa fdp me.jpg -o me.fdp --preview check.png\n"
               "  mpeg4fa fdp me.jpg -o me.json --deformer rbf      # JSON FDP; preview calibrated with RBF\n"
               "  mpeg4fa play talk.fba --fdp me.fdp -o talk.mp4",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("photo", type=Path, help="a photo of a face seen from the front (JPEG, PNG...)")
    p.add_argument("-o", "--output", type=Path, required=True,
                   help="the FDP to write: binary (.fdp), or JSON when the name ends in .json")
    p.add_argument("--side", type=Path, metavar="SIDE_PHOTO",
                   help="a second photo of the face turned 20 to 60 degrees (the landmark model finds no face in a "
                        "full profile): the points on the side it shows become the mean of both photos' estimates")
    p.add_argument("--points", type=Path, metavar="JSON",
                   help='your own pixel positions of some points on the photo ({"3.5": [246, 102], ...}): they win '
                        "over the found ones")
    p.add_argument("--preview", type=Path,
                   help="also write a PNG: the photo with the found points, and the calibrated textured head "
                        "front and three-quarter")
    p.add_argument("--deformer", choices=METHODS, default="dffd",
                   help="calibration warp for the preview and the check: Dirichlet FFD (default), RBF or elastic "
                        "(the FDP itself holds points; a receiver calibrates with its own)")
    p.add_argument("--no-texture", action="store_true", help="leave the photo out of the FDP (points only)")
    p.set_defaults(run=run_fdp)


def photo_points_file(path: Path) -> dict[str, tuple[float, float]]:
    """A JSON of photo pixels {label: [x, y]} (the one points reader, located errors); mesh points refused."""
    from ..fdp import FdpError
    from ..fdp.build import read_points_json

    points = read_points_json(path)
    for label, value in points.items():
        if not (isinstance(value, tuple) and len(value) == 2):
            raise FdpError.no_place(str(path), f"point {label} is not photo pixels [x, y]",
                                    hint='a JSON object like {"3.5": [246, 102], ...}')
    return points  # type: ignore[return-value]


def run_fdp(args: argparse.Namespace) -> int:
    from PIL import Image

    from ..fdp import save_fdp
    from ..tracking.photo import fdp_from_photo, preview

    refuse_overlaps({"photo": args.photo, "--side": args.side, "--points": args.points},
                    {"-o": args.output, "--preview": args.preview})
    given = photo_points_file(args.points) if args.points is not None else None
    started = time.perf_counter()
    with located(str(args.points or args.photo)):
        made = fdp_from_photo(args.photo, side=args.side, points=given, texture=not args.no_texture)
    found = time.perf_counter()
    picture = preview(made, args.deformer) if args.preview is not None else None
    with atomic_outputs(args.output, args.preview) as (out, check):
        save_fdp(made.fdp, out)
        if check is not None:
            Image.fromarray(picture).save(check, format="PNG")
    width, height = made.image.shape[1], made.image.shape[0]
    texture = "" if args.no_texture else f", texture {made.fdp.textures[0].name} ({width}x{height})"
    print(f"{args.photo}: face found ({made.landmarks.faces} in the photo), {len(made.fdp.labels)} feature points "
          f"in {found - started:.1f} s; {made.scale:.3f} mm per pixel"
          + (f"; {made.side[0]} shows the face's {made.side[1]} side: {made.side[2]} points from both photos"
             if made.side else "")
          + (f"; {len(given)} points from {args.points}" if given else ""), file=sys.stderr)
    say_notes(made, str(args.photo))
    print(f"wrote {args.output} ({len(made.fdp.labels)} feature points{texture})"
          + (f", {args.preview} (preview, calibrated with {args.deformer})" if args.preview else ""))
    return 0


def say_notes(made, where: str) -> None:
    """What of a photo's face the FDP made neutral (:attr:`mpeg4fa.tracking.PhotoFdp.notes`), a line each."""
    for note in made.notes:
        print(f"{where}: {note}", file=sys.stderr)


def photo_face(args: argparse.Namespace, method: str = "dffd"):
    """``--photo`` of play, snapshot and say: (the generic head calibrated to the face found in the photo,
    with the command's skull and deformer; the skin texture a receiver bakes from that FDP, or None
    when ``--texture`` or ``--no-fdp-texture`` says otherwise)."""
    from ..face.assemble import assemble_face
    from ..render.fdp_texture import bake_fdp_texture
    from ..tracking.photo import fdp_from_photo
    from .errors import UsageError

    for option in ("fdp", "face_mesh"):
        if getattr(args, option, None) is not None:
            name = "--" + option.replace("_", "-")
            raise UsageError(f"--photo and {name} both describe the face", hint="give one of them")
    deformer, blocks = getattr(args, "deformer", None), getattr(args, "blocks", None)
    if blocks is not None and deformer != "blocks":
        raise UsageError(f"--blocks goes with --deformer blocks, not {deformer}")
    made = fdp_from_photo(args.photo)
    face = assemble_face(fdp=made.fdp, method=getattr(args, "method", method),
                         skull=getattr(args, "skull", "triangles"), deformer=deformer, blocks=blocks)
    texture = None
    if getattr(args, "texture", None) is None and not getattr(args, "no_fdp_texture", False):
        texture = bake_fdp_texture(face.mesh, made.fdp, source=str(args.photo)).baked.image
    print(f"face: {args.photo} ({len(made.fdp.labels)} feature points found; the head calibrated to them"
          f"{', wearing the photo' if texture is not None else ''})", file=sys.stderr)
    say_notes(made, "face")
    return face, texture
