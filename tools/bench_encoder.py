#!/usr/bin/env python
"""Benchmark of the text encoder (mpeg4fa.speech): speed and bit rate of streams made from speech.

A script run on demand, not a test::

    .venv/bin/python tools/bench_encoder.py [--seconds 60] [--json OUT] [--engine espeak]

For about ``--seconds`` of English and of Chinese speech (original sample sentences with
expression tags, cycled until the speech is long enough) at 25 fps it measures:

1. speed: TTS time, the rest of the encoder (visemes, timeline, FAP stream, bitstream) and the
   whole, each as x real time (audio seconds per wall second);
2. size: bits per frame and kbit/s at the high level (FAP 1 + FAP 2; Chinese visemes go out
   as low-level FAPs, see mpeg4fa.speech.encoder), the low level (every moving FAP 3-68) and
   the low level restricted to the lip, jaw and brow groups (2, 4, 8), each with the encoder's
   coding options for text (``TEXT_CODING``) and with the codec's plain defaults.

Targets (issue 5): high level <= 30 bits/frame; low-level lip, jaw and brow FAPs <= 60
bits/frame (< 1.5 kbit/s). It prints tables, marks targets PASS/FAIL and writes JSON
(``bench_encoder.json`` unless ``--json``).
"""
from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402

from mpeg4fa import __version__ as MPEG4FA_VERSION  # noqa: E402
from mpeg4fa.fba import EncodeOptions, FapStream, decode, encode  # noqa: E402
from mpeg4fa.face.frames import resolve  # noqa: E402
from mpeg4fa.spec import FAP_GROUP  # noqa: E402
from mpeg4fa.speech.encoder import TEXT_CODING, encode_text, make_engine  # noqa: E402

FPS = 25.0
TARGET_HIGH = 30.0
TARGET_LIPS = 60.0
LIP_JAW_BROW_GROUPS = (2, 4, 8)

ENGLISH = [
    "(joy, 30, 0.6) Good morning, and welcome to the station.",
    "The next train to the harbour leaves from platform four in about ten minutes.",
    "(surprise, 35, 0.3) Oh, the bridge is closed today because of the strong wind!",
    "(joy, 0, 0.5) Please take the bus from the main square instead.",
    "It stops near the old market, the museum and the public library.",
    "(sadness, 25, 0.8) We are sorry for the trouble this may cause on your journey.",
    "(joy, 40, 0.5) Tickets for the evening concert are still available at the front desk.",
    "Remember to keep your bags with you, and have a pleasant trip.",
]
CHINESE = [
    "(joy, 30, 0.6)大家早上好，欢迎来到火车站。",
    "下一班开往海边的火车大约十分钟后从四号站台出发。",
    "(surprise, 35, 0.3)今天风很大，所以大桥暂时关闭了！",
    "(joy, 0, 0.5)请在中心广场换乘公共汽车。",
    "公共汽车经过老市场、博物馆和图书馆。",
    "(sadness, 25, 0.8)给您的旅途带来不便，我们非常抱歉。",
    "(joy, 40, 0.5)晚上音乐会的门票在服务台还可以买到。",
    "请随身携带您的行李，祝您旅途愉快。",
]


def long_text(sentences: list[str], seconds: float, engine) -> str:
    """Cycle the sentences until the engine's speech lasts ``seconds`` (measured once per sentence)."""
    lengths = []
    for s in sentences:
        enc = encode_text(s, engine=engine, level="low", fps=FPS)
        lengths.append(enc.speech.duration)
    out, total, k = [], 0.0, 0
    while total < seconds:
        out.append(sentences[k % len(sentences)])
        total += lengths[k % len(sentences)]
        k += 1
    return " ".join(out)


def max_error(enc) -> dict[str, float]:
    """Largest decoded-minus-timeline difference over the low-level FAPs a stream sends, in FAP units."""
    stream = decode(encode(enc.stream, enc.coding()))
    on_grid = np.repeat(resolve(stream), stream.skip + 1, axis=0)
    sent = enc.stream.fap_mask.any(axis=0) | (enc.level == "low")
    sent[:2] = False
    err = np.abs(on_grid[:, sent] - enc.values[:, sent]) if sent.any() else np.zeros(1)
    return {"max": float(err.max()), "mean": float(err.mean())}


def _mns_unit_mm() -> float | None:
    """Millimetres per MNS unit on the default head (a guide: jaw and vertical lip FAPs use MNS), if installed."""
    try:
        from mpeg4fa.face import FaceModel
        return FaceModel.default(auto_install=False).fapu.as_dict()["MNS0"] / 1024
    except Exception:  # no head installed: errors stay in FAP units
        return None


def lips_only(stream: FapStream) -> FapStream:
    """The low-level stream with only the lip, jaw and brow FAPs left in it."""
    keep = np.isin(FAP_GROUP, LIP_JAW_BROW_GROUPS)
    out = stream.copy()
    out.fap_mask[:, ~keep] = False
    out.fap_values[:, ~keep] = 0
    return out


