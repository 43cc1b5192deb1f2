#!/usr/bin/env python
"""Benchmark of the text encoder (mpeg4fa.speech): speed and bit rate of streams made from speech.

A script run on demand, not a test::

    .venv/bin/python tools/bench_encoder.py [--seconds 60] [--json OUT] [--engine espeak] [--before OLD.json]

1. per sentence (issue 14): each of the English sentences (``ENGLISH``: 3-10 s each, some with
   expression tags, some without, among them the sentence visage|SDK's encoder wrote at 18.3
   bits/frame) and the Chinese ones (``CHINESE``) encoded on its own at the high level at 25 fps,
   with the encoder's coding options for text (``TEXT_CODING``): bits per frame, mean and range.
   ``--before OLD.json`` (this script's JSON from an earlier version of the encoder) adds a
   before/after table;
2. speed, for about ``--seconds`` of English and of Chinese speech (the sentences cycled): TTS
   time, the rest of the encoder (visemes, timeline, FAP stream, bitstream) and the whole, each as
   x real time (audio seconds per wall second);
3. size of that long speech: bits per frame and kbit/s at the high level (FAP 1 + FAP 2; Chinese
   visemes go out as low-level FAPs, see mpeg4fa.speech.encoder), the low level (every moving FAP
   3-68) and the low level restricted to the lip, jaw and brow groups (2, 4, 8), each with
   ``TEXT_CODING`` and with the codec's plain defaults;
4. per language (issue 16): two sentences in each of the espeak-ng languages of ``LANGUAGES`` (the
   IPA route: visemes from articulatory features, ``spec/ipa_*.csv``), English and Mandarin on their
   tables for comparison, each encoded on its own at the high level: bits per frame (mean over the
   sentences and pooled), and for English the share of frames where the IPA route shows the viseme
   the English table does (the reference; ``mpeg4fa.speech.ipa.english_agreement``, on ``ENGLISH``);
5. alignment (issue 16, ``mpeg4fa.speech.align``): each sentence spoken by espeak-ng in another voice
   and at another rate (``ALIGN_VOICE``/``ALIGN_RATE``) stands in for a recording, and is aligned back
   from its transcript: seconds taken (espeak-ng's reference rendering included) as x real time, and
   the share of phone onsets within 30 ms of the recording's own (tools/bench_align.py has the full
   accuracy table). ``--align-only`` runs just this section; ``--sentences-only`` just section 1.

6. long text (issue 26 item 2, ``--long-only``): 10 kB, 200 kB and 1 MB of ordinary English (``ENGLISH``
   without its tags, shuffled into paragraphs by a fixed seed; ``--long-tags`` keeps the tags),
   each encoded in a child process by :func:`mpeg4fa.speech.pipeline.encode_text_to` (the streaming
   path of ``mpeg4fa encode TEXT``) with the WAV and the timings: seconds of speech, wall time, x real
   time and the child's peak RSS (its ``ru_maxrss``, as ``/usr/bin/time -v`` reports). Targets: peak
   RSS < 500 MB for 1 MB of text, >= 20 x real time (``LONG_SIZES``, ``TARGET_LONG_RSS_MB``,
   ``TARGET_LONG_SPEED``).

Targets: English high level <= 17 bits/frame on average over the sentences (issue 14; issue 5's
target was <= 30 on the long speech); low-level lip, jaw and brow FAPs <= 60 bits/frame
(< 1.5 kbit/s). It prints tables, marks targets PASS/FAIL and writes JSON (``bench_encoder.json``
unless ``--json``).
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
from mpeg4fa.decoded import resolve  # noqa: E402
from mpeg4fa.spec import FAP_GROUP  # noqa: E402
from mpeg4fa.speech.encoder import TEXT_CODING, encode_text, make_engine  # noqa: E402

FPS = 25.0
TARGET_SENTENCES = 17.0
"""English high level, mean bits/frame over ``ENGLISH`` each encoded on its own (issue 14)."""
TARGET_HIGH = 30.0
"""English high level on the long speech (issue 5): kept as a note, it is no longer the goal."""
TARGET_LIPS = 60.0
TARGET_AGREEMENT = 0.90
"""English through the IPA route vs the English table: share of frames with the same viseme (issue 16)."""
LIP_JAW_BROW_GROUPS = (2, 4, 8)

ENGLISH = [
    "Would you want me to tell you the latest info about hotels and book reservations?",  # visage: 18.3
    "(joy, 30, 0.6) Good morning, and welcome to the central station on this bright spring day.",
    "The next train to the harbour leaves from platform four in about ten minutes.",
    "(surprise, 35, 0.3) Oh, the bridge is closed today because of the strong wind!",
    "(joy, 0, 0.5) Please take the bus from the main square instead, it leaves every ten minutes.",
    "It stops near the old market, the museum and the public library.",
    "(sadness, 25, 0.8) We are very sorry for the trouble this may cause on your journey today.",
    "(joy, 40, 0.5) Tickets for the evening concert are still available at the front desk.",
    "Remember to keep your bags with you, and have a pleasant trip.",
    "My grandmother grew tomatoes, beans and sweet peppers behind her little yellow house.",
    "Could you send me the report by Friday afternoon, so that I can read it over the weekend?",
    "The library opens at nine in the morning and closes at half past six in the evening.",
    "When the rain finally stopped, the children ran outside to jump in every puddle they could find.",
    "A cup of hot tea and a good book make a cold winter evening feel much shorter.",
    "Turn left at the second traffic light, then follow the river until you see the blue bridge.",
    "(fear, 30, 0.4) Did you hear that noise coming from the basement just now?",
    "The weather forecast says it will be sunny tomorrow, with a light breeze from the west.",
    "(anger, 35, 0.5) I have asked you three times to close the door behind you!",
    "Our team finished the project two weeks early, and the client was very pleased with it.",
    "Please switch off your phone before the film starts, and enjoy the show.",
    "(joy, 45, 0.4) Congratulations on your new job, we are all so proud of you! (joy, 0, 1) Now, let us "
    "talk about the details.",
    "The museum shows paintings, old maps and a large collection of coins from many countries.",
    "He packed a sandwich, an apple and a bottle of water for the long walk over the hills.",
    "(disgust, 30, 0.5) This soup has been sitting in the fridge for far too long, please throw it away.",
    "If you need any help with the new software, just call the support line at any time.",
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


LANGUAGES = {
    "en": ("English (table)", ENGLISH[:2]),
    "zh": ("Mandarin (pinyin table)", CHINESE[:2]),
    "es": ("Spanish", ["El perro de mi vecino come pan y bebe agua todas las mañanas.",
                       "(joy, 30, 0.5) Mañana vamos a la playa con toda la familia."]),
    "fr": ("French", ["Le petit garçon a vu une lune rouge au-dessus du pont.",
                      "(surprise, 35, 0.3) Nous partons demain matin pour Paris!"]),
    "de": ("German", ["Der kleine Junge möchte heute über die Brücke gehen.",
                      "(joy, 30, 0.5) Wir fahren morgen früh mit dem Zug nach Berlin."]),
    "it": ("Italian", ["Il ragazzo mangia una buona pizza con gli amici.",
                       "(joy, 30, 0.5) Domani andiamo al mare con tutta la famiglia."]),
    "pt": ("Portuguese", ["O menino comeu pão com manteiga e bebeu um copo de leite.",
                          "(joy, 30, 0.5) Amanhã vamos à praia com toda a família."]),
    "ru": ("Russian", ["Мальчик пошёл в школу утром и купил хлеб.",
                       "(joy, 30, 0.5) Завтра мы поедем на море всей семьёй."]),
    "ja": ("Japanese (kana)", ["こんにちは、きょうはとてもいいてんきですね。",
                               "(joy, 30, 0.5) あしたはかぞくでうみにいきます。"]),
    "hi": ("Hindi", ["मेरा नाम राम है और मैं दिल्ली में रहता हूँ।",
                     "(joy, 30, 0.5) कल हम पूरे परिवार के साथ समुद्र जाएंगे।"]),
    "ar": ("Arabic", ["ذهب الولد إلى المدرسة في الصباح.",
                      "(joy, 30, 0.5) غدا نذهب إلى البحر مع العائلة."]),
    "yue": ("Cantonese", ["我哋今日去飲茶，好開心。", "(joy, 30, 0.5) 聽日我哋一家人去海邊。"]),
}
"""Language code -> (label, sentences) for the per-language table (``en`` and ``zh``: the reference tables)."""


def bench_languages(engine_name: str) -> list[dict]:
    """Each language's sentences encoded on their own at the high level: bits per frame; English also
    through the IPA route, against the English table frame by frame."""
    from mpeg4fa.speech.ipa import english_agreement
    from mpeg4fa.speech.markup import parse_markup

    engine = make_engine(engine_name)
    out = []
    for code, (label, sentences) in LANGUAGES.items():
        rows = []
        for text in sentences:
            enc = encode_text(text, engine=engine, lang=code, level="high", fps=FPS)
            data = encode(enc.stream, enc.coding())
            rows.append({"text": text, "audio_s": enc.speech.duration, "frames": len(enc.stream),
                         "bits": len(data) * 8, "bits_per_frame": len(data) * 8 / len(enc.stream)})
        entry = {"code": code, "language": label, "sentences": rows,
                 "mean": float(np.mean([r["bits_per_frame"] for r in rows])),
                 "pooled": sum(r["bits"] for r in rows) / sum(r["frames"] for r in rows),
                 "audio_s": sum(r["audio_s"] for r in rows)}
        if code == "en" and getattr(engine, "speaks_ipa", False):
            share, frames = english_agreement(engine, [parse_markup(text).text for text in ENGLISH], FPS)
            entry["ipa_agreement"] = {"share": share, "frames": frames}
        out.append(entry)
    return out


def _language_table(results: list[dict]) -> bool:
    """The per-language table; True when the IPA route agrees with the English table on >= 90 % of frames."""
    print("| language | code | sentences | audio s | mean bits/frame | pooled | note |")
    print("|---|---|---|---|---|---|---|")
    ok = True
    for r in results:
        note = ""
        if "ipa_agreement" in r:
            share = r["ipa_agreement"]["share"]
            ok = share >= TARGET_AGREEMENT
            note = (f"IPA route = English table on {share:.1%} of {r['ipa_agreement']['frames']} frames "
                    f"(>= {TARGET_AGREEMENT:.0%} {'PASS' if ok else 'FAIL'})")
        print(f"| {r['language']} | {r['code']} | {len(r['sentences'])} | {r['audio_s']:.1f} | {r['mean']:.1f} | "
              f"{r['pooled']:.1f} | {note} |")
    return ok


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


def bench_sentences(name: str, sentences: list[str], engine_name: str) -> dict:
    """Each sentence encoded on its own at the high level: bits per frame with the text coding, and
    where they go (:func:`bit_budget`)."""
    engine = make_engine(engine_name)
    rows, budget, frames = [], {}, 0
    for text in sentences:
        enc = encode_text(text, engine=engine, level="high", fps=FPS)
        data = encode(enc.stream, enc.coding())
        n = len(enc.stream)
        floor = fap1_floor(data)
        rows.append({"text": text, "audio_s": enc.speech.duration, "frames": n, "bits": len(data) * 8,
                     "bits_per_frame": len(data) * 8 / n, "tagged": bool(enc.utterance.cues),
                     "floor_bits_per_frame": floor / n})
        for key, bits in bit_budget(data).items():
            budget[key] = budget.get(key, 0) + bits
        frames += n
    per = np.array([r["bits_per_frame"] for r in rows])
    return {"language": name, "sentences": rows, "mean": float(per.mean()), "min": float(per.min()),
            "max": float(per.max()), "floor_mean": float(np.mean([r["floor_bits_per_frame"] for r in rows])),
            "pooled": sum(r["bits"] for r in rows) / sum(r["frames"] for r in rows),
            "budget_bits_per_frame": {k: v / frames for k, v in sorted(budget.items(), key=lambda kv: -kv[1])}}


def fap1_floor(data: bytes) -> float:
    """Bits of the stream with its FAP 1 P symbols priced at their own empirical entropy (each field
    under the best static model for this very sentence, sent for free) instead of what the adaptive
    models spend on them; every other element (headers, flushes, skips, FAP 2, intra planes) as
    coded. The same symbols cannot cost less under any order-0 code, and the decoder's models start
    uniform at each intra frame: a floor for this stream's choices of FAP 1 fields."""
    from collections import Counter

    from mpeg4fa.fba.trace import trace

    rest, fields = 0.0, None
    for e in trace(data):
        if e.kind == "segment" and e.name.startswith("FAP 1") and not e.intra:
            rest += 2  # the flush: a segment takes its doublings plus 2 bits
            fields = fields or [Counter() for _ in e.symbols]
            for counter, symbol in zip(fields, e.symbols):
                counter[symbol] += 1
        else:
            rest += e.width
    for counter in fields or []:
        total = sum(counter.values())
        rest -= sum(c * np.log2(c / total) for c in counter.values())
    return rest


