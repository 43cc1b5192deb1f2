#!/usr/bin/env python3
"""Lip sync report: how well the mouth of the generic head follows the speech.

Two modes, run on demand (not tests):

    .venv/bin/python tools/lipsync_report.py [FOLDER] [--json out.json] [--window S] [--max-lag N]
    .venv/bin/python tools/lipsync_report.py --generated [--json OUT] [--level high|low|both] [--no-align]

FOLDER: every FBA stream with a same-named .wav (default ../shared/vectors/fba/en, the 16
visage|SDK speech streams). For each pair it poses the generic head (FaceModel.default()) at every
frame, takes the inner-lip gap (feature point 2.2 above 2.3, mm) and correlates it (Pearson r) with
the short-time energy of the speech in dB around each frame time, at lag 0 and at lags -N..+N
frames. A positive best lag means the mouth leads the audio (opens before the sound); negative,
that it is late.

--generated: English and Chinese sentences spoken by espeak-ng and encoded by ``encode_text``
at 25 fps, coded, decoded, resolved and posed again (mpeg4fa.render.visemesync), against the
phoneme spans the encoder was given:
  half     share of visemes whose weight peaks in the first half of its phoneme (25 fps, and at
           --peak-fps, 100 by default, where a frame is shorter than most phonemes' halves)
  rel      median peak position in the phoneme (0 onset, 1 end); off: mean peak - onset, ms
  lag/r0   best lag of the inner-lip gap / energy correlation (frames, + = mouth leads), r at 0
  closures PP/bpm seen shut within one frame of the onset (share), missed ones, mean offset ms
English also against pocketsphinx's forced alignment of the audio (the ``test`` extra): mean and
95th percentile of viseme peak - aligned phone onset (ms), closures within a frame of the aligned
onsets, and the onsets themselves (espeak's events as given, and the spans after the closure
correction of mpeg4fa.speech.closures) against the aligned ones. Targets (issue, part 5): half
>= 90 % per language, lag 0 +- 1 frame, closures within 1 frame; PASS/FAIL lines; JSON to
out/lipsync_generated.json unless --json.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from mpeg4fa.face.model import FaceModel  # noqa: E402
from mpeg4fa.formats.sniff import read_stream  # noqa: E402
from mpeg4fa.render.audio import read_audio  # noqa: E402
from mpeg4fa.render.lipsync import (DEFAULT_FLOOR_DB, DEFAULT_MAX_LAG, LipSyncReport,  # noqa: E402
                                    lipsync_report)
from lipsync_generated import run_generated  # noqa: E402

DEFAULT_FOLDER = Path(__file__).resolve().parents[1].parent / "shared" / "vectors" / "fba" / "en"


def pairs(folder: Path) -> list[tuple[Path, Path]]:
    """(stream, audio) for every .fba/.FBA file that has a .wav (any case) of the same stem beside it."""
    wavs = {p.stem: p for p in folder.iterdir() if p.suffix.lower() == ".wav"}
    streams = sorted((p for p in folder.iterdir() if p.suffix.lower() == ".fba"), key=lambda p: p.name)
    return [(s, wavs[s.stem]) for s in streams if s.stem in wavs]


def fmt(r: float) -> str:
    return "   nan" if np.isnan(r) else f"{r:+.3f}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        description=__doc__.split("\n\n")[0].replace("\n", " "),
        epilog="Output: one row per pair (frames, stream and audio length in s, r at lag 0, best lag, "
               "r at best lag), then the means. Streams whose audio length differs from the stream's "
               "by more than a frame are flagged with '*'; only frames inside the audio are compared.",
    )
    parser.add_argument("folder", nargs="?", type=Path, default=DEFAULT_FOLDER,
                        help=f"folder of *.fba + *.wav pairs (default: {DEFAULT_FOLDER})")
    parser.add_argument("--json", type=Path, metavar="OUT", help="also write every report to this JSON file")
    parser.add_argument("--window", type=float, default=None,
                        help="energy window in seconds (default: one frame period, 0.04 s at 25 fps)")
    parser.add_argument("--max-lag", type=int, default=DEFAULT_MAX_LAG,
                        help=f"lags searched either way, in frames (default {DEFAULT_MAX_LAG})")
    parser.add_argument("--linear", action="store_true",
                        help="correlate with linear RMS instead of dB (default dB: see mpeg4fa.render.lipsync)")
    parser.add_argument("--floor-db", type=float, default=DEFAULT_FLOOR_DB,
                        help=f"energy floor in dBFS (default {DEFAULT_FLOOR_DB:g})")
    parser.add_argument("--generated", action="store_true",
                        help="measure encode_text's own English and Chinese speech instead of a folder")
    parser.add_argument("--level", choices=("high", "low", "both"), default="high",
                        help="--generated: the stream level to encode (default high: FAP 1, Chinese low-level)")
    parser.add_argument("--peak-fps", type=float, default=100.0,
                        help="--generated: the finer frame rate the peak share is also measured at (default 100)")
    parser.add_argument("--no-align", action="store_true", help="--generated: skip the pocketsphinx comparison")
    args = parser.parse_args(argv)
    if args.generated:
        return run_generated(args.json or Path("out/lipsync_generated.json"), level=args.level,
                             peak_fps=args.peak_fps, align=not args.no_align)

    if not args.folder.is_dir():
        print(f"{args.folder}: no such folder (give a folder of .fba + .wav pairs)", file=sys.stderr)
        return 2
    found = pairs(args.folder)
    if not found:
        print(f"{args.folder}: no .fba file with a same-named .wav", file=sys.stderr)
        return 2

    t0 = time.perf_counter()
    face = FaceModel.default()
    reports: list[LipSyncReport] = []
    header = f"{'stream':<26} {'frames':>6} {'stream s':>8} {'audio s':>8} {'r lag0':>7} {'best':>5} {'r best':>7}"
    print(header)
    print("-" * len(header))
    for stream_path, wav_path in found:
        stream, _ = read_stream(stream_path)
        audio = read_audio(wav_path)
        rep = lipsync_report(face, stream, audio, name=stream_path.stem, window=args.window,
                             max_lag=args.max_lag, db=not args.linear, floor_db=args.floor_db)
        reports.append(rep)
        flag = "*" if abs(rep.duration_mismatch) > 1.0 / rep.fps else " "
        print(f"{rep.name:<26} {rep.n_frames:>6} {rep.stream_duration:>8.2f} {rep.audio_duration:>7.2f}{flag} "
              f"{fmt(rep.correlation):>7} {rep.best_lag_frames:>+5d} {fmt(rep.best_correlation):>7}")
    print("-" * len(header))
    mean0 = float(np.nanmean([r.correlation for r in reports]))
    mean_best = float(np.nanmean([r.best_correlation for r in reports]))
    mean_lag = float(np.mean([r.best_lag_frames for r in reports]))
    print(f"{'mean (' + str(len(reports)) + ' streams)':<26} {'':>6} {'':>8} {'':>8} {fmt(mean0):>7} "
          f"{mean_lag:>+5.1f} {fmt(mean_best):>7}")
    print(f"* audio and stream lengths differ by more than one frame; "
          f"{time.perf_counter() - t0:.1f} s in all")

    if args.json:
        doc = {
            "folder": str(args.folder), "energy": "linear RMS" if args.linear else "dB",
            "floor_db": args.floor_db, "max_lag": args.max_lag,
            "lag_convention": "positive lag = mouth leads audio",
            "mean_correlation": mean0, "mean_best_correlation": mean_best, "mean_best_lag": mean_lag,
            "streams": [r.to_dict() for r in reports],
        }
        args.json.write_text(json.dumps(doc, indent=2) + "\n")
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
