"""How often a stop's closure is breath noise rather than silence, and how well the text path finds it.

espeak-ng's breathy voice variants (+f2..+f5) fill a stop's closure with breath noise at -50..-36 dBFS, so a
silence threshold alone (:data:`mpeg4fa.speech.closures.SILENCE_DB`) finds no closure and the stop starts
40-55 ms late. The same text in the same language's plain voice has the same phone times and digitally silent
closures: its silence-only closure is the reference. Per voice: stops after a sounding phoneme, and how many
of them start more than 15 ms from the reference's closure with the silence rule alone (``silence``) and with
the breath rule (:func:`mpeg4fa.speech.closures._closure_tail`, ``breath``). Sentences written for this check,
not the lip-sync benchmark's.

    .venv/bin/python tools/closure_breath_check.py [--json tools/closure_breath_check.json]
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.speech import closures  # noqa: E402
from mpeg4fa.speech.markup import parse_markup  # noqa: E402
from mpeg4fa.speech.tts.espeak import EspeakEngine  # noqa: E402
from mpeg4fa.speech.utterance import speak  # noqa: E402
from mpeg4fa.speech.visemes import PAUSE  # noqa: E402

TEXTS = {"en": ["Tuesday the cat kept a pet bat and a top hat at the depot.",
                "Stop by the shop, pick up a cup of soup and keep it hot.",
                "Debbie bought a kite; the dog dug a deep pit by the gate.",
                "Half past eight, the puppy slept in the back of the truck."],
         "de": ["Der Koch packt die Tasche und geht zum Hauptbahnhof.", "Peter tippt acht Texte pro Tag."],
         "fr": ["Le petit chat tape sur la porte du café.", "Pourquoi tu bois ce type de thé ?"],
         "es": ["El gato come tapas de pulpo en la casa.", "Pepe pide una copa de té caliente."]}
VOICES = {"en": ("en-us", ["+f1", "+f2", "+f3", "+f4", "+f5", "+m1", "+m3", "+m7", "+klatt"]),
          "de": ("de", ["+f2", "+f3", "+f4", "+m1"]), "fr": ("fr", ["+f2", "+f4", "+m3"]),
          "es": ("es", ["+f2", "+f3", "+m2"])}
OFF = 0.015
"""A closure farther than this (s) from the plain voice's starts a stop visibly late (over a third of a frame)."""


def _tails(voice: str, lang: str) -> list[tuple[str, float, float]]:
    """(prev-stop phones, silence-only closure, breath-rule closure) for each stop after a sounding phoneme."""
    out = []
    for text in TEXTS[lang]:
        u = speak(parse_markup(text), EspeakEngine(voice, 160), lang=lang, voice=voice)
        x, rate = u.speech.samples.astype(np.float64) / 32768.0, u.speech.rate
        spans = [t for t in u.timings if t.end > t.start]
        for prev, this in zip(spans, spans[1:]):
            if (this.set, this.viseme) not in closures.STOP_VISEMES or prev.viseme == PAUSE:
                continue
            if abs(prev.end - this.start) > 1e-6 or prev.end - prev.start <= closures.KEEP:
                continue
            out.append((f"{prev.phoneme}-{this.phoneme}", closures._silent_tail(x, rate, prev.start, this.start),
                        closures._closure_tail(x, rate, prev.start, this.start)))
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--json", type=Path)
    args = ap.parse_args()
    rows = []
    print(f"{'voice':14s} {'stops':>5s} {'silence off':>11s} {'breath off':>10s} {'breath err ms':>13s}")
    for lang, (plain, variants) in VOICES.items():
        ref = _tails(plain, lang)
        for voice in [plain] + [plain + v for v in variants]:
            got = _tails(voice, lang)
            if [g[0] for g in got] != [r[0] for r in ref]:
                print(f"{voice:14s} phones differ from {plain}: skipped")
                continue
            truth = np.array([r[1] for r in ref])
            silence, breath = np.array([g[1] for g in got]), np.array([g[2] for g in got])
            row = {"voice": voice, "stops": len(got), "silence_off": int((abs(silence - truth) > OFF).sum()),
                   "breath_off": int((abs(breath - truth) > OFF).sum()),
                   "breath_mean_error_ms": float(abs(breath - truth).mean() * 1000)}
            rows.append(row)
            print(f"{voice:14s} {row['stops']:5d} {row['silence_off']:11d} {row['breath_off']:10d} "
                  f"{row['breath_mean_error_ms']:13.1f}", flush=True)
    if args.json:
        args.json.write_text(json.dumps({"drop_db": closures.DROP_DB, "rows": rows}, indent=1) + "\n")


if __name__ == "__main__":
    main()