def bit_budget(data: bytes) -> dict[str, int]:
    """Bits of a stream by syntax element (from the decoder's own trace): intra planes as one item,
    P-plane segments by what they code, fixed fields by name."""
    from mpeg4fa.fba.trace import trace

    elements = list(trace(data))
    intra = {e.frame for e in elements if e.name == "is_intra" and e.value == 1}
    out: dict[str, int] = {}
    for e in elements:
        if e.frame in intra:
            key = "intra planes (headers, ranges, intra segments)"
        elif e.kind == "segment":
            key = e.name.split(" segment")[0] + " segment (P)"
        elif e.frame is None:
            key = "object start and end codes"
        else:
            key = e.name
        out[key] = out.get(key, 0) + e.width
    return out


def _sentence_tables(results: list[dict], before: dict | None) -> bool:
    """Per-sentence tables; True when the English mean meets its target."""
    old = {}
    if before is not None:
        old = {row["text"]: row for r in before.get("sentences", []) for row in r["sentences"]}
    print("| language | sentences | audio s (min-max) | mean bits/frame | range | pooled | floor (FAP 1 at entropy) "
          "| target |")
    print("|---|---|---|---|---|---|---|---|")
    ok = True
    for r in results:
        audio = [row["audio_s"] for row in r["sentences"]]
        verdict = ""
        if r["language"] == "English":
            ok = r["mean"] <= TARGET_SENTENCES
            verdict = f"<= {TARGET_SENTENCES:g} {'PASS' if ok else 'FAIL'}"
        print(f"| {r['language']} | {len(audio)} | {min(audio):.1f}-{max(audio):.1f} | {r['mean']:.1f} | "
              f"{r['min']:.1f}-{r['max']:.1f} | {r['pooled']:.1f} | {r['floor_mean']:.1f} | {verdict} |")
    print("\n| language | sentence | tags | audio s | bits/frame | floor" + (" | before | change |" if old else " |"))
    print("|---|---|---|---|---|---|" + ("---|---|" if old else ""))
    for r in results:
        for row in r["sentences"]:
            line = (f"| {r['language']} | {row['text'][:48]} | {'yes' if row['tagged'] else 'no'} | "
                    f"{row['audio_s']:.2f} | {row['bits_per_frame']:.1f} | {row['floor_bits_per_frame']:.1f} |")
            if old:
                was = old.get(row["text"])
                line += (f" {was['bits_per_frame']:.1f} | {row['bits_per_frame'] / was['bits_per_frame'] - 1:+.0%} |"
                         if was else " n/a | |")
            print(line)
    print("\n| language | where the bits go (high level, all sentences) | bits/frame |")
    print("|---|---|---|")
    for r in results:
        for key, value in r["budget_bits_per_frame"].items():
            if value >= 0.05:
                print(f"| {r['language']} | {key} | {value:.2f} |")
    if old:
        print("\n| language | before: mean (range) | after: mean (range) |")
        print("|---|---|---|")
        for r in results:
            prev = next((b for b in before["sentences"] if b["language"] == r["language"]), None)
            if prev:
                print(f"| {r['language']} | {prev['mean']:.1f} ({prev['min']:.1f}-{prev['max']:.1f}) | "
                      f"{r['mean']:.1f} ({r['min']:.1f}-{r['max']:.1f}) |")
    return ok


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


