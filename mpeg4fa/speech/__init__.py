"""The encoder's front end: tagged text -> speech with timed phonemes -> visemes and expressions
-> a FAP timeline -> a FapStream (and the speech audio).

Modules: ``markup`` (expression tags), ``tts/`` (speech engines with timed events),
``visemes`` (English phonemes and Mandarin pinyin to visemes), ``timeline`` (Hermite
transitions, expressions, merging, frames).
"""
