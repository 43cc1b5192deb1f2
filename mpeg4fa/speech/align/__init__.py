"""Audio-driven lip sync: a recording and its transcript -> an Utterance timed on the recording.

:func:`align_recording` (in :mod:`.core`) phonemises the transcript with espeak-ng and aligns it to the
recording, with pocketsphinx (English, :mod:`.sphinx`) or dynamic time warping against espeak-ng's own
rendering (any language, :mod:`.dtw`); :func:`mpeg4fa.speech.encoder.encode_recording` encodes the result.
"""
from mpeg4fa.speech.align.core import METHODS, Alignment, align_recording, choose_method
from mpeg4fa.speech.align.errors import AlignError
from mpeg4fa.speech.align.recording import Recording, read_recording

__all__ = ["METHODS", "Alignment", "AlignError", "Recording", "align_recording", "choose_method", "read_recording"]