ALIGN_VARIANT = "+f3"
"""The 'recording' voice of section 5: the language's voice (cmn for Mandarin) as espeak-ng's female
variant f3, at ``ALIGN_RATE``; the reference is the male voice at 175 wpm."""
ALIGN_RATE = 150


def bench_alignment() -> list[dict]:
    """Section 5: alignment cost and accuracy per language (English: pocketsphinx and DTW; others: DTW)."""
    import difflib

    from mpeg4fa.speech.align import Recording, align_recording
    from mpeg4fa.speech.markup import parse_markup
    from mpeg4fa.speech.tts.espeak import EspeakEngine

    engine = EspeakEngine()
    rows = []
    cases = [("en", "pocketsphinx"), ("en", "dtw")] + [(code, "dtw") for code in LANGUAGES if code != "en"]
    for code, method in cases:
        label, sentences = ("English", ENGLISH) if code == "en" else LANGUAGES[code]
        voice = {"en": "en-us", "zh": "cmn"}.get(code, code) + ALIGN_VARIANT
        audio = spent = 0.0
        errors, used = [], set()
        for text in sentences:
            plain = parse_markup(text).text
            truth = engine.synthesize(plain, voice=voice, rate=ALIGN_RATE, ipa=code not in ("en", "zh"))
            rec = Recording(truth.samples, truth.rate, f"{voice}@{ALIGN_RATE}")
            t0 = time.perf_counter()
            try:
                al = align_recording(rec, text, lang=code, method=method)
            except Exception as exc:  # noqa: BLE001 - a sentence pocketsphinx cannot take (digits): noted
                used.add(f"skipped: {exc.__class__.__name__}")
                continue
            spent += time.perf_counter() - t0
            audio += rec.duration
            used.add(al.method)
            a = [p for p in al.utterance.speech.phonemes() if not p.text.startswith("_")]
            t = [p for p in truth.phonemes() if not p.text.startswith("_")]
            sm = difflib.SequenceMatcher(None, [p.text for p in a], [p.text for p in t], autojunk=False)
            errors += [abs(a[b.a + k].start - t[b.b + k].start) for b in sm.get_matching_blocks() for k in range(b.size)]
        e = np.array(errors)
        rows.append({"language": label, "code": code, "method": method, "voice": voice, "rate": ALIGN_RATE,
                     "audio_s": audio, "align_s": spent, "x_realtime": audio / spent if spent else 0.0,
                     "within_30ms": float((e <= 0.030).mean()) if len(e) else None, "paired": len(e),
                     "used": sorted(used)})
    return rows


