#!/usr/bin/env python3
"""Benchmark playback: decode + deform + render + readback per frame, MP4/PNG export, memory.

Run on demand (not a test):
    .venv/bin/python tools/bench_render.py [--stream S.fba --audio S.wav] [--size 512] [--json out.json]
    .venv/bin/python tools/bench_render.py --against OLD_CHECKOUT [--rounds 3]
``--against`` times the per-frame stages of this checkout and of another one (e.g. ``git archive
HEAD~5 mpeg4fa spec | tar -x -C /tmp/old``) in turns, in child processes, and prints their ratio:
on a shared machine two separate runs differ by more than a change does.
Without --stream it plays the longest English vector in ../shared/vectors (or the codec's demo
stream when that folder is absent). Targets (issue 4): decode + deform + render + readback at
512x512 >= 25 frames/s on the 2-core CPU machine (Mesa llvmpipe); MP4 export >= 1x real time.
On a machine with a GPU the same script reports the GPU's figures (the GL renderer is printed).
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if "--root" in sys.argv:  # a child timing another checkout's package (see --against)
    ROOT = Path(sys.argv[sys.argv.index("--root") + 1]).resolve()
sys.path.insert(0, str(ROOT))

from mpeg4fa.face import FaceModel  # noqa: E402
from mpeg4fa.decoded import resolve  # noqa: E402
from mpeg4fa.fba import decode, demo_stream, encode  # noqa: E402
from mpeg4fa.render import Renderer, play  # noqa: E402
from mpeg4fa.render.context import describe_context, gl_context  # noqa: E402

VECTORS = ROOT / ".." / "shared" / "vectors" / "fba" / "en"


def rss_mib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def pick_stream(args) -> tuple[bytes, str, Path | None]:
    if args.stream:
        audio = args.audio or (args.stream.with_suffix(".wav") if args.stream.with_suffix(".wav").is_file() else None)
        return args.stream.read_bytes(), args.stream.name, audio
    pairs = sorted(VECTORS.glob("*.FBA")) if VECTORS.is_dir() else []
    if pairs:
        longest = max(pairs, key=lambda p: p.stat().st_size)
        return longest.read_bytes(), longest.name, longest.with_suffix(".wav")
    return encode(demo_stream(seconds=10.0)), "demo stream (10 s)", None


def per_frame(face, renderer, data: bytes, repeat: int) -> dict:
    """Seconds per frame of each stage over a whole stream (best of ``repeat``)."""
    best = {}
    for _ in range(repeat):
        t0 = time.perf_counter()
        stream = decode(data)
        t1 = time.perf_counter()
        values = resolve(stream)
        t2 = time.perf_counter()
        poses = [face.pose_values(v) for v in values]
        t3 = time.perf_counter()
        image = np.empty((renderer.height, renderer.width, 3), np.uint8)
        for pose in poses:
            renderer.render(pose, out=image)
        t4 = time.perf_counter()
        n = len(stream)
        stages = {"decode": (t1 - t0) / n, "resolve": (t2 - t1) / n, "deform": (t3 - t2) / n,
                  "render+readback": (t4 - t3) / n}
        for key, value in stages.items():
            best[key] = min(best.get(key, value), value)
    best["total"] = sum(best.values())
    best["frames"] = n
    return best


def albedo_bake(face, repeat: int = 3) -> dict:
    """The head's own colours baked into its UV images, as the GLB export and the browser pages' head do it:
    seconds (best of ``repeat``, renderer set-up included) and the PNGs' sizes."""
    import io

    from PIL import Image

    from mpeg4fa.export.gltf import ALBEDO_SIZE

    best, baked = float("inf"), None
    for _ in range(repeat):
        t = time.perf_counter()
        with Renderer(face, width=ALBEDO_SIZE, height=ALBEDO_SIZE, lighting=False, lashes=False) as r:
            baked = r.albedo()
        best = min(best, time.perf_counter() - t)

    def kib(image) -> float:
        png = io.BytesIO()
        Image.fromarray(image).save(png, format="PNG")
        return len(png.getvalue()) / 1024

    return {"size": ALBEDO_SIZE, "seconds": best, "parts": list(baked.parts), "head_png_kib": kib(baked.image),
            "eye_png_kib": kib(baked.eye) if baked.eye is not None else 0.0}


