"""Video tracking speed (issue 27 item 3): a 640x480 face video end to end (read, track, FAPs, encode), per stage.

    .venv/bin/python tools/bench_tracking.py [--seconds 10] [--out out/bench_tracking.json]

The video: the generic head wearing scikit-image's astronaut (tools/track_loop.py's head), talking, blinking and
turning, rendered once to 640x480 H.264 at 25 fps (not timed). Timed, best of ``--repeat`` runs: decoding the
frames to RGB (PyAV), the landmark model per frame (MediaPipe Face Mesh, video mode), the tracker's own work
(feature points, head pose, FAPs, One Euro filter), the FBA encoding, and all of it together through
``mpeg4fa.tracking.track_video`` + ``mpeg4fa.fba.encode``, as ``encode --video`` runs it. Also the One Euro
filter's delay on steps (frames until 50 % / 90 % of the step). Prints a table and writes JSON.
"""
from __future__ import annotations

import argparse
import importlib.util
import json
import os
import sys
import time
from pathlib import Path


TARGET_FPS = 25.0


def _loop_tool():
    spec = importlib.util.spec_from_file_location("track_loop_tool", Path(__file__).with_name("track_loop.py"))
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def make_video(path: Path, seconds: float, fps: float = 25.0) -> None:
    from mpeg4fa.render import play

    tool = _loop_tool()
    values, _ = tool.sent_values(seconds, fps)
    stream, _ = tool.sent_stream(values, fps)
    face, texture = tool.textured_head(512)
    play(stream, path, face=face, texture=texture, width=640, height=480, samples=2)


def stages(path: Path) -> dict[str, float]:
    """Seconds per stage over the whole video."""
    from mpeg4fa.fba import EncodeOptions, encode
    from mpeg4fa.speech.encoder import TEXT_CODING
    from mpeg4fa.tracking import FaceTracker, LandmarkFinder
    from mpeg4fa.tracking.video import read_frames

    t0 = time.perf_counter()
    frames = list(read_frames(path))
    t1 = time.perf_counter()
    with LandmarkFinder(static=False) as finder:
        found = [finder.find(rgb) for rgb in frames]
    t2 = time.perf_counter()
    tracker = FaceTracker(25.0)
    for lm in found:
        tracker.push_landmarks(lm)
    stream = tracker.stream()
    t3 = time.perf_counter()
    data = encode(stream, EncodeOptions(**TEXT_CODING))
    t4 = time.perf_counter()
    return {"frames": len(frames), "read": t1 - t0, "landmarks": t2 - t1, "faps": t3 - t2, "encode": t4 - t3,
            "bytes": len(data)}


def end_to_end(path: Path) -> tuple[float, int]:
    from mpeg4fa.fba import EncodeOptions, encode
    from mpeg4fa.speech.encoder import TEXT_CODING
    from mpeg4fa.tracking import track_video

    started = time.perf_counter()
    tracked = track_video(path)
    encode(tracked.stream, EncodeOptions(**TEXT_CODING))
    return time.perf_counter() - started, len(tracked.stream)


def filter_delays() -> list[dict]:
    from mpeg4fa.tracking.filters import OneEuroFilter, step_delay
    from mpeg4fa.tracking.tracker import BETA, MIN_CUTOFF, TRANSLATION_SCALE

    rows = []
    for size in (30.0, 100.0, 300.0, 1000.0):
        delay = step_delay(OneEuroFilter(25.0, MIN_CUTOFF, BETA, scale=TRANSLATION_SCALE), size=size)
        rows.append({"step_fapu": size, **delay})
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=10.0)
    parser.add_argument("--repeat", type=int, default=2)
    parser.add_argument("--out", type=Path, default=Path("out/bench_tracking.json"))
    parser.add_argument("--video", type=Path, help="track this video instead of rendering one")
    args = parser.parse_args(argv)
    video = args.video or args.out.with_name("bench_tracking_640x480.mp4")
    if args.video is None and not video.exists():
        video.parent.mkdir(parents=True, exist_ok=True)
        print(f"rendering {video} ({args.seconds:g} s at 640x480)...", file=sys.stderr)
        make_video(video, args.seconds)
    best = min((stages(video) for _ in range(args.repeat)), key=lambda r: r["read"] + r["landmarks"] + r["faps"])
    whole = min(end_to_end(video) for _ in range(args.repeat))
    n = best["frames"]
    rows = [(name, best[name]) for name in ("read", "landmarks", "faps", "encode")]
    print(f"{'stage':12} {'ms/frame':>9} {'frames/s':>9}")
    for name, seconds in rows:
        print(f"{name:12} {1000 * seconds / n:9.2f} {n / seconds:9.1f}")
    fps = whole[1] / whole[0]
    print(f"{'end to end':12} {1000 * whole[0] / whole[1]:9.2f} {fps:9.1f}   (target >= {TARGET_FPS:g} frames/s: "
          f"{'met' if fps >= TARGET_FPS else 'NOT met'}; {os.cpu_count()} CPUs)")
    delays = filter_delays()
    for d in delays:
        print(f"One Euro step of {d['step_fapu']:6.0f} FAPU: 50 % after {d['frames_50']:.0f} frames "
              f"({d['ms_50']:.0f} ms), 90 % after {d['frames_90']:.0f} ({d['ms_90']:.0f} ms) at 25 fps")
    report = {"video": str(video), "frames": n, "stages_s": {k: round(v, 4) for k, v in rows},
              "end_to_end_s": round(whole[0], 3), "end_to_end_fps": round(fps, 1), "target_fps": TARGET_FPS,
              "met": fps >= TARGET_FPS, "cpus": os.cpu_count(), "stream_bytes": best["bytes"],
              "filter_step_delay": delays}
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=1))
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
