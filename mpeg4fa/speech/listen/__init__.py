"""Lip sync from a recording alone: no transcript, any language.

* :func:`recognize_words` (English words with times, pocketsphinx's bundled language model) and
  :func:`recognize_phones` (phones with times, pocketsphinx's phone loop, any language);
* :func:`voice_activity`: which 10 ms frames are speech (level, periodicity, a voice's moving pitch),
  so that silence, breath, noise and music leave the mouth at rest;
* :func:`listen`: a :class:`~mpeg4fa.speech.align.Recording` -> :class:`Listened` (an
  :class:`~mpeg4fa.speech.utterance.Utterance` on the recording, for
  :func:`~mpeg4fa.speech.encoder.encode_utterance` and the say path);
* :func:`stream_listened` (:mod:`.stream`): a recording of any length, block by block, straight to an FBA
  stream, with the memory of a block.
"""
from mpeg4fa.speech.listen.core import (ENGLISH_DEFAULT, RECOGNIZERS, Listened, choose_recognizer, is_english,
                                        listen)
from mpeg4fa.speech.listen.phones import Phone, phone_events, phone_timings, recognize_phones
from mpeg4fa.speech.listen.voice import voice_activity
from mpeg4fa.speech.listen.words import HeardWord, recognize_words

__all__ = ["ENGLISH_DEFAULT", "RECOGNIZERS", "HeardWord", "Listened", "Phone", "choose_recognizer", "is_english",
           "listen", "phone_events", "phone_timings", "recognize_phones", "recognize_words", "voice_activity"]