def compare(args) -> int:
    """Per-frame stages of this checkout and of ``--against`` in turns; the best of each, and their ratio."""
    import subprocess

    best: dict[str, dict[str, dict]] = {"this": {}, "against": {}}
    with tempfile.TemporaryDirectory() as tmp:
        for k in range(args.rounds):
            for who, root in (("this", Path(__file__).resolve().parents[1]), ("against", args.against)):
                out = Path(tmp) / f"{who}{k}.json"
                cmd = [sys.executable, __file__, "--root", str(root), "--per-frame-only", "--size", str(args.size),
                       "--repeat", "1", "--json", str(out)] + (["--stream", str(args.stream)] if args.stream else [])
                subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)
                for key, t in json.loads(out.read_text()).items():
                    if key.startswith("per_frame"):
                        old = best[who].get(key)
                        best[who][key] = t if old is None or t["total"] < old["total"] else old
    print(f"{'per frame (ms, best of ' + str(args.rounds) + ')':32s} {'this':>8s} {'against':>8s} {'ratio':>7s}")
    result = {}
    for key in best["this"]:
        for stage in ("deform", "render+readback", "total"):
            a, b = best["this"][key][stage] * 1e3, best["against"][key][stage] * 1e3
            print(f"{key + ' ' + stage:32s} {a:8.2f} {b:8.2f} {a / b:7.3f}")
            result[f"{key} {stage}"] = {"this_ms": a, "against_ms": b, "ratio": a / b}
    args.json.write_text(json.dumps({"against": str(args.against), "rounds": args.rounds, **result}, indent=1))
    print(f"wrote {args.json}")
    return 0


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--stream", type=Path, help="a .fba stream (default: the longest en vector)")
    ap.add_argument("--audio", type=Path, help="its speech (default: the .wav beside it)")
    ap.add_argument("--size", type=int, default=512, help="square image size (default 512)")
    ap.add_argument("--repeat", type=int, default=3, help="repeats of the per-frame timing (best is kept)")
    ap.add_argument("--json", type=Path, default=Path("bench_render.json"))
    ap.add_argument("--against", type=Path, help="another checkout (its mpeg4fa/ and spec/): time both, print the ratio")
    ap.add_argument("--rounds", type=int, default=3, help="turns of each checkout with --against (best is kept)")
    ap.add_argument("--per-frame-only", action="store_true", help="skip the MP4/PNG exports")
    ap.add_argument("--root", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.against:
        return compare(args)

    result: dict = {"machine": {"python": platform.python_version(), "cpus": os.cpu_count()}}
    t = time.perf_counter()
    gl_context()
    result["context_s"] = time.perf_counter() - t
    result["gl"] = describe_context()
    data, name, audio = pick_stream(args)
    result["stream"] = name
    face = FaceModel.default()
    _ = face.rig
    size = args.size

    rows = []
    for samples in (0, 4):
        t = time.perf_counter()
        renderer = Renderer(face, width=size, height=size, samples=samples)
        setup = time.perf_counter() - t
        timing = per_frame(face, renderer, data, args.repeat)
        renderer.release()
        key = f"{size}x{size}" + (f" {samples}x MSAA" if samples else "")
        result[f"per_frame {key}"] = {**timing, "renderer_setup_s": setup}
        rows.append((key, timing))

    if args.per_frame_only:
        args.json.write_text(json.dumps(result, indent=1, default=float))
        return 0
    exports = {}
    with tempfile.TemporaryDirectory() as tmp:
        stream = decode(data)
        for label, target, samples in (("mp4", Path(tmp) / "out.mp4", 0), ("mp4 4x MSAA", Path(tmp) / "aa.mp4", 4),
                                       ("png", Path(tmp) / "png", 0)):
            with warnings.catch_warnings():  # a stream and its speech may differ by a few frames
                warnings.simplefilter("ignore")
                r = play(stream, target, face=face, audio=audio, width=size, height=size, samples=samples)
            exports[label] = {"seconds": r.seconds, "video_s": r.duration, "speed_x_realtime": r.speed,
                              "frames": r.n_frames, "rendered": r.rendered}
    result["export"] = exports
    result["albedo"] = albedo_bake(face)
    result["max_rss_mib"] = rss_mib()

    print(f"GL: {result['gl']['GL_RENDERER']} ({result['gl']['GL_VERSION']}); context {result['context_s'] * 1e3:.0f} ms")
    print(f"stream: {name}, {rows[0][1]['frames']} frames; image {size}x{size}")
    print(f"{'per frame':24s} {'decode':>8s} {'resolve':>8s} {'deform':>8s} {'render':>8s} {'total':>8s} {'fps':>7s}  target")
    for key, t in rows:
        ms = {k: v * 1e3 for k, v in t.items() if k != "frames"}
        fps = 1.0 / t["total"]
        print(f"{key:24s} {ms['decode']:7.2f}m {ms['resolve']:7.3f}m {ms['deform']:7.2f}m "
              f"{ms['render+readback']:7.2f}m {ms['total']:7.2f}m {fps:7.1f}  >= 25 {'PASS' if fps >= 25 else 'FAIL'}")
    print(f"{'export':24s} {'seconds':>8s} {'video s':>8s} {'x real time':>12s}  target")
    for label, e in exports.items():
        ok = "PASS" if e["speed_x_realtime"] >= 1 else "FAIL"
        print(f"{label:24s} {e['seconds']:8.2f} {e['video_s']:8.2f} {e['speed_x_realtime']:12.2f}  >= 1 {ok}")
    b = result["albedo"]
    print(f"albedo bake (the GLB's textures, Renderer.albedo at {b['size']}): {b['seconds']:.2f} s, "
          f"{', '.join(b['parts'])}; PNGs {b['head_png_kib']:.0f} + {b['eye_png_kib']:.0f} KiB")
    print(f"max RSS {result['max_rss_mib']:.0f} MiB")
    args.json.write_text(json.dumps(result, indent=1, default=float))
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
