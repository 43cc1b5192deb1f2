#!/usr/bin/env python3
"""Measure the face's reach (issue 29 item 3) into ``mpeg4fa/face/data/reach.csv``.

Per skin FAP (:func:`mpeg4fa.face.creases.full_range_faps`) and sign, on the generic head without its limiter
(:meth:`FaceModel.unlimited`), under the feature-point and the ARKit deformers: the largest value that passes
the crease criterion (:meth:`mpeg4fa.face.creases.Crease.ok`: no folded triangle, no fold line, strain within
twice its floor). The full default I range is scanned in :data:`SCAN` steps (so no fold hides below the
answer at that spacing), then the step where it first fails is bisected to :data:`TOLERANCE` of the range.
The table is the smaller of the two deformers' reach (one head, one reach: the limiter sits before the
deformer, so a stream shows the same values whichever poses it; the pages' facerig.js ports the feature-point
deformer, and the ARKit one differs only where its sculpted units are shallower).

The knee is the largest value ordinary use asks for (:func:`ordinary_use`); :func:`mpeg4fa.face.reach.limits`
turns reach and knee into the limiter's row.

    .venv/bin/python tools/measure_reach.py [--out mpeg4fa/face/data/reach.csv] [--only 3,5]
"""
from __future__ import annotations

import argparse
import csv
import importlib.util
import io
import re
import subprocess
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mpeg4fa.face import creases, reach  # noqa: E402
from mpeg4fa.face.model import FaceModel  # noqa: E402
from mpeg4fa.face.quality import skin_graph, used_magnitudes  # noqa: E402
from mpeg4fa.spec import FAPS, N_FAPS  # noqa: E402

SCAN = 16
"""Steps the full range is scanned in before bisecting."""
TOLERANCE = 0.002
"""Bisection stops within this share of the full range (and never finer than 1 unit)."""
DEFORMERS = ("fap", "arkit")


