#!/usr/bin/env python3
"""Benchmark the lid sheets' build (issue 29): evening out the corner shares, and the face's first pose per process.

Run on demand (not a test):  .venv/bin/python tools/bench_lids.py [--json bench_lids.json]
Times :func:`mpeg4fa.face.lids.build_lids` with its evened shares computed (an empty cache folder) and read
back from the cache, and, in fresh processes as a CLI call pays it, the generic head loaded, its rig built and
a blink posed. Target: the first pose near 0.55 s, what it took before the lids were evened out (issue 29).
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
import timeit
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.face.asset import load_head  # noqa: E402
from mpeg4fa.face.lids import build_lids  # noqa: E402

FIRST_POSE = """
import time
from mpeg4fa.face.asset import load_head
from mpeg4fa.face.model import FaceModel
mesh = load_head()
t = time.perf_counter()
FaceModel(mesh).deform({19: 500, 20: 500})
print(time.perf_counter() - t)
"""


def best_of(fn, repeat: int = 3) -> float:
    """Best wall seconds of ``repeat`` calls (the least disturbed by other work)."""
    return min(timeit.repeat(fn, number=1, repeat=repeat))


def first_pose(repeat: int) -> float:
    """Best of ``repeat`` fresh processes: rig build and a blink, the head already loaded (the cache as it is)."""
    root = Path(__file__).resolve().parents[1]
    runs = [float(subprocess.run([sys.executable, "-c", FIRST_POSE], cwd=root, capture_output=True, text=True,
                                 check=True).stdout.split()[-1]) for _ in range(repeat)]
    return min(runs)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path, default=Path("bench_lids.json"))
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    mesh = load_head()
    build_lids(mesh)  # the user cache now holds this head's shares
    result = {"build_lids_cached_s": best_of(lambda: build_lids(mesh), args.repeat)}
    saved = os.environ.get("MPEG4FA_CACHE")
    with tempfile.TemporaryDirectory(prefix="mpeg4fa-bench-") as tmp:
        def cold() -> None:
            os.environ["MPEG4FA_CACHE"] = tempfile.mkdtemp(dir=tmp)  # a new empty cache each time
            build_lids(mesh)
        try:
            result["build_lids_evened_s"] = best_of(cold, args.repeat)
        finally:
            if saved is None:
                os.environ.pop("MPEG4FA_CACHE", None)
            else:
                os.environ["MPEG4FA_CACHE"] = saved
    result["first_pose_s"] = first_pose(args.repeat)
    rows = [("build_lids, shares evened out", result["build_lids_evened_s"]),
            ("build_lids, shares read back", result["build_lids_cached_s"]),
            ("rig + first blink, fresh process", result["first_pose_s"])]
    print(f"{'what':<36} {'seconds':>8}")
    for name, seconds in rows:
        print(f"{name:<36} {seconds:8.3f}")
    args.json.write_text(json.dumps(result, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
