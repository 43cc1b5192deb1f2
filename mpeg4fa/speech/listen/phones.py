"""Phone recognition without words: pocketsphinx's phone loop (``allphone``, the bundled en-us
acoustic model and phone trigram) names the phones it hears, with times; each phone's ARPAbet name is
read as IPA (``spec/arpabet_ipa.csv``) and mapped to a viseme by its articulatory features
(:mod:`mpeg4fa.speech.ipa`, the map the text path uses for every language but English and Mandarin).

The acoustic model is English, but the shapes of the mouth follow the sounds, not the words: a /p/ or
/m/ in Spanish or Arabic is heard as P or M, an open vowel as AA, whatever the language.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from mpeg4fa.spec._load import read_table
from mpeg4fa.speech.align.recording import HOP, Recording
from mpeg4fa.speech.tts.base import Event
from mpeg4fa.speech.utterance import Timing
from mpeg4fa.speech.visemes import PAUSE

SILENCE = "SIL"
"""pocketsphinx's silence phone; its fillers (``+NSN+``, ``+SPN+``, ``+BREATH+``...) are no speech either."""
LANGUAGE_WEIGHT = 0.5
"""Weight of the phone trigram against the acoustics (pocketsphinx's ``-lw``, 6.5 by default). The
trigram is English phonotactics; at 6.5 it talks the decoder out of what it hears (p b m heard as other
phones or silence). Measured by hand on 13 espeak-ng sentences in six languages with the measures of
tools/bench_lipsync_audio.py (2026-12-05): closure onsets within 40 ms, English 4/25 at 6.5, 12/25 at 2, 15/25 at 1, 16/25 at
0.5; per-frame agreement 0.26 -> 0.50; the other languages alike. Context-dependent phones
(``allphone_ci`` off) found 18/25 but ran slower than real time; batch CMN and vocal-tract warping
(``warp_params`` 0.8-1.1) changed nothing beyond a closure or two either way."""


@dataclass(frozen=True)
class Phone:
    """One recognised phone: its ARPAbet name (``SIL`` for silence), start and end in seconds."""

    name: str
    start: float
    end: float

    @property
    def speech(self) -> bool:
        """Whether it is a phone (not silence or a filler such as ``+NSN+``)."""
        return self.name != SILENCE and not self.name.startswith("+")


@lru_cache(maxsize=1)
def arpabet_ipa() -> dict[str, str]:
    """ARPAbet phone -> IPA (``spec/arpabet_ipa.csv``)."""
    return {r["arpabet"]: r["ipa"] for r in read_table("arpabet_ipa.csv", "arpabet,ipa,example")}


@lru_cache(maxsize=1)
def phone_decoder():
    """pocketsphinx searching the bundled phone trigram (no words), weighted by :data:`LANGUAGE_WEIGHT`."""
    from pathlib import Path

    from mpeg4fa.extras import require

    require("align", "pocketsphinx")
    from pocketsphinx import Decoder, get_model_path

    from mpeg4fa.speech.align.sphinx import RATE

    phone_lm = Path(get_model_path()) / "en-us" / "en-us-phone.lm.bin"
    return Decoder(samprate=RATE, allphone=str(phone_lm), bestpath=False, loglevel="FATAL", lw=LANGUAGE_WEIGHT)


def decode_pcm(decoder, pcm: bytes) -> list:
    """One utterance through ``decoder``, from the state a fresh decoder has: its segments (empty where it finds no
    path). Without ``reinit_feat`` the front end carries state from the last utterance, so that the same block
    heard after other audio gave other phones and times: a block's result depended on what the process had heard
    before it (the order of blocks, one process or two)."""
    decoder.reinit_feat()
    decoder.start_utt()
    decoder.process_raw(pcm, full_utt=True)
    decoder.end_utt()
    return list(decoder.seg()) if decoder.hyp() is not None else []


def recognize_phones(recording: Recording, *, offset: float = 0.0, closures: bool = True) -> list[Phone]:
    """The phones pocketsphinx's phone loop hears in ``recording`` (any rate: resampled to 16 kHz), each
    with its time in seconds (plus ``offset``), silences included as ``SIL``; with ``closures``, p, b and m
    placed and added by the closure detector (:func:`.closures.refined_phones`)."""
    from mpeg4fa.speech.align.sphinx import OFFSET, pcm16k

    if len(recording.samples) == 0:
        return []
    segments = decode_pcm(phone_decoder(), pcm16k(recording.floats(), recording.rate))
    out = []
    end_of_audio = recording.duration
    for s in segments:
        start = max(0.0, s.start_frame * HOP + OFFSET)
        end = min(end_of_audio, (s.end_frame + 1) * HOP + OFFSET)
        if end > start:
            out.append(Phone(s.word, offset + start, offset + end))
    if closures:
        from mpeg4fa.speech.listen.closures import refined_phones

        out = refined_phones(recording, out, offset)
    return out


def active_share(start: float, end: float, active: np.ndarray, offset: float = 0.0) -> float:
    """Share of the 10 ms frames of [start, end) that :func:`~.voice.voice_activity` calls speech."""
    a = int(np.floor((start - offset) / HOP))
    b = max(a + 1, int(np.ceil((end - offset) / HOP)))
    part = active[max(a, 0):max(min(b, len(active)), 0)]
    return float(part.mean()) if len(part) else 0.0


RELEASE = 0.05
"""A closure is silent: a shut-lip phone counts as speech where voice activity comes within this many
seconds after it (its release into the next sound), however little of it is active itself (a p after s,
or before k, lies in a voiceless stretch longer than voice activity's reach)."""


def speech_share(start: float, end: float, active: np.ndarray, offset: float = 0.0, closure: bool = False) -> float:
    """:func:`active_share` of [start, end), or for a ``closure`` (lips shut) the larger of it and the share
    of the :data:`RELEASE` after it."""
    share = active_share(start, end, active, offset)
    return max(share, active_share(end, end + RELEASE, active, offset)) if closure else share


def phone_events(phones: list[Phone], active: np.ndarray | None = None, offset: float = 0.0) -> list[Event]:
    """Phones as IPA phoneme events; silence, fillers and phones mostly outside voice activity
    (``active``, frames from ``offset``; :func:`speech_share`) become pauses (an empty name)."""
    from mpeg4fa.speech.listen.closures import LABIALS

    table = arpabet_ipa()
    out = []
    for p in phones:
        name = table.get(p.name, "") if p.speech else ""
        if name and active is not None and speech_share(p.start, p.end, active, offset, p.name in LABIALS) < 0.5:
            name = ""
        out.append(Event("phoneme", p.start, p.end, name))
    return out


def phone_timings(events: list[Event], where: str = "pocketsphinx") -> list[Timing]:
    """IPA phoneme events -> timed visemes through the IPA feature map (diphthongs and affricates split
    as on the text path); pauses kept as ``none``."""
    from mpeg4fa.speech.ipa import ipa_visemes

    return [Timing(label, viseme, start, end) for label, viseme, start, end in ipa_visemes(events, where=where)
            if end > start]


def pause_count(timings: list[Timing]) -> int:
    """How many timings show no mouth shape (a pause)."""
    return sum(t.viseme == PAUSE for t in timings)
