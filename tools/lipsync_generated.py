"""The --generated mode of tools/lipsync_report.py: lip sync figures of encode_text's own speech.

See tools/lipsync_report.py for what each column means. Kept apart so the report's folder mode
needs neither the TTS nor the aligner.
"""
from __future__ import annotations

import json
import platform
import time
import unicodedata
from pathlib import Path

import numpy as np

from mpeg4fa.decoded import resolve
from mpeg4fa.face.model import FaceModel
from mpeg4fa.fba import decode, encode
from mpeg4fa.render.audio import Audio
from mpeg4fa.render.errors import RenderError
from mpeg4fa.render.lipsync import on_frame_grid
from mpeg4fa.render.phonealign import align_phones, aligned_offsets
from mpeg4fa.render.visemesync import SyncFigures, measure_sync, viseme_peaks, viseme_weights
from mpeg4fa.speech.encoder import encode_text, make_engine
from mpeg4fa.speech.markup import parse_markup
from mpeg4fa.speech.utterance import speak

EN_TEXTS = (
    "Peter picked a peck of pickled peppers, and my mother baked bread.",
    "Hello there, my old friend. How are you today?",
    "Please bring the maps back before the boat leaves.",
    "We should meet at the museum by the bridge at five.",
    "The weather will be warm and sunny for most of the week.",
    "Bob bought a big blue bag of apples from the market.",
    "Could you tell me the way to the nearest train station?",
    "She sells sea shells by the sea shore every summer.",
)
ZH_TEXTS = (
    "我们明天去北京看朋友，爸爸妈妈都很高兴。",
    "你好，世界！",
    "今天天气很好，我们去公园散步吧。",
    "请问火车站在哪里？",
    "他每天早上六点起床，然后跑步半个小时。",
    "妈妈买了一本书给我。",
)
FPS = 25.0
HALF_TARGET = 0.90


def _audio(speech) -> Audio:
    return Audio((speech.samples.astype(np.float32) / 32768.0)[:, None], speech.rate)


def _peak_share(text: str, level: str, fps: float) -> np.ndarray:
    """Per viseme, whether its peak is in the first half of its phoneme, on a stream at ``fps``."""
    enc = encode_text(text, level=level, fps=fps)
    stream = decode(encode(enc.stream, enc.coding()))
    spans = enc.utterance.spans()
    times, values = on_frame_grid(stream, resolve(stream))
    return viseme_peaks(viseme_weights(values, times, spans), times, spans).in_first_half


def _label(text: str, width: int) -> str:
    """``text`` cut and padded to ``width`` terminal columns (a hanzi takes two)."""
    out, used = "", 0
    for ch in text:
        w = 2 if unicodedata.east_asian_width(ch) in "WF" else 1
        if used + w > width - 1 and len(text) > len(out) + 1:
            return out + "…" + " " * (width - used - 1)
        out, used = out + ch, used + w
    return out + " " * (width - used)


def _ms(x: float) -> str:
    return "    -" if not np.isfinite(x) else f"{1000 * x:+5.0f}"


def _pct(x: float) -> str:
    return "   -" if not np.isfinite(x) else f"{100 * x:3.0f}%"


