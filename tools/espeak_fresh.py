"""espeak-ng speech that is the same every run: each synthesis in a process that has synthesised nothing before.

espeak-ng keeps state from one synthesis to the next inside a process (its pitch flutter and the voice variant
last set, among others): the same text, voice and rate come out up to ~150 samples longer or shorter, so a bench
or a test that speaks several sentences scored them on different audio each run, depending on what was spoken
before (the lip-sync figures moved by a closure or two). ``espeak_ng_SetRandSeed`` and a fresh
``espeak_Initialize`` do not reset that state; a fresh process does. And the voice variants with breath noise
(``+f2``, ``+f3``...) draw it from a generator espeak-ng seeds with the time at start-up: their samples differ
from one second to the next, even in a fresh process, unless ``espeak_ng_SetRandSeed`` is called after
``espeak_Initialize``.

So :func:`spoken` runs the transcript path's :func:`~mpeg4fa.speech.utterance.speak` in a new Python process a
sentence (~0.2 s each), espeak-ng's random seed set to :data:`SEED` first, and takes its utterance back pickled
(measured 2026-12-06: the same bytes for all 74 sentences of tools/bench_lipsync_audio.py, run after run).
Used by tools/bench_lipsync_audio.py and the listen tests.
"""
from __future__ import annotations

import json
import os
import pickle
import subprocess
import sys
from pathlib import Path

from mpeg4fa.speech.utterance import Utterance

ROOT = Path(__file__).resolve().parents[1]
SEED = 0
"""espeak-ng's random seed (breath noise of the voice variants)."""
CHILD = """
import ctypes, json, pickle, sys
from mpeg4fa.speech.markup import parse_markup
from mpeg4fa.speech.tts import espeak
from mpeg4fa.speech.tts.espeak import EspeakEngine
from mpeg4fa.speech.utterance import speak
with espeak._lock:
    lib = espeak._load()
lib.espeak_ng_SetRandSeed.argtypes = [ctypes.c_long]
a = json.loads(sys.argv[1])
lib.espeak_ng_SetRandSeed(a["seed"])
utt = speak(parse_markup(a["text"]), EspeakEngine(), lang=a["lang"], voice=a["voice"], rate=a["rate"])
sys.stdout.buffer.write(pickle.dumps(utt))
"""


def spoken(text: str, *, lang: str = "en", voice: str | None = None, rate: int = 160) -> Utterance:
    """:func:`~mpeg4fa.speech.utterance.speak` of ``text`` as a fresh process speaks it: the same samples and
    phone times every call, whatever was spoken before. RuntimeError with the child's error when it fails."""
    args = json.dumps({"text": text, "lang": lang, "voice": voice, "rate": rate, "seed": SEED})
    env = {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    done = subprocess.run([sys.executable, "-c", CHILD, args], capture_output=True, env=env, check=False)
    if done.returncode != 0:
        raise RuntimeError(f"espeak-ng in a fresh process failed on {text[:40]!r}: "
                           f"{done.stderr.decode('utf-8', 'replace').strip().splitlines()[-1:]}")
    return pickle.loads(done.stdout)
