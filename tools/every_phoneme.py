#!/usr/bin/env python
"""Every phoneme has a mouth, measured: the whole CMU word list on the English voices, and every voice's sample.

A script run on demand, not a test (``tests/speech/test_every_phoneme.py`` checks a fixed sample)::

    .venv/bin/python tools/every_phoneme.py [--voices en-us,en-gb] [--chunk 500] [--json every_phoneme.json]

1. English words: every headword of the CMU dictionary pocketsphinx ships (126,052 words), ``--chunk`` words
   a synthesis, on each of ``--voices`` (mnemonic events, :func:`mpeg4fa.speech.visemes.english_visemes`):
   words, phonemes, distinct mnemonics, how many phonemes the English table maps, how many go by their IPA
   (``spec/english_ipa.csv``), how many were guessed (the warning's count), failures, seconds;
2. every installed voice's sample (``tests/speech/data/voice_samples.csv``) through
   :func:`mpeg4fa.speech.utterance.speak`: spoken, refused (the voice's dictionary is not installed) or
   failed, and guessed phonemes.

It prints a table and writes JSON; exit status 1 if anything failed or was guessed.
"""
from __future__ import annotations

import argparse
import csv
import json
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLES = ROOT / "tests" / "speech" / "data" / "voice_samples.csv"


def cmu_words() -> list[str]:
    import pocketsphinx

    path = Path(pocketsphinx.__file__).parent / "model" / "en-us" / "cmudict-en-us.dict"
    with path.open(encoding="utf-8") as handle:
        return [line.split(" ", 1)[0] for line in handle if line.strip() and "(" not in line.split(" ", 1)[0]]


def english(engine, voice: str, words: list[str], chunk: int) -> dict:
    from mpeg4fa.speech.ipa import phoneme_fallbacks
    from mpeg4fa.speech.visemes import english_table, english_visemes

    table = english_table()
    counts = {"phonemes": 0, "table": 0, "ipa": 0, "failures": 0}
    mnemonics: set[str] = set()
    started = time.perf_counter()
    with phoneme_fallbacks(voice) as log:
        for k in range(0, len(words), chunk):
            try:
                phonemes = [p for p in engine.synthesize(" ".join(words[k:k + chunk]), voice=voice).phonemes()
                            if not p.text.startswith("_")]
                english_visemes(phonemes)
            except Exception as exc:  # noqa: BLE001 - counted and shown, the run goes on
                counts["failures"] += 1
                print(f"{voice} words {k}..{k + chunk}: {type(exc).__name__}: {exc}", file=sys.stderr)
                continue
            for p in phonemes:
                bare = p.text.lstrip("',")
                mnemonics.add(bare)
                counts["phonemes"] += 1
                counts["table" if bare in table else "ipa"] += 1
    return {"voice": voice, "words": len(words), **counts, "guessed": len(log),
            "mnemonics": len(mnemonics), "beyond_table": sorted(mnemonics - set(table)),
            "seconds": round(time.perf_counter() - started, 2)}


def every_voice(engine) -> list[dict]:
    from mpeg4fa.speech.errors import TTSError
    from mpeg4fa.speech.ipa import phoneme_fallbacks
    from mpeg4fa.speech.markup import parse_markup
    from mpeg4fa.speech.tts.espeak import voices
    from mpeg4fa.speech.utterance import speak

    with SAMPLES.open(encoding="utf-8", newline="") as handle:
        rows = {r["voice"]: r["text"] for r in csv.DictReader(handle)}
    out = []
    for v in voices():
        text = rows.get(v.identifier, "")
        text = rows.get(text, text) if text.startswith("@") else text
        entry = {"voice": v.identifier, "language": v.language, "result": "spoken", "guessed": 0, "phonemes": 0}
        if not text:
            entry["result"] = "no sample"
        else:
            try:
                with phoneme_fallbacks(v.identifier) as log:
                    said = speak(parse_markup(text), engine, lang=v.language, voice=v.identifier)
                entry["guessed"] = len(log)
                entry["phonemes"] = len(said.timings)
            except TTSError as exc:
                entry["result"] = f"refused: {exc}"
            except Exception as exc:  # noqa: BLE001
                entry["result"] = f"FAILED: {type(exc).__name__}: {exc}"
        out.append(entry)
    return out


def main(argv: list[str] | None = None) -> int:
    import warnings

    from mpeg4fa.speech.tts.espeak import EspeakEngine

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--voices", default="en-us,en-gb", help="English voices for the word list")
    parser.add_argument("--chunk", type=int, default=500, help="words a synthesis")
    parser.add_argument("--json", type=Path, default=Path("every_phoneme.json"))
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")  # the counts say it; one warning per voice would only repeat them
    engine = EspeakEngine()
    words = cmu_words()
    rows = [english(engine, voice, words, args.chunk) for voice in args.voices.split(",")]
    print(f"{'voice':<16}{'words':>8}{'phonemes':>10}{'table':>9}{'by IPA':>8}{'guessed':>8}{'failed':>7}"
          f"{'seconds':>9}  mnemonics beyond the table")
    for r in rows:
        print(f"{r['voice']:<16}{r['words']:>8}{r['phonemes']:>10}{r['table']:>9}{r['ipa']:>8}{r['guessed']:>8}"
              f"{r['failures']:>7}{r['seconds']:>9}  {' '.join(r['beyond_table'])}")
    spoken = every_voice(engine)
    tally: dict[str, int] = {}
    for s in spoken:
        tally[s["result"].split(":")[0]] = tally.get(s["result"].split(":")[0], 0) + 1
    guessed = sum(s["guessed"] for s in spoken)
    print(f"voices: {len(spoken)}: " + ", ".join(f"{k} {n}" for k, n in sorted(tally.items()))
          + f"; phonemes guessed {guessed}")
    for s in spoken:
        if s["result"] != "spoken" or s["guessed"]:
            print(f"  {s['voice']}: {s['result']} (guessed {s['guessed']})")
    args.json.write_text(json.dumps({"english": rows, "voices": spoken}, ensure_ascii=False, indent=1), "utf-8")
    print(f"wrote {args.json}")
    bad = any(r["failures"] or r["guessed"] for r in rows) or guessed or tally.get("FAILED", 0)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
