#!/usr/bin/env python3
"""Regenerate ``mpeg4fa/face/data/fap_magnitudes.csv``: the largest value each FAP takes, per sign.

The smooth-skin test poses every FAP alone at the largest magnitude a real face is asked
for, so that a ridge or a fold that some stream or profile would show is caught. Sources:
every real stream under ``../shared/vectors`` (``.fba`` and ``.fap``, resolved as the
player resolves them: held, interpolated, high-level expanded, clamped) and the viseme and
expression profiles (full strength, both viseme sets). The CSV is committed so that the
test runs where ``../shared`` is absent.

    .venv/bin/python tools/fap_magnitudes.py [--vectors ../shared/vectors] [--out PATH]
"""
from __future__ import annotations

import argparse
import csv
import sys
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mpeg4fa.face.frames import resolve  # noqa: E402
from mpeg4fa.formats import read_stream  # noqa: E402
from mpeg4fa.spec import FAPS, N_FAPS  # noqa: E402
from mpeg4fa.spec.profiles import EXPRESSION_PROFILES, VISEME_PROFILES  # noqa: E402

OUT = ROOT / "mpeg4fa" / "face" / "data" / "fap_magnitudes.csv"


def stream_extremes(paths: list[Path]) -> tuple[np.ndarray, np.ndarray, list[str], list[str]]:
    """(largest positive, largest |negative|) per FAP over the streams, and where each came from."""
    pos, neg = np.zeros(N_FAPS), np.zeros(N_FAPS)
    pos_from, neg_from = [""] * N_FAPS, [""] * N_FAPS
    for path in paths:
        stream, _ = read_stream(path)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # clamps are the player's business; we take what it shows
            values = resolve(stream)
        if len(values) == 0:
            continue
        hi, lo = values.max(axis=0), -values.min(axis=0)
        for f in range(N_FAPS):
            if hi[f] > pos[f]:
                pos[f], pos_from[f] = hi[f], path.name
            if lo[f] > neg[f]:
                neg[f], neg_from[f] = lo[f], path.name
    return pos, neg, pos_from, neg_from


def profile_extremes() -> tuple[np.ndarray, np.ndarray, list[str], list[str]]:
    profiles = {f"{s}:{k}": np.asarray(v, float) for s, table in VISEME_PROFILES.items() for k, v in table.items()}
    profiles.update({f"expression:{k}": np.asarray(v, float) for k, v in EXPRESSION_PROFILES.items()})
    names = list(profiles)
    stack = np.stack([profiles[n] for n in names])
    hi, lo = np.maximum(stack.max(axis=0), 0), np.maximum(-stack.min(axis=0), 0)
    return hi, lo, [names[i] if hi[f] else "" for f, i in enumerate(stack.argmax(axis=0))], \
        [names[i] if lo[f] else "" for f, i in enumerate(stack.argmin(axis=0))]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--vectors", type=Path, default=ROOT.parent / "shared" / "vectors")
    ap.add_argument("--out", type=Path, default=OUT)
    args = ap.parse_args(argv)
    paths = sorted(p for p in args.vectors.rglob("*") if p.suffix.lower() in (".fba", ".fap"))
    if not paths:
        print(f"no streams under {args.vectors}", file=sys.stderr)
        return 1
    sp, sn, spf, snf = stream_extremes(paths)
    pp, pn, ppf, pnf = profile_extremes()
    with open(args.out, "w", newline="", encoding="utf-8") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(["fap", "name", "max_pos", "max_neg", "pos_from", "neg_from"])
        for k in range(2, N_FAPS):
            pos = max(sp[k], pp[k])
            neg = max(sn[k], pn[k])
            w.writerow([k + 1, FAPS[k].name, f"{pos:g}", f"{neg:g}",
                        (spf[k] if sp[k] >= pp[k] else ppf[k]) if pos else "",
                        (snf[k] if sn[k] >= pn[k] else pnf[k]) if neg else ""])
    print(f"{len(paths)} streams -> {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
