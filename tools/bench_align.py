"""Alignment accuracy and cost: espeak-ng speech with known phoneme times as the 'recording'.

Each sentence is spoken by a voice and at a rate other than the aligner's reference (en-us, 175 wpm),
then aligned back from its transcript with pocketsphinx and with DTW (its reference re-spoken at the
rate that matches the recording's length, and at the plain 175 wpm). The truth is the recording's own
phoneme events; the aligned phones are paired with them by name, in order (difflib), per sentence,
and an onset counts as right within 30 ms. Cost: audio seconds aligned per wall second (x real time,
espeak-ng's reference rendering included). Prints a table; --json writes the figures.

    .venv/bin/python tools/bench_align.py [--json align.json] [--quick]
"""
from __future__ import annotations

import argparse
import difflib
import json
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.speech.align import Recording, align_recording  # noqa: E402
from mpeg4fa.speech.tts.espeak import EspeakEngine  # noqa: E402

SENTENCES = [
    "Peter picked a peck of pickled peppers, and my mother baked bread.",
    "Please bring the maps back before the boat leaves.",
    "The quick brown fox jumps over the lazy dog.",
    "She sells sea shells by the sea shore, while the children watch.",
    "How much wood would a woodchuck chuck if a woodchuck could chuck wood?",
    "We were away a year ago, in the old house on the hill.",
]
CASES = [("en-gb", 140), ("en-gb", 210), ("en-us+f3", 140), ("en-us+f3", 210)]
TOLERANCE = 0.030


def recording(text: str, voice: str, rate: int):
    speech = EspeakEngine().synthesize(text, voice=voice, rate=rate)
    return Recording(speech.samples, speech.rate, f"{voice}@{rate}"), speech


def onset_errors(aligned, truth) -> tuple[np.ndarray, int]:
    """|aligned - true| onset of each phone paired by name in order; and the number of true phones."""
    a = [p for p in aligned.phonemes() if not p.text.startswith("_")]
    t = [p for p in truth.phonemes() if not p.text.startswith("_")]
    sm = difflib.SequenceMatcher(None, [p.text for p in a], [p.text for p in t], autojunk=False)
    errors = [abs(a[blk.a + k].start - t[blk.b + k].start) for blk in sm.get_matching_blocks() for k in range(blk.size)]
    return np.array(errors), len(t)


def run_case(voice: str, rate: int, method: str, ref_rate: int | None, sentences: list[str]) -> dict:
    errors, paired, total, audio, spent = [], 0, 0, 0.0, 0.0
    for text in sentences:
        rec, truth = recording(text, voice, rate)
        t0 = time.perf_counter()
        al = align_recording(rec, text, lang="en", method=method, rate=ref_rate)
        spent += time.perf_counter() - t0
        audio += rec.duration
        e, n = onset_errors(al.utterance.speech, truth)
        errors.append(e)
        paired += len(e)
        total += n
    e = np.concatenate(errors)
    return {"voice": voice, "rate": rate, "method": method, "reference_rate": ref_rate or "matched",
            "within_30ms": float((e <= TOLERANCE).mean()), "mean_ms": float(e.mean() * 1000),
            "p90_ms": float(np.percentile(e, 90) * 1000), "paired": paired, "phones": total,
            "x_real_time": audio / spent, "align_s": spent, "audio_s": audio}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", type=Path, help="write the rows here")
    parser.add_argument("--quick", action="store_true", help="two sentences only")
    args = parser.parse_args(argv)
    sentences = SENTENCES[:2] if args.quick else SENTENCES
    rows = []
    print(f"{len(sentences)} sentences; reference en-us; onset right within {TOLERANCE * 1000:.0f} ms")
    print(f"{'voice':<10} {'rate':>4}  {'aligner':<13} {'ref wpm':>7}  {'<=30ms':>6}  {'mean':>6}  {'p90':>6}  "
          f"{'paired':>11}  {'x real time':>11}")
    for voice, rate in CASES:
        for method, ref_rate in (("pocketsphinx", None), ("dtw", None), ("dtw", 175)):
            r = run_case(voice, rate, method, ref_rate, sentences)
            rows.append(r)
            print(f"{voice:<10} {rate:>4}  {method:<13} {str(r['reference_rate']):>7}  {100 * r['within_30ms']:5.1f}%  "
                  f"{r['mean_ms']:4.0f}ms  {r['p90_ms']:4.0f}ms  {r['paired']:>4}/{r['phones']:<6}  "
                  f"{r['x_real_time']:11.1f}", flush=True)
    if args.json:
        args.json.write_text(json.dumps(rows, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
