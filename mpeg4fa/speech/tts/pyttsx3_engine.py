"""pyttsx3: speech with word boundaries only, like SAPI 5 in the seed design.

The engine runs in a child process (:mod:`._pyttsx3_worker`): pyttsx3 drives the one espeak-ng
instance a process may initialise, which :class:`~.espeak.EspeakEngine` also uses. It returns
the audio and one word event per word the engine reported, at the sample where the word starts;
no phonemes. The encoder times the visemes inside each word by estimate and resynchronises at
every word (:mod:`mpeg4fa.speech.wordsync`).
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
import wave
from pathlib import Path
from typing import Sequence

import numpy as np

from mpeg4fa.speech.errors import TTSError
from mpeg4fa.speech.tts.base import Event, Speech, snap_to_tokens, word_tokens
from mpeg4fa.speech.tts.espeak import check_voice_name

WHERE = "pyttsx3"
TIMEOUT = 120.0  # seconds for one synthesis; espeak makes ~50x real time here


class Pyttsx3Engine:
    """Word-boundary speech from pyttsx3 (espeak-ng driver); voice by name or language code."""

    name = "pyttsx3"

    def __init__(self, voice: str = "en-us", rate: int = 175) -> None:
        self.voice = voice
        self.rate = rate

    def synthesize(self, text: str, *, voice: str | None = None, rate: int | None = None,
                   marks: Sequence[tuple[int, str]] = ()) -> Speech:
        """Speak ``text``; marks are not sent (pyttsx3 reads no SSML): tags take the next word's start."""
        voice = voice or self.voice
        if not text.strip():
            raise TTSError("nothing to say: the text is empty", where=WHERE, hint="pass some words")
        check_voice_name(voice, WHERE)  # the worker's espeak-ng would abort on it
        with tempfile.TemporaryDirectory(prefix="mpeg4fa-pyttsx3-") as tmp:
            wav = Path(tmp) / "speech.wav"
            request = {"text": text, "voice": voice, "rate": int(rate or self.rate), "wav": str(wav)}
            result = _run_worker(request)
            samples, hz = _read_wav(wav)
        tokens = word_tokens(text)
        events: list[Event] = []
        seen: set[int] = set()
        reported = sorted(result["words"], key=lambda w: w[2])
        for (position, _length, sample), k in zip(reported, snap_to_tokens([w[0] for w in reported], tokens)):
            if k < 0 or k in seen:
                continue  # a word the engine split (numbers) keeps its first boundary
            seen.add(k)
            events.append(Event("word", sample / hz, sample / hz, tokens[k][2], tokens[k][0]))
        duration = len(samples) / hz
        ends = [e.start for e in events[1:]] + [duration]
        events = [Event("word", e.start, max(e.start, end), e.text, e.position) for e, end in zip(events, ends)]
        events.append(Event("end", duration, duration, ""))
        return Speech(samples, hz, tuple(events), self.name, voice)


def _run_worker(request: dict) -> dict:
    try:
        done = subprocess.run([sys.executable, "-m", "mpeg4fa.speech.tts._pyttsx3_worker"],
                              input=json.dumps(request), capture_output=True, text=True, timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        raise TTSError(f"pyttsx3 took longer than {TIMEOUT:.0f} s", where=WHERE,
                       hint="split the text into shorter pieces") from None
    lines = done.stdout.strip().splitlines()
    try:
        result = json.loads(lines[-1]) if lines else {}
    except json.JSONDecodeError:
        result = {}
    if "error" in result:
        raise TTSError(result["error"], where=WHERE, hint=result.get("hint", ""))
    if done.returncode != 0 or "words" not in result:
        tail = (done.stderr.strip().splitlines() or ["no output"])[-1]
        raise TTSError(f"the pyttsx3 worker failed (exit {done.returncode}): {tail}", where=WHERE,
                       hint="check that pyttsx3==2.99 and espeakng-loader==0.2.4 are installed")
    return result


def _read_wav(path: Path) -> tuple[np.ndarray, int]:
    try:
        with wave.open(str(path), "rb") as f:
            if f.getsampwidth() != 2 or f.getnchannels() != 1:
                raise TTSError("pyttsx3 wrote a WAV that is not 16-bit mono", where=str(path))
            return np.frombuffer(f.readframes(f.getnframes()), "<i2").astype(np.int16), f.getframerate()
    except (OSError, wave.Error) as exc:
        raise TTSError(f"pyttsx3 wrote no readable audio ({exc})", where=WHERE) from None
