#!/usr/bin/env python3
"""Pictures of the NURBS skull (:mod:`mpeg4fa.face.nurbs`) next to the triangle head, for looking at.

Writes under ``--out`` (default /tmp/nurbs): ``views.png`` (triangle head top row, NURBS head
below; front, side, back, three-quarter, top), ``seam.png`` (close-ups of the seam with the
triangle edges drawn, NURBS triangles in blue and moving triangles in orange), ``posed.png``
(the NURBS head with a few FAP poses and head turns), ``texture.png`` (both heads wearing a
checker texture: the tessellation's texture coordinates) and the silhouette differences printed.

    .venv/bin/python tools/nurbs_sheet.py [--size 384] [--out /tmp/nurbs] [--spacing 6]
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.face import FaceModel  # noqa: E402
from mpeg4fa.face.nurbs import compare_silhouettes, nurbs_head  # noqa: E402
from mpeg4fa.render.camera import frame_points  # noqa: E402
from mpeg4fa.render.renderer import Renderer  # noqa: E402

VIEWS = {"front": (0.0, 0.0), "side": (90.0, 0.0), "back": (180.0, 0.0), "three-quarter": (30.0, 5.0),
         "top": (0.0, 80.0)}
POSES = {"neutral": {}, "jaw 3=600": {3: 600}, "brows up 31-36=300": {k: 300 for k in range(31, 37)},
         "smile 53/54=300": {53: 300, 54: 300}, "head yaw 49=0.3 rad": {49: 30000},
         "head pitch 48=-0.3 rad": {48: -30000}}


def _label(img: np.ndarray, text: str) -> Image.Image:
    im = Image.fromarray(img)
    ImageDraw.Draw(im).text((6, 6), text, fill=(0, 0, 0))
    return im


def _grid(rows: list[list[Image.Image]]) -> Image.Image:
    w, h = rows[0][0].size
    out = Image.new("RGB", (w * max(len(r) for r in rows), h * len(rows)), (255, 255, 255))
    for j, row in enumerate(rows):
        for i, im in enumerate(row):
            out.paste(im, (i * w, j * h))
    return out


def _head_points(face: FaceModel) -> np.ndarray:
    skin = face.mesh.vertices[face.mesh.part("skin")]
    return skin[skin[:, 1] > face.mesh.fp("2.1")[1] - 20.0]


def _edges(img: np.ndarray, face: FaceModel, camera, n_old_skin: int, size: int, new_from: int, new_to: int):
    """Draw the skin's triangle edges facing the camera: NURBS ones blue, the others orange."""
    im = Image.fromarray(img)
    draw = ImageDraw.Draw(im)
    v = face.mesh.vertices
    tri = face.mesh.triangles["skin"]
    pix = camera.project(v, size, size)
    n = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    facing = np.einsum("td,td->t", n, camera.position - v[tri].mean(axis=1)) > 0
    for t in tri[facing]:
        nurbs = ((t >= new_from) & (t < new_to)).any()
        colour = (40, 90, 220) if nurbs else (230, 120, 30)
        p = pix[t][:, :2]
        draw.line([tuple(p[0]), tuple(p[1]), tuple(p[2]), tuple(p[0])], fill=colour, width=1)
    return im


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=384)
    ap.add_argument("--out", type=Path, default=Path("/tmp/nurbs"))
    ap.add_argument("--spacing", type=float, default=6.0)
    args = ap.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    tri_face = FaceModel.default()
    t0 = time.perf_counter()
    mesh = nurbs_head(tri_face.mesh, tri_face.rig, spacing_mm=args.spacing)
    print(f"NURBS head: {mesh.n_vertices} vertices ({time.perf_counter() - t0:.2f} s)")
    nurbs_face = FaceModel(mesh)
    size = args.size
    pts = _head_points(tri_face)
    rows = []
    for name, face in (("triangles", tri_face), ("NURBS", nurbs_face)):
        row = []
        with Renderer(face, width=size, height=size, samples=4) as r:
            for view, yp in VIEWS.items():
                r.set_camera(frame_points(pts, size, size, view=yp, orthographic=True, margin=0.08))
                row.append(_label(r.render(face.neutral()), f"{name} {view}"))
        rows.append(row)
    _grid(rows).save(args.out / "views.png")
    # seam close-ups with edges
    n_skin_old = tri_face.mesh.part_ranges["skin"][1]
    rows = []
    for name, face in (("triangles", tri_face), ("NURBS", nurbs_face)):
        row = []
        new_from, new_to = 0, 0
        if face is nurbs_face:
            new_from, new_to = _first_new(face.mesh, tri_face.mesh), face.mesh.part_ranges["skin"][1]
        with Renderer(face, width=size, height=size, samples=4) as r:
            for view, labels in (((60.0, 10.0), ("4.5", "10.1", "11.3", "11.1")),
                                 ((0.0, 20.0), ("4.1", "4.2", "11.1", "4.5", "4.6")),
                                 ((120.0, 0.0), ("10.3", "10.1", "11.6", "10.5"))):
                cam = frame_points(np.array([face.mesh.fp(lb) for lb in labels]), size, size, view=view,
                                   margin=0.6)
                r.set_camera(cam)
                img = r.render(face.neutral())
                row.append(_label(np.asarray(_edges(img, face, cam, n_skin_old, size, new_from, new_to)),
                                  f"{name} seam {view}"))
                row.append(_label(img, f"{name} shaded"))
        rows.append(row)
    _grid(rows).save(args.out / "seam.png")
    # poses
    row = []
    with Renderer(nurbs_face, width=size, height=size, samples=4) as r:
        r.set_camera(frame_points(pts, size, size, view=(30.0, 5.0), margin=0.15))
        for name, faps in POSES.items():
            row.append(_label(r.render(nurbs_face.deform(faps)), f"NURBS {name}"))
    _grid([row]).save(args.out / "posed.png")
    # a checker texture shows whether the texture coordinates of the tessellation are continuous
    n = 1024
    y, x = np.mgrid[:n, :n]
    check = (((x // 32) + (y // 32)) % 2).astype(np.uint8)
    texture = np.stack([40 + 200 * check, 80 + 100 * check, 255 - 200 * check], axis=-1).astype(np.uint8)
    rows = []
    for name, face in (("triangles", tri_face), ("NURBS", nurbs_face)):
        row = []
        with Renderer(face, width=size, height=size, samples=4, texture=texture) as r:
            for view in ((0.0, 0.0), (90.0, 10.0), (180.0, 20.0), (0.0, 80.0)):
                r.set_camera(frame_points(pts, size, size, view=view, orthographic=True, margin=0.08))
                row.append(_label(r.render(face.neutral()), f"{name} {view}"))
        rows.append(row)
    _grid(rows).save(args.out / "texture.png")
    for d in compare_silhouettes(tri_face.mesh, mesh):
        print(f"silhouette {d.view:13s} area {100 * d.area_fraction:.3f} %  max {d.max_mm:.2f} mm")
    print(f"wrote {args.out}/views.png, seam.png, posed.png, texture.png")
    return 0


def _first_new(mesh, old) -> int:
    """First NURBS vertex: the kept skin vertices come first (unchanged), the tessellation after them."""
    skin_old = old.vertices[old.part("skin")]
    skin_new = mesh.vertices[mesh.part("skin")]
    same = np.all(np.isin(skin_new.view([("", skin_new.dtype)] * 3), skin_old.view([("", skin_old.dtype)] * 3)),
                  axis=-1).ravel()
    return int(np.flatnonzero(~same)[0])


if __name__ == "__main__":
    raise SystemExit(main())
