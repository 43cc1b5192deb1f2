"""Why the tracker reads the inner lips (FAPs 4/5) at a fifth: how far the face moves them, and what the landmarks see.

    .venv/bin/python tools/lip_reach.py [--cache out/train_tracker/cache] [--out out/lip_reach.json]

Two measurements (issue 27, inner lips). ``reach``: the face engine's vertex motion per FAP, as a share of what the
FAP asks, in bands of distance from the face's midline, with the jaw open (FAP 3 = 300): FAP 5 alone moves a bump on the
inner lower lip, full near the midline and next to nothing past the mid-lip points (2.8/2.9), where the jaw moves the
whole lip. ``seen``: over tools/train_tracker.py's cached calm runs, the least-squares slope of the inner lip landmarks'
vertical motion (the tracker's inputs: head motion out, over ES0) on the sent FAPs' displacements (1: the landmark
moves as far as the FAP asks). Prints a table and writes JSON.
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BANDS = ((0, 3), (3, 8), (8, 13), (13, 18), (18, 24))
"""Distance from the midline (mm of the generic head, whose mouth is 49 mm wide)."""
ASKED = {"3": 100, "4": 300, "5": -300, "52": -300}
"""FAP: value added to the open jaw, for the reach."""
FITTED = (3, 4, 5, 51, 52)
LANDMARKS = {"13 (upper inner lip)": 13, "14 (lower inner lip)": 14, "0 (upper outer lip)": 0,
             "17 (lower outer lip)": 17}


def reach() -> dict[str, list[float]]:
    """Per FAP of :data:`ASKED`: the 90th percentile of vertical motion / asked over the mouth's front vertices (within
    15 mm of its centre's height) per band of :data:`BANDS`."""
    from mpeg4fa.face import FaceModel

    face = FaceModel.default()
    base = np.zeros(68)
    base[2] = 300
    posed = face.pose_values(base)
    still = posed.vertices
    labels = list(face.mesh.fp_labels)
    mouth = np.mean([posed.feature_points[labels.index(k)][1] for k in ("2.2", "2.3")])
    front = (still[:, 2] > still[:, 2].max() - 30.0) & (np.abs(still[:, 1] - mouth) < 15.0)
    out = {}
    for fap, value in ASKED.items():
        row = base.copy()
        row[int(fap) - 1] += value
        share = (face.pose_values(row).vertices - still)[:, 1] / (face.fapu.unit("MNS") * abs(value))
        out[fap] = []
        for lo, hi in BANDS:
            band = front & (np.abs(still[:, 0]) >= lo) & (np.abs(still[:, 0]) < hi)
            out[fap].append(round(float(np.percentile(np.abs(share[band]), 90)), 2) if band.any() else 0.0)
    return out


def seen(cache: Path) -> dict[str, dict[str, float]] | None:
    """Per landmark of :data:`LANDMARKS`: slope of its vertical motion on each of :data:`FITTED` (None without runs)."""
    import importlib.util

    from mpeg4fa.tracking import learned

    spec = importlib.util.spec_from_file_location("train_tracker_tool", ROOT / "tools" / "train_tracker.py")
    tool = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(tool)
    if not cache.is_dir():
        return None
    runs = [r for r in tool.runs(cache, 20.0, render=False) if not r["wide"]]
    if not runs:
        return None
    for run in runs:
        run["moved"], run["angles"], run["fapu"] = tool.inputs(run["landmarks"])
    moved, angles, values, fapus, which = tool._stack(runs)
    faps = np.array(FITTED)
    x = np.concatenate([np.concatenate([learned.displacements(values[which == i][:, faps - 1], faps, u)
                                        for i, u in enumerate(fapus)]), learned.angle_terms(angles)], axis=1)
    out = {}
    for name, k in LANDMARKS.items():
        slope = np.linalg.lstsq(x, moved[:, k, 1], rcond=None)[0]
        out[name] = {str(f): round(float(s), 2) for f, s in zip(FITTED, slope)}
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cache", type=Path, default=Path("out/train_tracker/cache"),
                        help="tools/train_tracker.py's cache of rendered runs (the calm ones are read)")
    parser.add_argument("--out", type=Path, default=Path("out/lip_reach.json"))
    args = parser.parse_args(argv)
    report = {"bands_mm": [list(b) for b in BANDS], "reach": reach(), "seen": seen(args.cache)}
    print("reach (share of the asked motion, 90th percentile, jaw open; by mm from the midline): "
          + " ".join(f"{lo}-{hi}" for lo, hi in BANDS))
    for fap, shares in report["reach"].items():
        print(f"  FAP {fap:>3}: " + " ".join(f"{s:5.2f}" for s in shares))
    if report["seen"] is None:
        print(f"seen: no cached runs in {args.cache} (run tools/train_tracker.py first)")
    else:
        print("seen (landmark's vertical motion per asked motion, calm training runs): FAP "
              + " ".join(map(str, FITTED)))
        for name, slopes in report["seen"].items():
            print(f"  {name:22} " + " ".join(f"{s:+5.2f}" for s in slopes.values()))
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
