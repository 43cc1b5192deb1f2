"""What cutting a short recording in two costs the lip sync (issue 28): clips heard whole (:func:`listen`) against
the same clips heard as ``encode`` and ``say`` hear them (:func:`stream_listened`: a clip of 4 s or more cut in two at
the pause nearest its middle, the halves heard at once, the first pair judged together).

Clips of three sentences one after another (10-12 s): espeak-ng's English sentences of tools/bench_lipsync_audio.py
(each spoken by a fresh process, the text path's timings the reference), festival's voices when installed (their own
segments the truth, tools/bench_lipsync_festival.py) and, with ``--human DIR``, the LibriVox recordings one and two
at a time (the transcript's forced alignment the reference). Scored as there: closures (p, b, m) within 40 ms,
closures shown farther than 100 ms from any (extra), frame agreement. ``--halves-alone``: each half keeps its own
judgement of ``either`` (the rule before the pair was judged together), to measure what judging together does.

    .venv/bin/python tools/bench_lipsync_cut.py [--json out.json] [--human DIR] [--voices slt,kal,ked]
        [--no-espeak] [--halves-alone]
"""
from __future__ import annotations

import argparse
import io
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

import festival_speech  # noqa: E402
from bench_lipsync_audio import MORE, RATE, SPEECH, _score, _sum  # noqa: E402
from bench_lipsync_festival import truth_timings  # noqa: E402
from espeak_fresh import spoken  # noqa: E402

from mpeg4fa.speech.align import Recording, align_recording, read_recording  # noqa: E402
from mpeg4fa.speech.encoder import phones  # noqa: E402
from mpeg4fa.speech.listen import listen  # noqa: E402
from mpeg4fa.speech.listen import stream  # noqa: E402
from mpeg4fa.speech.utterance import Timing  # noqa: E402


def heard_cut(rec: Recording) -> tuple[list[Timing], int]:
    """The timings ``encode`` writes for ``rec`` (English, auto), and how many blocks it heard."""
    out, timings = io.BytesIO(), io.StringIO()
    heard = stream.stream_listened(stream.Source("clip", rec.rate, rec.duration, iter([rec.samples])), out,
                                   timings=timings, lang="en", level="low")
    items = json.loads(timings.getvalue())
    return [Timing(i["phoneme"], i["viseme"], i["start"], i["end"]) for i in items], heard.blocks


def espeak_clips():
    items = SPEECH["en"] + MORE["en"]
    for k in range(0, len(items) - 1, 2):
        parts, ref, offset = [], [], 0.0
        for voice, text in items[k:k + 3]:
            utt = phones(spoken(text, lang="en", voice=voice, rate=RATE))
            parts.append(utt.speech.samples)
            ref += [t.shifted(offset) for t in utt.timings]
            offset += utt.speech.duration
        yield "espeak-ng", Recording(np.concatenate(parts), utt.speech.rate, f"espeak {k}"), ref


def festival_clips(voices: list[str]):
    texts = [t for _, t in SPEECH["en"]] + list(dict.fromkeys(t for _, t in MORE["en"]))
    for voice in voices:
        for k in range(0, len(texts) - 1, 2):
            parts, truth, offset = [], [], 0.0
            for text in texts[k:k + 3]:
                samples, rate, segments = festival_speech.speak(text, voice)
                parts.append(samples)
                truth += [(name, a + offset, b + offset) for name, a, b in segments]
                offset += len(samples) / rate
            x = np.clip(np.rint(np.concatenate(parts) * 32768), -32768, 32767).astype(np.int16)
            yield f"festival {voice}", Recording(x, rate, f"{voice} {k}"), truth_timings(truth)


def human_clips(folder: Path):
    wavs = sorted(folder.glob("*.wav"))
    recs = [read_recording(w) for w in wavs]
    texts = [w.with_suffix(".txt").read_text(encoding="utf-8").strip() for w in wavs]
    for i in range(len(wavs)):
        for picked in ([i], [i, (i + 1) % len(wavs)]):
            rec = Recording(np.concatenate([recs[j].samples for j in picked]), recs[i].rate, "librivox")
            if rec.duration < stream.SPLIT_SECONDS:
                continue
            ref = phones(align_recording(rec, " ".join(texts[j] for j in picked), lang="en").utterance).timings
            yield "LibriVox", rec, ref


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--json", type=Path, help="write the figures here")
    ap.add_argument("--human", type=Path, metavar="DIR", help="also the LibriVox NAME.wav + NAME.txt recordings")
    ap.add_argument("--voices", default="slt,kal,ked", help="festival voices (when festival is installed)")
    ap.add_argument("--no-espeak", action="store_true", help="leave espeak-ng's clips out")
    ap.add_argument("--halves-alone", action="store_true", help="each half keeps its own judgement of either")
    args = ap.parse_args()
    if args.halves_alone:
        stream._heard_as = lambda rec, heard, how, lang: heard
    sources = [] if args.no_espeak else [espeak_clips()]
    if festival_speech.available() is None and args.voices:
        sources.append(festival_clips(args.voices.split(",")))
    if args.human is not None:
        sources.append(human_clips(args.human))
    per: dict[str, dict[str, list]] = {}
    for clips in sources:
        for name, rec, ref in clips:
            whole = phones(listen(rec, lang="en").utterance).timings
            cut, blocks = heard_cut(rec)
            rows = per.setdefault(name, {"whole": [], "cut": [], "blocks": []})
            rows["whole"].append(_score(ref, whole, rec.duration))
            rows["cut"].append(_score(ref, cut, rec.duration))
            rows["blocks"].append(blocks)
            print(f"{rec.name:<14} {rec.duration:6.2f} s  blocks {blocks}  within 40 ms: whole "
                  f"{rows['whole'][-1]['hits']}/{rows['whole'][-1]['closures']}, cut {rows['cut'][-1]['hits']}", flush=True)
    print(f"\n{'source':<14} {'clips':>5} {'cut':>4} {'PP':>4} {'whole <=40ms':>12} {'cut <=40ms':>10} "
          f"{'whole prec':>10} {'cut prec':>8} {'whole agree':>11} {'cut agree':>9}")
    figures = []
    for name, rows in per.items():
        whole, cut = _sum(rows["whole"]), _sum(rows["cut"])
        figures.append({"source": name, "clips": len(rows["blocks"]), "cut_in_two": sum(b == 2 for b in rows["blocks"]),
                        "halves_alone": args.halves_alone, "whole": whole, "cut": cut})
        print(f"{name:<14} {len(rows['blocks']):>5} {figures[-1]['cut_in_two']:>4} {whole['closures']:>4} "
              f"{whole['within_40ms']:>12.1%} {cut['within_40ms']:>10.1%} {whole['precision']:>10.1%} "
              f"{cut['precision']:>8.1%} {whole['frame_agreement']:>11.1%} {cut['frame_agreement']:>9.1%}")
    if args.json is not None:
        args.json.write_text(json.dumps(figures, indent=1) + "\n", encoding="utf-8")
        print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
