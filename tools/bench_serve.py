#!/usr/bin/env python3
"""Benchmark the live server over loopback: latency from text to first frame, and delivery of a long speech.

Run on demand (not a test):
    .venv/bin/python tools/bench_serve.py [--runs 5] [--speed 1] [--json out/bench_serve.json]

The server runs in-process (uvicorn in a thread, 127.0.0.1, warmed up: engine loaded, codec
compiled) with the generic head when it is built, else the procedural head; the client is
:func:`mpeg4fa.serve.client.play` in the same process (so both share this machine's cores).

* **latency**: from sending ``say`` to receiving the first ``frames`` message (client) and
  from receiving ``say`` to sending it (server), for first sentences of three lengths, ``--runs``
  times each (median and worst). The whole first sentence is spoken and encoded before its
  first frame goes out, so this grows with the first sentence's length.
* **sustained**: about 60 s of speech in 16 sentences, played by a client whose clock runs
  ``--speed`` times real time (1: true real time, a minute), reporting its buffer every 100 ms:
  underruns (items that came after their time), the smallest margin by which an item came
  before its time, the most media held ahead of the playhead (flow control bounds it by the
  window plus one chunk), wall time against media time, and the server's waits on the window.
"""
from __future__ import annotations

import argparse
import json
import platform
import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests")]

from mpeg4fa.serve.app import create_app  # noqa: E402
from mpeg4fa.serve.client import play  # noqa: E402
from serve.live_server import face_for_tests, running  # noqa: E402

FIRST = {
    "short (2 words)": "Hello there. ",
    "medium (9 words)": "The quick brown fox jumps over the lazy dog. ",
    "long (24 words)": "We walked along the old road for hours, talking about music, books, films and all the "
                       "places we had seen together that year. ",
}
REST = "And then we went home."
LONG = ["The quick brown fox jumps over the lazy dog near the bank of the river.",
        "(surprise, 30, 0.4) Nobody expected the weather to turn so quickly this afternoon.",
        "We walked along the old road, talking about music, books and the places we had seen.",
        "(joy, 45, 0.6) Then the sun came out again, and everything looked bright and new."]


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--speed", type=float, default=1.0, help="client clock speed for the long speech")
    parser.add_argument("--window", type=float, default=2.0)
    parser.add_argument("--json", type=Path, default=ROOT / "out" / "bench_serve.json")
    args = parser.parse_args()

    face = face_for_tests()
    app = create_app(face, window=args.window, warm=True)
    report = {"machine": platform.platform(), "python": platform.python_version(), "window": args.window,
              "head": "generic" if app.state.live.units is not None else "procedural", "latency": {}, "sustained": {}}
    with running(app) as base:
        url = base.replace("http://", "ws://") + "/ws"
        print(f"latency from text to first frame ({args.runs} runs each; ms)")
        print(f"{'first sentence':<18} {'client median':>13} {'client max':>10} {'server median':>13} "
              f"{'sentence s':>10}")
        for name, first in FIRST.items():
            client, server, seconds = [], [], 0.0
            for _ in range(args.runs):
                played = play(url, first + REST, speed=8.0)
                client.append(played.first_frame_after * 1e3)
                server.append(played.done["first_frame_after"] * 1e3)
                seconds = played.segments[0]["duration"]
            row = {"client_median_ms": statistics.median(client), "client_max_ms": max(client),
                   "server_median_ms": statistics.median(server), "first_sentence_s": seconds}
            report["latency"][name] = row
            print(f"{name:<18} {row['client_median_ms']:>13.0f} {row['client_max_ms']:>10.0f} "
                  f"{row['server_median_ms']:>13.0f} {seconds:>10.2f}")

        text = " ".join(LONG * 4)
        played = play(url, text, speed=args.speed, prebuffer=0.3, timeout=600)
        record = app.state.live.utterances[-1]
        media = played.done["duration"]
        row = {"media_s": media, "wall_s": played.wall, "speed": args.speed, "frames": played.frames,
               "sentences": record["sentences"], "underruns": played.underruns,
               "max_lateness_ms": played.max_lateness * 1e3, "min_margin_s": played.min_margin,
               "max_ahead_s": played.max_ahead, "server_waits": record["waits"], "reports": played.reports,
               "first_frame_ms": played.first_frame_after * 1e3}
        report["sustained"] = row
    print(f"\nsustained: {media:.1f} s of speech ({row['sentences']} sentences, {row['frames']} frames) "
          f"played at {args.speed:g}x in {played.wall:.1f} s")
    print(f"{'underruns':<34} {row['underruns']}")
    print(f"{'smallest margin before due (s)':<34} {row['min_margin_s']:.3f}")
    print(f"{'most held ahead of playhead (s)':<34} {row['max_ahead_s']:.3f} (window {args.window:g} + chunk 0.2)")
    print(f"{'server waits on the window':<34} {row['server_waits']}")
    print(f"{'first frame (ms)':<34} {row['first_frame_ms']:.0f}")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2))
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
