#!/usr/bin/env python3
"""Photo -> FDP speed and memory (issue 27 item 1): per step in-process, and the whole `mpeg4fa fdp` command.

    .venv/bin/python tools/bench_photo.py [PHOTO] [--repeat 10] [--out out/bench_photo.json]

Without PHOTO: scikit-image's astronaut (512 x 512). In-process, best of ``--repeat``: opening the landmark
model, finding the landmarks in the photo (model open), the whole FDP (landmarks, points, similarity,
segmentation, texture), calibrating the generic head (dffd, rbf, elastic) and baking the texture a receiver
bakes. Then the command `mpeg4fa fdp PHOTO -o X.fdp` with and without `--preview`, each run under
`/usr/bin/time -v` for its wall time and peak resident memory. Prints a table and writes JSON.
"""
from __future__ import annotations

import argparse
import json
import re
import subprocess
import sys
import tempfile
import timeit
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))


def best(fn, repeat: int) -> float:
    """Best wall seconds of ``repeat`` calls (the least disturbed by other work)."""
    return min(timeit.repeat(fn, number=1, repeat=repeat))


def command(argv: list[str]) -> dict:
    """Wall seconds and peak RSS (MiB) of one run of the CLI, from GNU time."""
    run = subprocess.run(["/usr/bin/time", "-v", str(ROOT / ".venv/bin/mpeg4fa"), *argv], capture_output=True,
                         text=True, cwd=ROOT)
    if run.returncode != 0:
        raise SystemExit(f"mpeg4fa {' '.join(argv)} failed: {run.stderr[-500:]}")
    wall = re.search(r"Elapsed \(wall clock\) time.*: (?:(\d+):)?(\d+):([\d.]+)", run.stderr)
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", run.stderr)
    seconds = int(wall.group(1) or 0) * 3600 + int(wall.group(2)) * 60 + float(wall.group(3))
    return {"wall_s": round(seconds, 2), "peak_rss_mib": round(int(rss.group(1)) / 1024, 1)}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("photo", nargs="?", type=Path)
    p.add_argument("--repeat", type=int, default=10)
    p.add_argument("--out", type=Path, default=ROOT / "out" / "bench_photo.json")
    args = p.parse_args(argv)

    from PIL import Image

    from mpeg4fa.render.fdp_texture import bake_fdp_texture
    from mpeg4fa.tracking import LandmarkFinder
    from mpeg4fa.tracking.photo import fdp_from_photo, read_photo

    with tempfile.TemporaryDirectory() as tmp:
        photo = args.photo
        if photo is None:
            from skimage import data
            photo = Path(tmp) / "astronaut.jpg"
            Image.fromarray(data.astronaut()).save(photo, quality=92)
        image, _ = read_photo(photo)
        rows: dict[str, float] = {}

        def open_model():
            with LandmarkFinder(static=True):
                pass
        rows["open the landmark model"] = best(open_model, max(args.repeat // 3, 1))
        with LandmarkFinder(static=True) as finder:
            finder.find(image)
            rows["landmarks of one photo (model open)"] = best(lambda: finder.find(image), args.repeat)
        made = fdp_from_photo(photo)
        rows["FDP from the photo (all steps)"] = best(lambda: fdp_from_photo(photo), max(args.repeat // 3, 1))
        for method in ("dffd", "rbf", "elastic"):
            from mpeg4fa.face import FaceModel
            head = FaceModel.default()
            rows[f"calibrate the head ({method})"] = best(lambda: head.calibrate(made.fdp, method=method), 3)
        face = made.calibrated("dffd")
        rows["bake the FDP's texture (1024)"] = best(lambda: bake_fdp_texture(face.mesh, made.fdp), 3)
        cli = {"mpeg4fa fdp": command(["fdp", str(photo), "-o", str(Path(tmp) / "me.fdp")]),
               "mpeg4fa fdp --preview": command(["fdp", str(photo), "-o", str(Path(tmp) / "me2.fdp"),
                                                 "--preview", str(Path(tmp) / "check.png")])}
    print(f"photo: {photo if args.photo else 'astronaut'} {image.shape[1]}x{image.shape[0]}")
    print(f"{'step (in-process, best of runs)':44s} {'ms':>9s}")
    for name, seconds in rows.items():
        print(f"{name:44s} {seconds * 1000:9.1f}")
    print(f"{'command':44s} {'wall s':>9s} {'peak MiB':>9s}")
    for name, figures in cli.items():
        print(f"{name:44s} {figures['wall_s']:9.2f} {figures['peak_rss_mib']:9.1f}")
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps({"photo": str(args.photo or "astronaut"), "size": list(image.shape[1::-1]),
                                    "steps_ms": {k: round(v * 1000, 2) for k, v in rows.items()},
                                    "commands": cli}, indent=2))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