def _alignment_table(rows: list[dict]) -> None:
    print(f"\nAlignment (a 'recording' in another voice at {ALIGN_RATE} wpm, aligned back from its transcript; "
          "reference en-us or the language's voice):\n")
    print("| language | aligner | voice | audio s | align s | x real time | onsets within 30 ms |")
    print("|---|---|---|---|---|---|---|")
    for r in rows:
        share = f"{100 * r['within_30ms']:.1f} % of {r['paired']}" if r["within_30ms"] is not None else "n/a"
        print(f"| {r['language']} | {r['method']} | {r['voice']} | {r['audio_s']:.1f} | {r['align_s']:.2f} | "
              f"{r['x_realtime']:.0f} | {share} |")


def os_cpus() -> int:
    import os
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


LONG_SIZES = {"10 kB": 10_000, "200 kB": 200_000, "1 MB": 1_000_000}
TARGET_LONG_RSS_MB = 500.0
TARGET_LONG_SPEED = 20.0

def long_english(size: int, tags: bool = False, seed: int = 26) -> str:
    """About ``size`` characters of English prose from ``ENGLISH`` (tags removed unless ``tags``), sentences
    drawn by a fixed seed into paragraphs of five: ordinary text, not random letters."""
    import random
    import re

    rng = random.Random(seed)
    pattern = re.compile(r"\(\s*\w+\s*,[^)]*\)\s*")
    sentences = ENGLISH if tags else [pattern.sub("", s) for s in ENGLISH]
    paragraphs, length = [], 0
    while length < size:
        paragraph = " ".join(rng.choice(sentences) for _ in range(5))
        paragraphs.append(paragraph)
        length += len(paragraph) + 2
    return "\n\n".join(paragraphs)[:size].rstrip()


