"""Speech from festival (a second synthesiser beside espeak-ng) with its own segment times, for the lip-sync
tools: tools/bench_lipsync_festival.py scores the audio-only track on it, against a truth espeak-ng did not make.

festival is not a dependency of mpeg4fa: ``apt install festival festvox-kallpc16k festvox-kdlpc16k
festvox-hi-nsk festvox-us-slt-hts``. Diphone voices (kal, ked: American men; NSK: a Hindi man) splice
recordings of a person, so their closures are a person's; the HTS voice (slt, an American woman) is
statistical parametric speech learned from one.
"""
from __future__ import annotations

import shutil
import subprocess
import tempfile
import wave
from pathlib import Path

import numpy as np

VOICES = {"kal": "kal_diphone", "ked": "ked_diphone", "nsk": "hindi_NSK_diphone", "slt": "cmu_us_slt_arctic_hts"}
"""Short name -> festival voice (``voice_<name>``)."""
CLOSING = frozenset({"p", "b", "m", "ph", "bh"})
"""festival's phones that shut the lips (its English radio set and the Hindi NSK voice's)."""


def available() -> str | None:
    """None when festival can run, else what to install."""
    if shutil.which("festival") is None:
        return "festival is not installed: apt install festival festvox-kallpc16k festvox-kdlpc16k festvox-hi-nsk " \
               "festvox-us-slt-hts"
    return None


def speak(text: str, voice: str, stretch: float = 1.0) -> tuple[np.ndarray, int, list[tuple[str, float, float]]]:
    """``text`` spoken by festival's ``voice`` (a key of :data:`VOICES`), durations times ``stretch`` ->
    (samples in [-1, 1], rate, segments: phone, start, end in s)."""
    quoted = text.replace("\\", " ").replace('"', " ")
    with tempfile.TemporaryDirectory() as tmp:
        wav, segs, script = Path(tmp) / "s.wav", Path(tmp) / "s.segs", Path(tmp) / "s.scm"
        script.write_text(f"(voice_{VOICES[voice]})\n(Parameter.set 'Duration_Stretch {stretch:.3f})\n"
                          f'(set! utt (utt.synth (Utterance Text "{quoted}")))\n'
                          f'(utt.save.wave utt "{wav}" \'riff)\n(utt.save.segs utt "{segs}")\n', encoding="utf-8")
        subprocess.run(["festival", "-b", str(script)], check=True, capture_output=True, timeout=120)
        with wave.open(str(wav)) as w:
            rate = w.getframerate()
            samples = np.frombuffer(w.readframes(w.getnframes()), dtype="<i2").astype(np.float64) / 32768.0
        out, start = [], 0.0
        for line in segs.read_text(encoding="utf-8").splitlines():
            parts = line.split()
            if len(parts) == 3 and parts[0] != "#":
                out.append((parts[2], start, float(parts[0])))
                start = float(parts[0])
    return samples, rate, out


def closure_spans(segments: list[tuple[str, float, float]]) -> list[tuple[float, float]]:
    """The segments that shut the lips (:data:`CLOSING`), as (start, end)."""
    return [(a, b) for name, a, b in segments if name in CLOSING and b > a]
