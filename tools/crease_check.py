#!/usr/bin/env python3
"""Creases and folds at the extremes (issue 29 item 3): per pose, folded triangles and strain / floor.

Poses the generic head (and the conformance suite's adult head calibrated to it) through the
poses people notice creases in: the brows at twice their usual extreme (31-36 at 400), the cheeks
41/42 at 600, every skin FAP alone at its full default I range (``i_max x quant_step`` of
``spec/faps.csv``, each sign), and head turns to 40 degrees with the jaw open. Per pose and
deformer it prints the folded skin triangles (normal turned > 90 degrees from rest, or against a
neighbour it agreed with at rest), the worst edge strain, the geometric floor
(:func:`mpeg4fa.face.quality.strain_floor`) and their ratio; ``--pictures DIR`` renders the named
poses front, three-quarter and from below (PNG) for looking at.

The face eases each FAP into its reach (:mod:`mpeg4fa.face.reach`); ``--unlimited`` measures it without.

    .venv/bin/python tools/crease_check.py [--deformer fap --deformer arkit ...] [--head generic|adult]
                                           [--only named|range] [--json out.json] [--pictures out/creases]
                                           [--unlimited]
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.face import FaceModel  # noqa: E402
from mpeg4fa.face.creases import crease_poses, full_range_poses, measure_pose  # noqa: E402
from mpeg4fa.face.quality import skin_graph  # noqa: E402

VIEWS = {"front": "front", "three-quarter": "three-quarter", "below": (35.0, -40.0), "below-front": (0.0, -55.0)}


def face_for(head: str) -> FaceModel:
    face = FaceModel.default()
    if head == "generic":
        return face
    from mpeg4fa.conformance.manifest import default_root
    from mpeg4fa.fdp import load_fdp

    return face.calibrate(load_fdp(default_root() / "faces" / f"{head}.fdp"), method="elastic")


def pictures(face: FaceModel, poses: dict[str, np.ndarray], out: Path, size: int = 384) -> list[Path]:
    from PIL import Image, ImageDraw

    from mpeg4fa.render.camera import frame_points
    from mpeg4fa.render.renderer import Renderer

    out.mkdir(parents=True, exist_ok=True)
    renderers = {name: Renderer(face, width=size, height=size, samples=4,
                                camera=frame_points(face.mesh.feature_points(), size, size, view=view, margin=0.35))
                 for name, view in VIEWS.items()}
    written = []
    try:
        for label, values in poses.items():
            pose = face.pose_values(values)
            tiles = []
            for name, r in renderers.items():
                img = Image.fromarray(r.render(pose))
                ImageDraw.Draw(img).text((4, 4), f"{label} [{name}]", fill=(255, 255, 0))
                tiles.append(img)
            board = Image.new("RGB", (size * len(tiles), size))
            for i, t in enumerate(tiles):
                board.paste(t, (i * size, 0))
            tag = "-unlimited" if not face.saturates else ""
            written.append(out / f"{face.deformer}{tag}-{label.replace(' ', '_').replace('/', '-')}.png")
            board.save(written[-1])
    finally:
        for r in renderers.values():
            r.release()
    return written


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--deformer", action="append", choices=FaceModel.DEFORMERS,
                        help="deformer(s) to check (default: all)")
    parser.add_argument("--head", default="generic", choices=["generic", "adult", "child"])
    parser.add_argument("--only", choices=["named", "range"])
    parser.add_argument("--json", type=Path)
    parser.add_argument("--pictures", type=Path, help="render the named poses into this folder")
    parser.add_argument("--unlimited", action="store_true", help="without the reach limiter")
    parser.add_argument("--poses", help="only these poses (comma-separated labels), e.g. for --pictures")
    args = parser.parse_args(argv)
    base = face_for(args.head)
    graph = skin_graph(base.mesh)
    named = crease_poses(base)
    cases = {}
    if args.only in (None, "named"):
        cases.update(named)
    if args.only in (None, "range"):
        cases.update(full_range_poses())
    if args.poses:
        wanted = [p.strip() for p in args.poses.split(",")]
        cases = {k: v for k, v in {**named, **full_range_poses()}.items() if k in wanted}
        named = cases
    rows = []
    print(f"{'deformer':9} {'pose':26} {'folded':>6} {'flipped':>7} {'strain':>7} {'floor':>7} {'ratio':>6}  worst near")
    for deformer in args.deformer or FaceModel.DEFORMERS:
        face = base if deformer == "fap" else base.with_deformer(deformer)
        face = face.unlimited() if args.unlimited else face
        for label, values in cases.items():
            m = measure_pose(face, values, graph)
            rows.append({"deformer": deformer, "pose": label, **m.as_dict()})
            flag = "" if m.ok() else "  <-"
            print(f"{deformer:9} {label:26} {m.folded:6d} {m.flipped:7d} {m.strain:7.3f} {m.floor:7.3f} "
                  f"{m.ratio:6.2f}  {m.near}{flag}")
        if args.pictures:
            for path in pictures(face, named, args.pictures):
                print(path)
    bad = [r for r in rows if not r["ok"]]
    print(f"{len(rows) - len(bad)}/{len(rows)} poses without folds and within {2:g} x the floor")
    if args.json:
        args.json.write_text(json.dumps({"head": args.head, "limiter": not args.unlimited, "rows": rows}, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
