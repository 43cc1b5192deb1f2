"""Why each skin FAP alone at its full default I range folds or strains (issue 29 item 3), measured.

Run on demand (not a test):
    .venv/bin/python tools/crease_range_why.py [--deformer fap] [--json tools/crease_check.json] [--unlimited]

Per pose of :func:`mpeg4fa.face.creases.full_range_poses` on the generic head: the crease measure
(folded triangles, fold lines, worst strain / floor), which criterion fails (``folded`` when any
triangle or sheet turns over, else ``ratio`` when the strain exceeds twice its floor), how far the
FAP drives its own feature point (mm), and the first other skin feature point in its way (within
:data:`PATH_MM` of its straight path at rest) with the distance along the path; ``through`` is true
when the point moves further than that: it is driven through the neighbour (raise_b_midlip 2.3 up
through the upper lip), which no smooth skin can follow without folding. The face eases each FAP into its reach
(:mod:`mpeg4fa.face.reach`) past ordinary use; ``--unlimited`` measures the face without that limiter, and
``limited`` says per pose whether the limiter acts on it.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.face import creases, quality, reach  # noqa: E402
from mpeg4fa.face.model import FaceModel  # noqa: E402
from mpeg4fa.spec import FAPS  # noqa: E402

PATH_MM = 8.0
"""A feature point within this of the moving point's straight path (at rest) lies in its way."""


def classify(face: FaceModel) -> list[dict]:
    """One row per full-range pose (see the module docstring)."""
    mesh = face.mesh
    graph = quality.skin_graph(mesh)
    skin = mesh.part("skin")
    on_skin = np.array([skin.start <= v < skin.stop for v in mesh.fp_vertex])
    rest = mesh.feature_points()
    rows = []
    table = reach.load_reach()
    for name, values in creases.full_range_poses().items():
        fap = int(name.split()[1])
        limited = bool(face.saturates and table.limited()[0 if values[fap - 1] > 0 else 1, fap - 1])
        m = creases.measure_pose(face, values, graph)
        label = FAPS[fap - 1].feature_point[0]
        i = mesh.fp_index(label)
        step = face.pose_values(values).feature_points[i] - rest[i]
        moved = float(np.linalg.norm(step))
        ahead = (rest - rest[i]) @ (step / max(moved, 1e-12))  # how far along the point's path each point lies
        aside = np.linalg.norm(rest - rest[i] - ahead[:, None] * step / max(moved, 1e-12), axis=1)
        ahead[~on_skin | (mesh.fp_vertex == mesh.fp_vertex[i]) | (ahead <= 0) | (aside > PATH_MM)] = np.inf
        j = int(np.argmin(ahead))
        rows.append({"pose": name, "fap": fap, "name": FAPS[fap - 1].name, "point": label, "limited": limited,
                     "folded": m.folded, "fold_lines": m.flipped, "ratio": round(float(m.ratio), 2),
                     "fails": None if m.ok() else ("folded" if m.folded or m.flipped else "ratio"),
                     "point_moved_mm": round(moved, 1),
                     "ahead": mesh.fp_labels[j] if np.isfinite(ahead[j]) else None,
                     "ahead_mm": round(float(ahead[j]), 1) if np.isfinite(ahead[j]) else None,
                     "through": bool(np.isfinite(ahead[j]) and moved > ahead[j])})
    return rows


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--deformer", default="fap")
    parser.add_argument("--json", type=Path)
    parser.add_argument("--unlimited", action="store_true", help="without the reach limiter")
    args = parser.parse_args()
    face = FaceModel.default(auto_install=False)
    if args.deformer != "fap":
        face = face.with_deformer(args.deformer)
    if args.unlimited:
        face = face.unlimited()
    rows = classify(face)
    print(f"{'pose':22s} {'fails':7s} {'folded':>6s} {'lines':>5s} {'ratio':>6s} {'moved':>6s}  in its way")
    for r in rows:
        print(f"{r['pose']:22s} {str(r['fails']):7s} {r['folded']:6d} {r['fold_lines']:5d} {r['ratio']:6.2f} "
              f"{r['point_moved_mm']:6.1f}  {r['ahead']} at {r['ahead_mm']} mm{' (through)' if r['through'] else ''}")
    fails = [r for r in rows if r["fails"]]
    summary = {"deformer": args.deformer, "limiter": face.saturates, "poses": len(rows),
               "limited": sum(r["limited"] for r in rows), "passing": len(rows) - len(fails),
               "folded": sum(r["fails"] == "folded" for r in rows), "ratio_only": sum(r["fails"] == "ratio" for r in rows),
               "through_a_neighbour": sum(r["through"] for r in fails),
               "failing_unlimited": [r["pose"] for r in fails if not r["limited"]],
               "failing_limited": [r["pose"] for r in fails if r["limited"]]}
    print(summary)
    if args.json:
        args.json.write_text(json.dumps({"summary": summary, "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