def _long_child(size: int, tags: bool, folder: Path, engine: str) -> None:
    """Run in a child process: encode the text to files and print what was spoken as JSON."""
    from mpeg4fa.speech.pipeline import encode_text_to

    text = long_english(size, tags)
    spoken = encode_text_to(text, folder / "long.fba", audio=folder / "long.wav" if engine != "estimate" else None,
                            timings=folder / "long.json", engine=engine)
    print(json.dumps({"chars": len(text), "seconds": spoken.seconds, "frames": spoken.frames, "bytes": spoken.bytes,
                      "chunks": spoken.chunks, "encode_wall_s": spoken.wall}))


def bench_long(engine: str, tags: bool, sizes: dict[str, int] = LONG_SIZES) -> list[dict]:
    """Section 6: each size in a child process; wall time and peak RSS of the whole child."""
    import os
    import subprocess
    import tempfile

    rows = []
    for label, size in sizes.items():
        with tempfile.TemporaryDirectory() as folder:
            started = time.perf_counter()
            child = subprocess.Popen([sys.executable, __file__, "--long-child", str(size), "--long-folder", folder,
                                      "--engine", engine] + (["--long-tags"] if tags else []),
                                     stdout=subprocess.PIPE, text=True)
            out = child.stdout.read()
            _, status, usage = os.wait4(child.pid, 0)
            wall = time.perf_counter() - started
            child.returncode = os.waitstatus_to_exitcode(status)
            if child.returncode:
                raise SystemExit(f"{label}: the child failed with status {child.returncode}")
            row = {"size": label, **json.loads(out.strip().splitlines()[-1]), "wall_s": wall,
                   "peak_rss_mb": usage.ru_maxrss / 1024, "cpu_s": usage.ru_utime + usage.ru_stime, "tags": tags,
                   "engine": engine}
            row["x_realtime"] = row["seconds"] / wall
            row["x_realtime_per_cpu_s"] = row["seconds"] / max(row["cpu_s"], 1e-9)
            rows.append(row)
            print(f"  {label}: {row['seconds']:.0f} s of speech in {wall:.1f} s, {row['peak_rss_mb']:.0f} MB",
                  file=sys.stderr)
    return rows