def sizes(folded: FapStream, coding: EncodeOptions, plain: FapStream) -> dict[str, dict[str, float]]:
    """Bits of the stream as the encoder sends it, and of the same timeline unfolded with plain options."""
    rows = {}
    for label, stream, options in (("text coding", folded, coding), ("plain", plain, EncodeOptions())):
        data = encode(stream, options)
        back = decode(data)  # skipped repeats are absent from ``back``: compare the time covered
        assert abs(back.duration - stream.duration) < 0.5 / FPS, "the stream lost its end"
        bits = len(data) * 8
        n = round(stream.duration * FPS)
        rows[label] = {"bytes": len(data), "bits_per_frame": bits / n, "kbit_s": bits / (n / FPS) / 1000}
    return rows


def bench_language(name: str, sentences: list[str], seconds: float, engine_name: str) -> dict:
    engine = make_engine(engine_name)
    text = long_text(sentences, seconds, engine)
    result: dict = {"language": name, "characters": len(text)}
    for level in ("high", "low"):
        t0 = time.perf_counter()
        speech_engine = _Timed(engine)
        enc = encode_text(text, engine=speech_engine, level=level, fps=FPS)
        t_encoder = time.perf_counter()
        data = encode(enc.stream, enc.coding())
        t_end = time.perf_counter()
        audio = enc.speech.duration
        tts = speech_engine.seconds
        rest = (t_encoder - t0 - tts) + (t_end - t_encoder)
        plain = encode_text(text, engine=engine, level=level, fps=FPS, fold=False)
        result[level] = {
            "audio_s": audio, "frames": len(enc.stream), "tts_s": tts, "encoder_s": rest,
            "x_realtime_without_tts": audio / rest, "x_realtime_with_tts": audio / (tts + rest),
            "bytes": len(data), "sizes": sizes(enc.stream, enc.coding(), plain.stream),
            "max_error": max_error(enc), "mask_types": list(enc.mask_types),
        }
        if level == "low":
            result["low_lips"] = {"sizes": sizes(lips_only(enc.stream), enc.coding(), lips_only(plain.stream))}
    return result


class _Timed:
    """An engine wrapper that adds up the time spent synthesizing."""

    def __init__(self, engine) -> None:
        self.engine, self.name, self.seconds = engine, engine.name, 0.0
        self.rate = getattr(engine, "rate", None)

    def synthesize(self, text, **kw):
        t = time.perf_counter()
        try:
            return self.engine.synthesize(text, **kw)
        finally:
            self.seconds += time.perf_counter() - t


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="speech length per language (default 60)")
    ap.add_argument("--engine", default="espeak", help="espeak (default), pyttsx3 or estimate")
    ap.add_argument("--json", type=Path, default=Path("bench_encoder.json"))
    args = ap.parse_args(argv)

    results = [bench_language("English", ENGLISH, args.seconds, args.engine),
               bench_language("Chinese", CHINESE, args.seconds, args.engine)]
    print(f"mpeg4fa {MPEG4FA_VERSION}, {platform.python_implementation()} {platform.python_version()}, "
          f"{platform.machine()}, engine {args.engine}, {FPS:g} fps, coding for text: {TEXT_CODING}\n")
    print("| language | level | audio s | TTS s | encoder s | x real time (no TTS) | x real time (with TTS) |")
    print("|---|---|---|---|---|---|---|")
    for r in results:
        for level in ("high", "low"):
            x = r[level]
            print(f"| {r['language']} | {level} | {x['audio_s']:.1f} | {x['tts_s']:.2f} | {x['encoder_s']:.2f} | "
                  f"{x['x_realtime_without_tts']:.0f} | {x['x_realtime_with_tts']:.0f} |")
    print("\n| language | stream | coding | bits/frame | kbit/s | target |")
    print("|---|---|---|---|---|---|")
    ok = True
    for r in results:
        for key, target in (("high", TARGET_HIGH), ("low", None), ("low_lips", TARGET_LIPS)):
            for coding, s in r[key]["sizes"].items():
                verdict = ""
                if target is not None and coding == "text coding":
                    passed = s["bits_per_frame"] <= target
                    ok &= passed
                    verdict = f"<= {target:g} {'PASS' if passed else 'FAIL'}"
                label = {"high": "high level", "low": "low level (all moving FAPs)",
                         "low_lips": "low level, lip/jaw/brow groups"}[key]
                print(f"| {r['language']} | {label} | {coding} | {s['bits_per_frame']:.1f} | {s['kbit_s']:.2f} | "
                      f"{verdict} |")
    mns = _mns_unit_mm()
    print("\n| language | level | mask types (groups 1-10) | max error, FAP units | mean error | max error, mm |")
    print("|---|---|---|---|---|---|")
    for r in results:
        for level in ("high", "low"):
            e = r[level]["max_error"]
            mm = f"{e['max'] * mns:.2f} (MNS0/1024 = {mns:.4f} mm)" if mns else "n/a (no default head)"
            print(f"| {r['language']} | {level} | {r[level]['mask_types']} | {e['max']:.0f} | {e['mean']:.2f} | {mm} |")
    args.json.write_text(json.dumps({"version": MPEG4FA_VERSION, "engine": args.engine, "fps": FPS,
                                     "text_coding": TEXT_CODING, "results": results, "targets_met": ok},
                                    indent=1))
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