def _tool(name: str):
    spec = importlib.util.spec_from_file_location(name, ROOT / "tools" / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def ordinary_use() -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(2, 68) largest positive / negative magnitude ordinary use asks of each FAP, and each source's own:
    real streams and profiles (``data/fap_magnitudes.csv``), the visemes of both sets, the six expressions
    with both FAP 2 slots at intensity 63, the named brow poses (x2 up and down, 400, squeeze x2), blinks
    to full close, and the tracker's training and held-out streams (tools/train_tracker.py). (The knee is
    at least :data:`mpeg4fa.face.reach.EXACT_UP_TO` besides: the conformance suite's exact range.)"""
    from mpeg4fa.spec.profiles import EXPRESSION_PROFILES, VISEME_PROFILES, expression_blend

    sources: dict[str, list[np.ndarray]] = {}
    used = np.zeros((2, N_FAPS))
    for fap, (pos, neg) in used_magnitudes().items():
        used[:, fap - 1] = pos, neg
    sources["streams and profiles"] = [used[0], -used[1]]
    sources["visemes"] = [p for profiles in VISEME_PROFILES.values() for p in profiles.values()]
    sources["expressions 63 x 2"] = [expression_blend(e, 63, e, 63) for e in EXPRESSION_PROFILES if e != "neutral"]
    poses = creases.crease_poses()
    sources["brows named"] = [poses[k] for k in ("brows x2 up", "brows x2 down", "brows 400", "squeeze x2")]
    loop = _tool("track_loop")
    blink = np.zeros(N_FAPS)
    blink[18:20] = loop.BLINK_PEAK
    sources["blinks"] = [blink]
    train = _tool("train_tracker")
    streams = sorted({(seed, swept) for _, seed, _, swept in train.stream_plan()})
    sources["tracker streams"] = [train.training_values(seed, 20.0, swept) for seed, swept in streams]
    per = {}
    for name, rows in sources.items():
        v = np.vstack([np.atleast_2d(r) for r in rows])[:, :N_FAPS]
        per[name] = np.stack([np.clip(v, 0, None).max(axis=0), np.clip(-v, 0, None).max(axis=0)])
    return np.max(np.stack(list(per.values())), axis=0), per


def _crease(face: FaceModel, fap: int, value: float, graph) -> creases.Crease:
    v = np.zeros(N_FAPS)
    v[fap - 1] = value
    return creases.measure_pose(face, v, graph)


def _unfolded(m: creases.Crease) -> bool:
    return m.folded == 0 and m.flipped == 0


CRITERIA = {"ok": creases.Crease.ok, "fold": _unfolded}
"""``ok``: the whole crease criterion; ``fold``: no folded triangle and no fold line (strain aside)."""


def reach_of(face: FaceModel, fap: int, sign: int, graph) -> dict[str, float]:
    """Per criterion, the largest magnitude of ``fap`` (this sign) that passes; ``inf`` when the whole full
    range does."""
    top = creases.full_range_value(fap)
    found = {}
    first_fail = {}
    for k in range(1, SCAN + 1):
        m = _crease(face, fap, sign * top * k / SCAN, graph)
        for name, rule in CRITERIA.items():
            if name not in first_fail and not rule(m):
                first_fail[name] = k
        if len(first_fail) == len(CRITERIA):
            break
    for name, rule in CRITERIA.items():
        if name not in first_fail:
            found[name] = np.inf
            continue
        lo, hi = top * (first_fail[name] - 1) / SCAN, top * first_fail[name] / SCAN
        while hi - lo > max(1.0, TOLERANCE * top):
            mid = 0.5 * (lo + hi)
            lo, hi = (mid, hi) if rule(_crease(face, fap, sign * mid, graph)) else (lo, mid)
        found[name] = float(np.floor(lo))
    return found


def _fmt(x: float) -> str:
    return "" if not np.isfinite(x) else f"{x:g}"


def measure(faps: list[int]) -> list[dict]:
    base = FaceModel.default(auto_install=False)
    graph = skin_graph(base.mesh)
    faces = {d: (base if d == "fap" else base.with_deformer(d)).unlimited() for d in DEFORMERS}
    used, _ = ordinary_use()
    rows = []
    for fap in faps:
        row = {"fap": fap, "name": FAPS[fap - 1].name, "full_range": _fmt(creases.full_range_value(fap))}
        for side, sign in (("pos", 1), ("neg", -1)):
            if sign < 0 and FAPS[fap - 1].unidirectional:
                found = {d: {c: np.inf for c in CRITERIA} for d in DEFORMERS}
            else:
                found = {d: reach_of(face, fap, sign, graph) for d, face in faces.items()}
            ok, fold = (min(found[d][c] for d in DEFORMERS) for c in CRITERIA)
            knee, limit = reach.limits(ok, fold, used[0 if sign > 0 else 1, fap - 1])
            row.update({f"used_{side}": _fmt(used[0 if sign > 0 else 1, fap - 1]),
                        **{f"{c}_{d}_{side}": _fmt(found[d][c]) for c in CRITERIA for d in DEFORMERS},
                        f"knee_{side}": _fmt(knee), f"limit_{side}": _fmt(limit)})
        rows.append(row)
        print(" ".join(f"{row[k]:>9}" if k != "name" else f"{row[k]:22}" for k in row), flush=True)
    return rows


def relimit(path: Path) -> list[dict]:
    """The rows of ``path`` with ``used``, ``knee`` and ``limit`` recomputed (ordinary use or the rule changed)."""
    with path.open(encoding="utf-8") as f:
        rows = list(csv.DictReader(line for line in f if not line.startswith("#")))
    used, _ = ordinary_use()
    num = {"": np.inf}
    for row in rows:
        fap = int(row["fap"])
        for side, k in (("pos", 0), ("neg", 1)):
            ok, fold = (min(float(num.get(row[f"{c}_{d}_{side}"], row[f"{c}_{d}_{side}"])) for d in DEFORMERS)
                        for c in CRITERIA)
            knee, limit = reach.limits(ok, fold, used[k, fap - 1])
            row.update({f"used_{side}": _fmt(used[k, fap - 1]), f"knee_{side}": _fmt(knee),
                        f"limit_{side}": _fmt(limit)})
    return rows


HEADER = """# The face's reach (mpeg4fa.face.reach), written by tools/measure_reach.py at {commit}: per skin FAP and
# sign, the largest value (FAPU units) that passes the crease criterion (creases.Crease.ok: no folded triangle, no fold
# line, strain within 2 x its floor) on the generic head without its limiter, FAP alone, full default I range
# scanned in {scan} steps then bisected to {tol:g} of it; fap_* and arkit_* per deformer (empty: the whole range
# passes); ok_*: the whole criterion, fold_*: no fold (strain aside). used_*: the largest magnitude ordinary use
# asks (streams, profiles, visemes, expressions 63 x 2, brows x2, blinks, the tracker's training streams).
# knee = max(used, {exact:g}: exact for conformance); limit = min over deformers of ok (fold where ok x (1 - {margin:g})
# <= knee) x (1 - {margin:g}); empty where nothing is limited (the range passes, or folds start within the knee).
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=ROOT / "mpeg4fa" / "face" / "data" / "reach.csv")
    parser.add_argument("--only", help="comma-separated FAPs (prints, writes nothing)")
    parser.add_argument("--relimit", action="store_true",
                        help="keep the measured reaches of --out, recompute ordinary use, knee and limit")
    args = parser.parse_args(argv)
    faps = [int(f) for f in args.only.split(",")] if args.only else creases.full_range_faps()
    rows = relimit(args.out) if args.relimit else measure(faps)
    if args.only:
        return 0
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip() or "unknown"
    if args.relimit:  # the reaches stay those measured at the commit the file names
        commit = re.search(r" at (\S+):", args.out.read_text(encoding="utf-8")).group(1)
    out = io.StringIO()
    out.write(HEADER.format(commit=commit, scan=SCAN, tol=TOLERANCE, margin=reach.MARGIN, exact=reach.EXACT_UP_TO))
    writer = csv.DictWriter(out, fieldnames=list(rows[0]), lineterminator="\n")
    writer.writeheader()
    writer.writerows(rows)
    args.out.write_text(out.getvalue(), encoding="utf-8")
    folds_in_use = [(int(r["fap"]), s) for r in rows for s in ("pos", "neg")  # a reach found, yet not limited
                    if r[f"limit_{s}"] == "" and any(r[f"fold_{d}_{s}"] != "" for d in DEFORMERS)]
    print(f"wrote {args.out}; limited {sum(r[f'limit_{s}'] != '' for r in rows for s in ('pos', 'neg'))} "
          f"FAP-signs; folding at or below ordinary use (left): {folds_in_use}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
