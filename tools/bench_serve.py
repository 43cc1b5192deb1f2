#!/usr/bin/env python3
"""Benchmark the live server over loopback: latency from text to first frame, and delivery of a long speech.

Run on demand (not a test):
    .venv/bin/python tools/bench_serve.py [--runs 5] [--speed 1] [--json tools/bench_serve.json]

The server runs in-process (uvicorn in a thread, 127.0.0.1, warmed up: engine loaded, codec
compiled) with the generic head when it is built, else the procedural head; the client is
:func:`mpeg4fa.serve.client.play` in the same process (so both share this machine's cores).

* **latency**: from sending ``say`` to receiving the first FBA message (client) and
  from receiving ``say`` to sending it (server), for first sentences of three lengths, ``--runs``
  times each (median and worst). The whole first sentence is spoken and encoded before its
  first frame goes out, so this grows with the first sentence's length.
* **sustained**: about 60 s of speech in 16 sentences, played by a client whose clock runs
  ``--speed`` times real time (1: true real time, a minute), reporting its buffer every 100 ms:
  underruns (items that came after their time), the smallest margin by which an item came
  before its time, the most media held ahead of the playhead (flow control bounds it by the
  window plus one chunk), wall time against media time, and the server's waits on the window.
* **bandwidth** of that speech's face data (issue 31: at most 2 kbit/s): the FBA messages as sent
  (protocol 2: the bitstream, 12-byte message heads included; the ``segment`` JSON that announces each
  counted apart), against protocol 1's per-frame ``frames`` JSON of ARKit weights for the same decoded
  frames (what it sent before: rebuilt here from the same streams, 0.2 s per message, 3 decimals, as
  Starlette writes JSON), and the audio for scale.
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


def bandwidth(face, played, chunk: float) -> dict:
    """Face data as sent (FBA) against protocol 1's weights JSON for the same frames, in kbit/s of speech."""
    import warnings

    import numpy as np

    from mpeg4fa.decoded import resolve
    from mpeg4fa.export.arkit_units import arkit_units
    from mpeg4fa.fba import decode

    media = played.done["duration"]
    units = arkit_units(face)
    weights_bytes = segment_bytes = 0
    for seg in played.segments:
        stream = decode(seg["fba"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            w = np.round(units.weights(resolve(stream)), 3)
        times = seg["start"] + np.asarray(stream.timestamps)
        edges = np.floor((times - seg["start"]) / chunk + 1e-9).astype(np.int64)
        cut = np.flatnonzero(np.diff(edges)) + 1
        for a, b in zip(np.r_[0, cut], np.r_[cut, len(edges)]):
            message = {"type": "frames", "segment": seg["index"], "times": times[a:b].tolist(), "weights": w[a:b].tolist()}
            weights_bytes += len(json.dumps(message, separators=(",", ":")).encode())
        announced = {k: v for k, v in seg.items() if k != "fba"}
        segment_bytes += len(json.dumps(announced, separators=(",", ":"), ensure_ascii=False).encode())
    audio_bytes = sum(len(b) + 12 for _, b in played.audio)
    kbps = lambda n: n * 8 / media / 1000  # noqa: E731
    return {"media_s": media, "fba_bytes": played.face_bytes, "fba_kbps": kbps(played.face_bytes),
            "segment_json_kbps": kbps(segment_bytes), "weights_json_bytes": weights_bytes,
            "weights_json_kbps": kbps(weights_bytes), "audio_kbps": kbps(audio_bytes),
            "ratio": weights_bytes / played.face_bytes}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--runs", type=int, default=5)
    parser.add_argument("--speed", type=float, default=1.0, help="client clock speed for the long speech")
    parser.add_argument("--window", type=float, default=2.0)
    parser.add_argument("--json", type=Path, default=ROOT / "tools" / "bench_serve.json")
    args = parser.parse_args()

    face = face_for_tests()
    app = create_app(face, window=args.window, warm=True)
    report = {"machine": platform.platform(), "python": platform.python_version(), "window": args.window,
              "head": "generic" if face.mesh.face_units is not None else "procedural", "latency": {}, "sustained": {}}
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
        report["bandwidth"] = bandwidth(face, played, app.state.live.chunk)
    print(f"\nsustained: {media:.1f} s of speech ({row['sentences']} sentences, {row['frames']} frames) "
          f"played at {args.speed:g}x in {played.wall:.1f} s")
    print(f"{'underruns':<34} {row['underruns']}")
    print(f"{'smallest margin before due (s)':<34} {row['min_margin_s']:.3f}")
    print(f"{'most held ahead of playhead (s)':<34} {row['max_ahead_s']:.3f} (window {args.window:g} + chunk 0.2)")
    print(f"{'server waits on the window':<34} {row['server_waits']}")
    print(f"{'first frame (ms)':<34} {row['first_frame_ms']:.0f}")
    bw = report["bandwidth"]
    print(f"\nbandwidth over the same {media:.1f} s of speech (kbit/s)")
    for name, label in (("fba_kbps", "face: FBA bitstream (protocol 2)"), ("segment_json_kbps", "segment announcements"),
                        ("weights_json_kbps", "face: ARKit weights JSON (protocol 1)"), ("audio_kbps", "audio (PCM)")):
        print(f"{label:<40} {bw[name]:>8.3f}")
    print(f"{'weights JSON / FBA':<40} {bw['ratio']:>8.1f}x")
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(report, indent=2))
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
