"""What a stream may ask of the codec (fba.limits) and the codec's place in the one error contract."""
from __future__ import annotations

import math
import pickle
import time

import numpy as np
import pytest

from mpeg4fa.errors import MpegFaError
from mpeg4fa.fba import EncodeOptions, FapStream, FbaError, FrameRate, decode, encode
from mpeg4fa.fba.limits import MAX_SPAN_SECONDS, check_span, fps_problem, frame_limit

from .conftest import make_stream

FACE = np.zeros(68, dtype=bool)
FACE[2] = True


@pytest.mark.parametrize("fps, words", [
    (300, "frame rate 300 is more than the bitstream can carry"),
    (256, "more than"),
    (255.99, "more than"),
    (0.01, "frame rate 0.01 is less than the bitstream can carry"),
    (0, "frame rate 0 is not a positive finite number"),
    (-5, "frame rate -5 is not a positive finite number"),
    (math.nan, "frame rate nan is not a positive finite number"),
    (math.inf, "frame rate inf is not a positive finite number"),
    (float("1e400"), "frame rate inf"),
    ("25", "frame rate '25' is not a number"),
    (True, "is not a number"),
])
def test_impossible_frame_rates_are_fba_errors(fps, words):
    with pytest.raises(FbaError) as info:
        FrameRate.from_fps(fps)
    assert words in str(info.value) and "1/16 to 255 15/16" in info.value.hint
    assert fps_problem(fps) == info.value.message


@pytest.mark.parametrize("fps", [25, 29.97, 30000 / 1001, 0.0625, 1, 255.9, 255.9375, np.float32(12.5)])
def test_frame_rates_the_header_carries(fps):
    assert fps_problem(fps) is None
    assert abs(FrameRate.from_fps(fps).fps - fps) <= 1 / 32


@pytest.mark.parametrize("options, words", [
    (dict(fps=math.nan), "EncodeOptions fps=nan"),
    (dict(fps=math.inf), "EncodeOptions fps=inf"),
    (dict(fps=0), "EncodeOptions fps=0"),
    (dict(fps=-5), "EncodeOptions fps=-5"),
    (dict(fps=300), "EncodeOptions fps=300: frame rate 300 is more than"),
    (dict(fap_quant=32), "fap_quant=32 is not an integer in 0..31"),
    (dict(bap_quant=-1), "bap_quant=-1"),
    (dict(fap_quant=1.5), "fap_quant=1.5"),
    (dict(intra_period=-3), "intra_period=-3 is not an integer >= 0"),
    (dict(intra_period=2.5), "intra_period=2.5"),
])
def test_encode_options_refuse_what_no_stream_carries(options, words):
    with pytest.raises(FbaError, match=words.replace("(", r"\(")):
        EncodeOptions(**options)


def test_encode_options_accept_the_edges():
    EncodeOptions(fps=255.9, fap_quant=0, bap_quant=31, intra_period=0)
    EncodeOptions(fap_quant=np.int64(5), intra_period=np.int32(10))


def test_a_stream_at_300_fps_is_an_fba_error_not_a_value_error_crash():
    s = make_stream(0, 3, fap_mask=FACE)
    s.source_fps = 300.0
    with pytest.raises(FbaError, match="frame rate 300 is more than"):
        encode(s)


def test_a_gap_of_two_billion_frames_fails_at_once():
    """The 304-byte .fap with frames 0 and 2147483647 made encode run 125 s at 1.19 GB."""
    s = make_stream(0, 2, fap_mask=FACE)
    s.skip[0] = 2**31 - 2
    start = time.perf_counter()
    with pytest.raises(FbaError) as info:
        encode(s)
    assert time.perf_counter() - start < 2
    assert "spans 2,147,483,648 frames" in info.value.message and info.value.frame == 0
    assert "24 h" in info.value.hint and "2,160,000 frames at 25 fps" in info.value.hint


def test_span_limit_edges():
    assert frame_limit(25.0) == 25 * MAX_SPAN_SECONDS == 2_160_000
    s = make_stream(0, 2, fap_mask=FACE)
    s.skip[0] = frame_limit(25.0) - 2          # exactly 24 h of slots: allowed
    check_span(s, 25.0)
    s.skip[0] += 1
    with pytest.raises(FbaError, match="more than a stream may"):
        check_span(s, 25.0)
    s.skip[0] = -1
    with pytest.raises(FbaError, match="skip count -1 is negative") as info:
        check_span(s, 25.0)
    assert info.value.frame == 0


def test_a_long_skip_within_the_limit_is_sent_as_skip_counts():
    s = make_stream(0, 2, fap_mask=FACE)
    s.skip[0] = 25 * 3600 - 2                  # an hour of held frames
    data = encode(s)
    assert len(data) < 20_000
    back = decode(data)
    assert len(back) == 2 and back.skip[0] == s.skip[0]


def test_fba_error_is_the_base_error_with_its_place():
    err = FbaError("stream ends inside a field", 2400, 3, hint="is it truncated?")
    assert isinstance(err, MpegFaError) and isinstance(err, ValueError)
    assert err.message == "stream ends inside a field" and err.where == "bit 2400 (byte 300), frame 3"
    assert str(err) == "stream ends inside a field at bit 2400 (byte 300), frame 3 (is it truncated?)"
    assert str(FbaError("plain")) == "plain" and FbaError("plain").where is None
    err.frame = 7                               # filled in as it travels up: where follows
    assert err.where.endswith("frame 7")
    partial = FapStream.empty(2)
    back = pickle.loads(pickle.dumps(FbaError("m", 8, 1, partial, "h")))
    assert (back.message, back.bit_offset, back.frame, back.hint, len(back.partial)) == ("m", 8, 1, "h", 2)
    assert str(back) == "m at bit 8 (byte 1), frame 1 (h)"


def test_decode_errors_keep_their_old_text():
    with pytest.raises(FbaError) as info:
        decode(b"\x00\x00\x01")
    assert str(info.value) == "stream is shorter than a start code: not an FBA stream at bit 0 (byte 0)"
    assert info.value.where == "bit 0 (byte 0)"