def _long_table(rows: list[dict]) -> bool:
    print("\n| text | characters | chunks | speech s | speech h | wall s | x real time | CPU s | x real time per CPU s "
          "| peak RSS MB | target |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    ok = True
    for r in rows:
        passed = r["x_realtime"] >= TARGET_LONG_SPEED and (r["size"] != "1 MB" or r["peak_rss_mb"] < TARGET_LONG_RSS_MB)
        ok &= passed
        print(f"| {r['size']}{' (tagged)' if r['tags'] else ''} | {r['chars']:,} | {r['chunks']} | {r['seconds']:.0f} | "
              f"{r['seconds'] / 3600:.2f} | {r['wall_s']:.1f} | {r['x_realtime']:.0f} | {r['cpu_s']:.1f} | "
              f"{r['x_realtime_per_cpu_s']:.0f} | {r['peak_rss_mb']:.0f} | "
              f"{'PASS' if passed else 'FAIL'} |")
    print(f"\ntargets: >= {TARGET_LONG_SPEED:g} x real time; peak RSS < {TARGET_LONG_RSS_MB:g} MB for 1 MB of text")
    return ok


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="speech length per language (default 60)")
    ap.add_argument("--engine", default="espeak", help="espeak (default), pyttsx3 or estimate")
    ap.add_argument("--json", type=Path, default=Path("bench_encoder.json"))
    ap.add_argument("--before", type=Path, help="this script's JSON from an earlier encoder: a before/after table")
    ap.add_argument("--align-only", action="store_true", help="only section 5, the alignment cost")
    ap.add_argument("--sentences-only", action="store_true",
                    help="only section 1, bits per frame of each sentence (issue 14's target; about 10 s)")
    ap.add_argument("--long-only", action="store_true",
                    help="only section 6: 10 kB, 200 kB and 1 MB of text through the streaming encoder (minutes)")
    ap.add_argument("--long-tags", action="store_true", help="section 6 with the sentences' expression tags kept")
    ap.add_argument("--long-sizes", help="section 6's sizes, comma-separated labels of " + ", ".join(LONG_SIZES))
    ap.add_argument("--long-child", type=int, help=argparse.SUPPRESS)
    ap.add_argument("--long-folder", type=Path, help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.long_child is not None:
        _long_child(args.long_child, args.long_tags, args.long_folder, args.engine)
        return 0
    if args.long_only:
        sizes = {k: LONG_SIZES[k.strip()] for k in args.long_sizes.split(",")} if args.long_sizes else LONG_SIZES
        rows = bench_long(args.engine, args.long_tags, sizes)
        print(f"mpeg4fa {MPEG4FA_VERSION}, {platform.python_implementation()} {platform.python_version()}, "
              f"{platform.machine()}, {os_cpus()} CPUs, engine {args.engine}, {FPS:g} fps, high level")
        ok = _long_table(rows)
        args.json.write_text(json.dumps({"version": MPEG4FA_VERSION, "engine": args.engine, "long_text": rows,
                                         "targets_met": ok}, indent=1))
        print(f"\nwrote {args.json}")
        return 0
    if args.align_only:
        alignment = bench_alignment()
        _alignment_table(alignment)
        args.json.write_text(json.dumps({"version": MPEG4FA_VERSION, "alignment": alignment}, indent=1))
        print(f"\nwrote {args.json}")
        return 0
    before = json.loads(args.before.read_text()) if args.before else None

    sentences = [bench_sentences("English", ENGLISH, args.engine), bench_sentences("Chinese", CHINESE, args.engine)]
    if args.sentences_only:
        print(f"mpeg4fa {MPEG4FA_VERSION}, engine {args.engine}, {FPS:g} fps, coding for text: {TEXT_CODING}\n")
        ok = _sentence_tables(sentences, before)
        args.json.write_text(json.dumps({"version": MPEG4FA_VERSION, "engine": args.engine, "fps": FPS,
                                         "text_coding": TEXT_CODING, "sentences": sentences, "targets_met": ok},
                                        indent=1))
        print(f"\nwrote {args.json}")
        return 0

    results = [bench_language("English", ENGLISH, args.seconds, args.engine),
               bench_language("Chinese", CHINESE, args.seconds, args.engine)]
    languages = bench_languages(args.engine) if args.engine == "espeak" else []
    print(f"mpeg4fa {MPEG4FA_VERSION}, {platform.python_implementation()} {platform.python_version()}, "
          f"{platform.machine()}, engine {args.engine}, {FPS:g} fps, coding for text: {TEXT_CODING}\n")
    ok = _sentence_tables(sentences, before)
    print()
    print("| language | level | audio s | TTS s | encoder s | x real time (no TTS) | x real time (with TTS) |")
    print("|---|---|---|---|---|---|---|")
    for r in results:
        for level in ("high", "low"):
            x = r[level]
            print(f"| {r['language']} | {level} | {x['audio_s']:.1f} | {x['tts_s']:.2f} | {x['encoder_s']:.2f} | "
                  f"{x['x_realtime_without_tts']:.0f} | {x['x_realtime_with_tts']:.0f} |")
    print("\n| language | stream | coding | bits/frame | kbit/s | target |")
    print("|---|---|---|---|---|---|")
    for r in results:
        for key, target in (("high", TARGET_HIGH), ("low", None), ("low_lips", TARGET_LIPS)):
            for coding, s in r[key]["sizes"].items():
                verdict = ""
                if target is not None and coding == "text coding":
                    passed = s["bits_per_frame"] <= target
                    if key == "high":  # issue 5's target, a note now
                        verdict = f"(was <= {target:g}: {'met' if passed else 'not met'})"
                    else:
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
    if languages:
        print("\nPer language (high level, each sentence on its own; visemes from IPA features except en, zh):\n")
        ok &= _language_table(languages)
    alignment = bench_alignment() if args.engine == "espeak" else []
    if alignment:
        _alignment_table(alignment)
    args.json.write_text(json.dumps({"version": MPEG4FA_VERSION, "engine": args.engine, "fps": FPS,
                                     "text_coding": TEXT_CODING, "sentences": sentences, "results": results,
                                     "languages": languages, "alignment": alignment, "targets_met": ok},
                                    indent=1))
    print(f"\nwrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
