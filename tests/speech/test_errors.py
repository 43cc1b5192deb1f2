"""The speech layer's errors in the one error contract (mpeg4fa.errors.MpegFaError)."""
from __future__ import annotations

import pickle

from mpeg4fa.errors import MpegFaError
from mpeg4fa.speech.errors import MarkupError, TTSError


def test_markup_error_is_the_base_error_with_its_place():
    e = MarkupError("unknown expression 'glee'", 2, 7, hint="use joy", source="a.txt")
    assert isinstance(e, MpegFaError) and isinstance(e, ValueError)
    assert (e.message, e.where, e.hint) == ("unknown expression 'glee'", "a.txt:2:7", "use joy")
    assert str(e) == "a.txt:2:7: unknown expression 'glee' (use joy)"
    e.source = "script.txt"                                    # renamed after the fact: where follows
    assert e.where == "script.txt:2:7" and str(e).startswith("script.txt:2:7: ")
    back = pickle.loads(pickle.dumps(e))
    assert (back.message, back.line, back.column, back.hint, back.source, str(back)) == \
        (e.message, 2, 7, "use joy", "script.txt", str(e))
    assert str(MarkupError("m", 1, 1)) == "<text>:1:1: m"


def test_tts_error_is_the_base_error():
    assert issubclass(TTSError, MpegFaError)
