#!/usr/bin/env python3
"""Benchmark live lip sync (:class:`mpeg4fa.speech.live.LiveLipSync`): a long WAV fed in 20 ms chunks.

    nice -n 5 .venv/bin/python tools/bench_live.py [--seconds 300] [--mode both|realtime|fast]
                                                   [--wav FILE] [--json tools/bench_live.json]

The WAV (unless ``--wav``): espeak-ng sentences in four voices and three rates, joined with pauses of
0.4-2.0 s (seeded), to ``--seconds`` of audio (default 5 minutes), 16 kHz mono, written to a temporary
file and read back with the package's WAV reader. Speech onsets are measured on the audio (a 10 ms frame
louder than -45 dBFS after at least 300 ms quieter), not taken from espeak-ng's events.

* **realtime**: chunk ``k`` is handed over at ``t0 + (k + 1) x 20 ms`` on the monotonic clock (when a
  microphone would have delivered it) and no earlier; a chunk whose time has passed goes at once. Per
  chunk: processing time (wall and the thread's CPU time, ``feed``; on a shared machine the wall time
  includes waiting for a core: the load average is recorded), and the backlog (how late the hand-over was: it grows if
  the stream falls behind). CPU share: process time over wall time.
* **fast**: the chunks fed back to back, for the throughput (x real time); ``+fba``: each feed's frames
  also coded as the server sends them (:class:`~mpeg4fa.speech.live.LiveEncoder`; realtime always codes).
* **quality**: the live track's visemes against the text path's for the same speech (espeak-ng's own
  phonemes through the English table), and the recording path's (``speech.listen``, phones recognised
  from the whole file at once) against the same: what deciding in 320 ms windows costs.
* **latency**: for each speech onset, the delay from the hand-over of the chunk holding the onset to the
  return of the ``feed`` that first gave a frame with the lips or jaw moved (a frame within 300 ms
  before the onset or later). Realtime mode: wall-clock; both modes also give it in audio time (the
  audio fed by then, minus the onset), which is what a listener sees when processing keeps up.
* **rest**: sounds that are not speech, fed in 20 ms chunks (``--rest-seconds`` each, default 8): silence,
  white noise at -30 dBFS and the synthetic music of :mod:`mpeg4fa.speech.listen.signals` (plucked melody,
  chords, hi-hat; -18 dBFS); the share of frames with the lips and jaw at rest (all of :data:`LIPS` zero), and
  when the mouth last moved. ``--mode rest`` runs these rows alone and keeps the JSON's other results.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mpeg4fa.spec import FAP_BY_NAME  # noqa: E402
from mpeg4fa.speech.align.recording import frame_levels, resample  # noqa: E402
from mpeg4fa.speech.live import LATENCY, LiveEncoder, LiveLipSync  # noqa: E402
from mpeg4fa.wav import write_pcm16  # noqa: E402
from mpeg4fa.wavread import read_wav  # noqa: E402

RATE = 16000
CHUNK = 0.02
FPS = 25.0
SENTENCES = [
    "Hello there, how are you today?", "Maybe Bob will bring a map to the meeting.",
    "The quick brown fox jumps over the lazy dog.", "Please call me back before five o'clock.",
    "We were away a year ago, in the old house on the hill.", "Open wide and say ah.",
    "She sells sea shells by the sea shore.", "My mother baked bread for the whole family.",
    "Peter picked a peck of pickled peppers.", "What time does the next train leave?",
    "I think it will rain tomorrow, so bring an umbrella.", "Thank you very much for your help.",
]
VOICES = [("en-us", 175), ("en-gb", 150), ("en-us+f3", 200), ("en-gb-scotland", 160)]
LIPS = [FAP_BY_NAME[n].number - 1 for n in (
    "open_jaw", "lower_t_midlip", "raise_b_midlip", "stretch_l_cornerlip", "stretch_r_cornerlip",
    "lower_t_lip_lm", "lower_t_lip_rm", "raise_b_lip_lm", "raise_b_lip_rm", "push_b_lip", "push_t_lip")]


def make_wav(path: Path, seconds: float, seed: int = 0) -> list:
    """espeak-ng sentences with seeded pauses, at least ``seconds`` long, as a 16 kHz WAV; returns the text
    path's visemes of it (espeak-ng's phonemes through the English table, as Timings on the WAV's time)."""
    from mpeg4fa.speech.tts.espeak import EspeakEngine
    from mpeg4fa.speech.utterance import Timing
    from mpeg4fa.speech.visemes import english_visemes

    engine, rng = EspeakEngine(), np.random.default_rng(seed)
    cache: dict = {}
    parts, total, k, truth = [np.zeros(int(0.8 * RATE))], 0.8, 0, []
    while total < seconds:
        text, (voice, wpm) = SENTENCES[k % len(SENTENCES)], VOICES[(k // len(SENTENCES)) % len(VOICES)]
        if (text, voice, wpm) not in cache:
            speech = engine.synthesize(text, voice=voice, rate=wpm)
            cache[text, voice, wpm] = (resample(speech.samples / 32768.0, speech.rate, RATE),
                                       english_visemes(list(speech.phonemes())))
        audio, visemes = cache[text, voice, wpm]
        truth += [Timing(e.text, v, total + e.start, total + e.end) for v, e in visemes if e.end > e.start]
        pause = np.zeros(int(rng.uniform(0.4, 2.0) * RATE))
        parts += [audio, pause]
        total += (len(audio) + len(pause)) / RATE
        k += 1
    x = np.concatenate(parts)[:int(seconds * RATE)]
    write_pcm16(path, np.clip(np.rint(x * 32767), -32768, 32767).astype(np.int16), RATE)
    return [t for t in truth if t.end <= seconds]


def quality(pcm: np.ndarray, truth: list) -> dict:
    """The live track's visemes against the text path's (espeak-ng's own phonemes), beside the recording
    path's phone recognition of the whole file at once (speech.listen, phonetic): per-frame agreement and
    closure onsets within 40 ms (speech.listen.compare)."""
    from mpeg4fa.speech.align.recording import Recording
    from mpeg4fa.speech.listen import listen
    from mpeg4fa.speech.listen.compare import agreement, onset_score

    live = LiveLipSync(RATE, FPS, keep_spans=True)
    step = int(CHUNK * RATE)
    for k in range(0, len(pcm), step):
        live.feed(pcm[k:k + step])
    live.flush()
    whole = listen(Recording(pcm, RATE, "bench"), recognizer="phonetic").utterance.timings
    duration = len(pcm) / RATE
    out = {}
    for name, timings in (("live", live.timings), ("whole_file", list(whole))):
        share, frames = agreement(truth, timings, duration)
        onsets = onset_score(truth, timings)
        out[name] = {"agreement": share, "frames": frames, "closures": onsets.reference,
                     "closures_within_40ms": onsets.share, "closure_mean_error_ms": 1e3 * onsets.mean_error,
                     "extra_closures": onsets.extra}
    return out


def onsets(pcm: np.ndarray) -> list[float]:
    """Speech onsets (s): a 10 ms frame above -45 dBFS after at least 300 ms below it."""
    loud = frame_levels(pcm / 32768.0, RATE) > -45
    out, quiet = [], 30
    for k, v in enumerate(loud):
        if v and quiet >= 30:
            out.append(k * 0.01)
        quiet = 0 if v else quiet + 1
    return out


def run(pcm: np.ndarray, realtime: bool, coded: bool = False) -> dict:
    live = LiveLipSync(RATE, FPS)
    coder = LiveEncoder(FPS) if coded else None
    step = int(CHUNK * RATE)
    n = -(-len(pcm) // step)
    proc, cpu_chunk, late, moved_at = np.zeros(n), np.zeros(n), np.zeros(n), []  # moved_at: (chunk, first moving frame time) per feed
    emitted = 0
    load0, cpu0, t0 = os.getloadavg()[0], time.process_time(), time.monotonic()
    for k in range(n):
        due = t0 + (k + 1) * CHUNK
        if realtime:
            wait = due - time.monotonic()
            if wait > 0:
                time.sleep(wait)
            late[k] = max(0.0, time.monotonic() - due)
        a, c = time.monotonic(), time.thread_time()
        frames = live.feed(pcm[k * step:(k + 1) * step])
        if coder is not None and len(frames):
            coder.encode(frames)
        proc[k], cpu_chunk[k] = time.monotonic() - a, time.thread_time() - c
        if len(frames):
            move = np.flatnonzero(np.abs(frames[:, LIPS]).max(axis=1) > 0)
            for i in move:
                moved_at.append((k, (emitted + i) / FPS, proc[k] + late[k]))
            emitted += len(frames)
    live.flush()
    wall, cpu = time.monotonic() - t0, time.process_time() - cpu0
    lat_audio, lat_wall = [], []
    for onset in onsets(pcm):
        first = next(((k, t, d) for k, t, d in moved_at if t >= onset - 0.3), None)
        if first is None:
            continue
        k, _, handed = first
        onset_chunk = int(onset / CHUNK)  # handed over at (onset_chunk + 1) x CHUNK
        lat_audio.append((k + 1) * CHUNK - onset)
        lat_wall.append((k - onset_chunk) * CHUNK + handed + (onset_chunk + 1) * CHUNK - onset)
    third = n // 3
    return {"mode": ("realtime" if realtime else "fast") + ("+fba" if coded else ""), "audio_s": len(pcm) / RATE, "chunks": n, "wall_s": wall,
            "x_realtime": len(pcm) / RATE / wall, "cpu_share": cpu / wall, "cpu_per_audio_s": cpu / (len(pcm) / RATE),
            "chunk_ms": {"mean": 1e3 * proc.mean(), "p99": 1e3 * float(np.percentile(proc, 99)),
                         "max": 1e3 * proc.max(), "over_20ms": int((proc > CHUNK).sum())},
            "chunk_cpu_ms": {"mean": 1e3 * cpu_chunk.mean(), "p99": 1e3 * float(np.percentile(cpu_chunk, 99)),
                             "max": 1e3 * cpu_chunk.max(), "over_20ms": int((cpu_chunk > CHUNK).sum())},
            "load_average": [load0, os.getloadavg()[0]],
            "backlog_ms": {"max": 1e3 * late.max(), "mean_first_third": 1e3 * late[:third].mean(),
                           "mean_last_third": 1e3 * late[-third:].mean()} if realtime else None,
            "onsets": len(onsets(pcm)), "onsets_seen": len(lat_audio),
            "latency_audio_ms": _stats(lat_audio), "latency_wall_ms": _stats(lat_wall) if realtime else None}


def rest(seconds: float) -> list[dict]:
    """Silence, white noise at -30 dBFS and synthetic music through the live path in 20 ms chunks: the share
    of frames whose lips and jaw are at rest (the mouth should not move for what is not speech)."""
    from mpeg4fa.speech.listen.signals import music, white_noise

    sounds = {"silence": np.zeros(int(seconds * RATE)), "noise -30 dBFS": white_noise(seconds, RATE, -30.0),
              "music -18 dBFS": music(seconds, RATE)}
    step = int(CHUNK * RATE)
    rows = []
    for name, x in sounds.items():
        pcm = np.clip(np.rint(x * 32767), -32768, 32767).astype(np.int16)
        live = LiveLipSync(RATE, FPS)
        frames = [live.feed(pcm[k:k + step]) for k in range(0, len(pcm), step)] + [live.flush()]
        frames = np.concatenate([f for f in frames if len(f)])
        moved = np.abs(frames[:, LIPS]).max(axis=1) > 0
        rows.append({"sound": name, "seconds": len(pcm) / RATE, "frames": len(frames),
                     "at_rest": float(1 - moved.mean()), "frames_moved": int(moved.sum()),
                     "last_move_s": float(np.flatnonzero(moved)[-1] / FPS) if moved.any() else None})
    return rows


def print_rest(rows: list[dict]) -> None:
    print(f"\n{'not speech, 20 ms chunks':<26} {'frames':>6} {'at rest':>8} {'moved':>6} {'last move s':>12}")
    for r in rows:
        last = "-" if r["last_move_s"] is None else f"{r['last_move_s']:.2f}"
        print(f"{r['sound']:<26} {r['frames']:6d} {r['at_rest']:8.1%} {r['frames_moved']:6d} {last:>12}")


def _stats(xs: list[float]) -> dict:
    a = 1e3 * np.asarray(xs) if xs else np.zeros(1)
    return {"mean": float(a.mean()), "median": float(np.median(a)), "p95": float(np.percentile(a, 95)),
            "max": float(a.max()), "within_200ms": float((a <= 200).mean())}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--seconds", type=float, default=300.0)
    p.add_argument("--mode", choices=("both", "realtime", "fast", "rest"), default="both",
                   help="fast: as fast as possible, without and with FBA coding; realtime: a real-time clock, "
                        "with FBA coding as the server does; both: all three; rest: only the rows for silence, "
                        "noise and music (every mode runs them), the JSON's other results kept")
    p.add_argument("--rest-seconds", type=float, default=8.0, help="seconds of each sound of the rest rows")
    p.add_argument("--wav", type=Path)
    p.add_argument("--json", type=Path, default=ROOT / "tools" / "bench_live.json")
    args = p.parse_args()
    rows = rest(args.rest_seconds)
    print_rest(rows)
    if args.mode == "rest":
        out = json.loads(args.json.read_text()) if args.json.exists() else {}
        args.json.write_text(json.dumps({**out, "rest": rows, "rest_date": time.strftime("%Y-%m-%d")}, indent=1) + "\n")
        print(f"wrote {args.json} (rest rows; the other results kept)")
        return
    truth = None
    with tempfile.TemporaryDirectory() as tmp:
        wav = args.wav or Path(tmp) / "live.wav"
        if args.wav is None:
            truth = make_wav(wav, args.seconds)
        pcm, rate = read_wav(wav)
    if rate != RATE:
        pcm = np.clip(np.rint(resample(pcm / 32768.0, rate, RATE) * 32767), -32768, 32767).astype(np.int16)
    modes = {"both": ((False, False), (False, True), (True, True)), "fast": ((False, False), (False, True)),
             "realtime": ((True, True),)}[args.mode]
    results = [run(pcm, realtime, coded) for realtime, coded in modes]
    print(f"live lip sync, {len(pcm) / RATE:.0f} s of espeak-ng speech in 20 ms chunks, latency {LATENCY * 1e3:.0f} ms")
    print(f"{'mode':<13} {'x rt':>6} {'cpu':>5} {'chunk wall mean/p99/max ms':>26} {'>20ms':>5} "
          f"{'chunk cpu mean/p99/max ms':>26} {'>20ms':>5} "
          f"{'backlog max/first/last ms':>26} {'onsets':>7} {'move after onset ms (audio) mean/p95/max':>40} "
          f"{'wall mean/p95/max':>18}")
    for r in results:
        c, b, la, lw = r["chunk_ms"], r["backlog_ms"], r["latency_audio_ms"], r["latency_wall_ms"]
        print(f"{r['mode']:<13} {r['x_realtime']:6.1f} {r['cpu_share']:5.0%} "
              f"{c['mean']:12.2f}/{c['p99']:6.2f}/{c['max']:6.2f} {c['over_20ms']:5d} "
              f"{r['chunk_cpu_ms']['mean']:12.2f}/{r['chunk_cpu_ms']['p99']:6.2f}/{r['chunk_cpu_ms']['max']:6.2f} "
              f"{r['chunk_cpu_ms']['over_20ms']:5d} "
              + (f"{b['max']:10.1f}/{b['mean_first_third']:6.2f}/{b['mean_last_third']:6.2f}" if b else f"{'-':>26}")
              + f" {r['onsets_seen']:3d}/{r['onsets']:<3d} {la['mean']:22.0f}/{la['p95']:4.0f}/{la['max']:4.0f}"
              + (f" {lw['mean']:8.0f}/{lw['p95']:4.0f}/{lw['max']:4.0f}" if lw else f" {'-':>18}")
              + f"  load {r['load_average'][0]:.1f}-{r['load_average'][1]:.1f}")
    scores = quality(pcm, truth) if truth is not None else None
    if scores:
        print(f"\n{'visemes vs the text path':<26} {'agree':>6} {'closures <=40ms':>16} {'mean err ms':>12} {'extra':>6}")
        for name, q in scores.items():
            print(f"{name:<26} {q['agreement']:6.1%} {q['closures_within_40ms']:16.1%} "
                  f"{q['closure_mean_error_ms']:12.1f} {q['extra_closures']:6d}   ({q['closures']} closures)")
    out = {"latency_setting_ms": LATENCY * 1e3, "chunk_ms": CHUNK * 1e3, "fps": FPS, "results": results,
           "quality": scores, "rest": rows, "rest_date": time.strftime("%Y-%m-%d"),
           "machine": {"python": platform.python_version(), "cpus": __import__("os").cpu_count()}}
    args.json.write_text(json.dumps(out, indent=1) + "\n")
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