def run_generated(json_path: Path, *, level: str = "high", peak_fps: float = 100.0, align: bool = True) -> int:
    t0 = time.perf_counter()
    face = FaceModel.default()
    rows = []
    header = (f"{'text':<22} {'n':>3} {'half':>4} {'half' + str(int(peak_fps)):>7} {'rel':>4} {'off':>5} "
              f"{'lag':>3} {'r0':>5} {'clos':>4} {'in1':>4} {'miss':>4} {'c.off':>5} | "
              f"{'ps n':>4} {'mean':>5} {'p95':>5} {'c.in1':>5} {'es.on':>5} {'es.95':>5} {'sp.on':>5} {'sp.95':>5}")
    print(f"generated speech, level {level}, {FPS:g} fps (times in ms; aligned columns: English, pocketsphinx)")
    print(header)
    print("-" * len(header))
    for lang, texts in (("en", EN_TEXTS), ("zh", ZH_TEXTS)):
        for text in texts:
            enc = encode_text(text, level=level, fps=FPS)
            stream = decode(encode(enc.stream, enc.coding()))
            audio = _audio(enc.speech)
            spans = enc.utterance.spans()
            phones, raw, given = None, None, None
            if lang == "en" and align:
                try:
                    phones = align_phones(audio, text)
                except RenderError as exc:
                    print(f"  (no alignment: {exc})")
                    align = False
            fig = measure_sync(face, stream, audio, spans, name=text, phones=phones)
            if phones is not None:
                espeak_spans = speak(parse_markup(text), make_engine("espeak")).spans()
                raw = aligned_offsets([s.viseme for s in espeak_spans], np.array([s.start for s in espeak_spans]),
                                      np.array([s.start for s in espeak_spans]), phones)
                starts = np.array([s.start for s in spans])
                given = aligned_offsets([s.viseme for s in spans], starts, starts, phones)
            fine = _peak_share(text, level, peak_fps)
            rows.append({"lang": lang, "figures": fig, "fine": fine,
                         "espeak_onsets": raw, "span_onsets": given})
            print(f"{_label(text, 22)} {fig.n_visemes:>3} {_pct(fig.first_half_fraction)} {_pct(fine.mean()):>7} "
                  f"{fig.median_relative_peak:4.2f} {_ms(fig.mean_peak_offset)} {fig.best_lag_frames:>+3d} "
                  f"{fig.correlation:5.2f} {fig.n_closures:>4} {_pct(fig.closures_within_frame)} "
                  f"{fig.closures_missed:>4} {_ms(fig.mean_closure_offset)} | "
                  + (f"{fig.n_aligned:>4} {_ms(fig.aligned_mean_offset)} {_ms(fig.aligned_p95_offset)} "
                     f"{_pct(fig.aligned_closures_within_frame):>5} {_ms(raw.mean)} {_ms(raw.p95)} "
                     f"{_ms(given.mean)} {_ms(given.p95)}" if phones is not None else ""))
    print("-" * len(header))

    summary = {}
    ok = True
    for lang in ("en", "zh"):
        mine = [r for r in rows if r["lang"] == lang]
        figs: list[SyncFigures] = [r["figures"] for r in mine]
        counts = np.array([f.n_visemes for f in figs])
        half = float(np.sum([f.first_half_fraction * n for f, n in zip(figs, counts)]) / counts.sum())
        fine = float(np.concatenate([r["fine"] for r in mine]).mean())
        lags = [f.best_lag_frames for f in figs]
        n_clos = sum(f.n_closures for f in figs)
        clos = float(np.sum([f.closures_within_frame * f.n_closures for f in figs if f.n_closures]) / max(n_clos, 1))
        entry = {"visemes": int(counts.sum()), "first_half": half, f"first_half_{int(peak_fps)}fps": fine,
                 "lags": lags, "closures": n_clos, "closures_within_frame": clos,
                 "closures_missed": sum(f.closures_missed for f in figs),
                 "median_relative_peak": float(np.median([f.median_relative_peak for f in figs])),
                 "mean_peak_offset": float(np.mean([f.mean_peak_offset for f in figs]))}
        checks = [(f"{lang}: peaks in the first half, {FPS:g} fps", half >= HALF_TARGET, f"{100 * half:.1f} %"),
                  (f"{lang}: peaks in the first half, {peak_fps:g} fps", fine >= HALF_TARGET, f"{100 * fine:.1f} %"),
                  (f"{lang}: energy lag 0 +- 1 frame", all(abs(x) <= 1 for x in lags), f"lags {lags}"),
                  (f"{lang}: closures shut within a frame", clos == 1.0 or n_clos == 0,
                   f"{100 * clos:.0f} % of {n_clos}")]
        aligned = [r for r in mine if r["span_onsets"] is not None]
        if aligned:
            offsets = np.concatenate([r["figures"].aligned_offsets for r in aligned])
            entry["aligned"] = {
                "pairs": len(offsets),
                "mean_peak_offset": float(offsets.mean()),
                "p95_peak_offset": float(np.percentile(np.abs(offsets), 95)),
                "closures_within_frame": float(np.nanmean([r["figures"].aligned_closures_within_frame
                                                           for r in aligned])),
                "espeak_onsets_mean": float(np.mean([r["espeak_onsets"].mean for r in aligned])),
                "espeak_onsets_p95_max": float(max(r["espeak_onsets"].p95 for r in aligned)),
                "span_onsets_mean": float(np.mean([r["span_onsets"].mean for r in aligned])),
                "span_onsets_p95_max": float(max(r["span_onsets"].p95 for r in aligned)),
            }
        summary[lang] = entry
        for what, passed, value in checks:
            ok &= passed
            print(f"{'PASS' if passed else 'FAIL'}  {what}: {value}")
        if aligned:
            a = entry["aligned"]
            print(f"      {lang}: viseme peak - aligned onset: mean {1000 * a['mean_peak_offset']:+.0f} ms, "
                  f"p95 {1000 * a['p95_peak_offset']:.0f} ms over {a['pairs']} pairs; closures within a "
                  f"frame of the aligned onset {100 * a['closures_within_frame']:.0f} %; onsets - aligned: espeak "
                  f"events {1000 * a['espeak_onsets_mean']:+.0f} ms (p95 <= {1000 * a['espeak_onsets_p95_max']:.0f}), "
                  f"spans {1000 * a['span_onsets_mean']:+.0f} ms (p95 <= {1000 * a['span_onsets_p95_max']:.0f})")
    print(f"{time.perf_counter() - t0:.1f} s in all")
    json_path.parent.mkdir(parents=True, exist_ok=True)
    json_path.write_text(json.dumps({
        "python": platform.python_version(), "fps": FPS, "peak_fps": peak_fps, "level": level,
        "lag_convention": "positive lag = mouth leads audio", "summary": summary,
        "utterances": [{"lang": r["lang"], **r["figures"].to_dict()} for r in rows],
    }, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    print(f"wrote {json_path}")
    return 0 if ok else 1
