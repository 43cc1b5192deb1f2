"""The encoder's front end: tagged text -> speech with timed phonemes -> visemes and expressions
-> a FAP timeline -> a FapStream (and the speech audio).

Modules: ``markup`` (expression tags), ``script`` (which text a voice can speak), ``tts/``
(speech engines with timed events), ``visemes`` (English phonemes and Mandarin pinyin to
visemes), ``utterance`` (timed visemes and tags), ``timeline`` (Hermite transitions,
expressions, merging, frames), ``encoder`` (the FapStream); long text goes through ``pipeline``,
a line of passes run chunk by chunk (``chunks`` -> speak -> phones -> ``frames`` -> ``bits``).

The names below are imported on first use, so that ``import mpeg4fa.speech.markup`` does
not load the engines, and ``say`` (which renders, :mod:`mpeg4fa.say`) does not pull the
renderer into the speech layer.
"""
from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "encode_text": "mpeg4fa.speech.encoder",
    "encode_text_to": "mpeg4fa.speech.pipeline",
    "stream_text": "mpeg4fa.speech.pipeline",
    "Encoded": "mpeg4fa.speech.encoder",
    "make_engine": "mpeg4fa.speech.encoder",
    "ENGINES": "mpeg4fa.speech.encoder",
    "LEVELS": "mpeg4fa.speech.encoder",
    "parse_markup": "mpeg4fa.speech.markup",
    "Markup": "mpeg4fa.speech.markup",
    "MarkupError": "mpeg4fa.speech.errors",
    "TTSError": "mpeg4fa.speech.errors",
    "check_speakable": "mpeg4fa.speech.script",
    "say": "mpeg4fa.say",
    "Said": "mpeg4fa.say",
}

__all__ = sorted(_EXPORTS)


def __getattr__(name: str) -> Any:
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'mpeg4fa.speech' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_EXPORTS))
