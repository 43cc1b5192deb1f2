"""Hostile .fap files and paths: one FormatError at path:line:column naming the file, bounded work, no other type."""
from __future__ import annotations

import io
import os
import pickle
import time
from pathlib import Path

import pytest

from bad_files import make_cases

from mpeg4fa.errors import MpegFaError
from mpeg4fa.fba import encode
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.formats import FormatError, read_fap, read_stream, write_fap

M1 = " ".join(["1"] + ["0"] * 67)                 # FAP 1 only: 4 values a frame
M2 = " ".join(["0", "1"] + ["0"] * 66)            # FAP 2 only: 6 values a frame
M3 = " ".join(["0", "0", "1"] + ["0"] * 65)       # FAP 3 only: 1 value a frame


def read_text(text: str) -> FapStream:
    return read_fap(io.StringIO(text), name="t.fap")


def error_of(text: str) -> FormatError:
    with pytest.raises(FormatError) as info:
        read_text(text)
    return info.value


@pytest.mark.parametrize("frame, line, column, words", [
    ("0 20 0 63 0", 3, 3, "frame 0: FAP 1 viseme_select1 = 20 is not a viseme (0..14)"),
    ("0 3 15 63 0", 3, 5, "frame 0: FAP 1 viseme_select2 = 15 is not a viseme (0..14)"),
    ("0 3 4 79 0", 3, 7, "frame 0: FAP 1 viseme_blend = 79 is out of range 0..78"),
    ("0 3 4 63 2", 3, 10, "frame 0: FAP 1 viseme_def = 2 is not a flag (0 or 1)"),
])
def test_viseme_fields_are_checked_at_read_time(frame, line, column, words):
    err = error_of(f"2.1 a 25 1\n{M1}\n{frame}\n")
    assert (err.line, err.column) == (line, column), str(err)
    assert str(err).startswith(f"t.fap:{line}:{column}: {words} (")
    assert err.hint and isinstance(err, MpegFaError)


@pytest.mark.parametrize("frame, column, words", [
    ("7 9 0 0 0 0 0", 3, "frame 7: FAP 2 expression_select1 = 9 is not an expression (0..6)"),
    ("7 1 -1 0 0 0 0", 5, "FAP 2 expression_intensity1 = -1 is out of range 0..78"),
    ("7 1 10 2 99 0 0", 10, "FAP 2 expression_intensity2 = 99 is out of range 0..78"),
    ("7 1 10 2 9 3 0", 12, "FAP 2 init_face = 3 is not a flag (0 or 1)"),
])
def test_expression_fields_are_checked_at_read_time(frame, column, words):
    err = error_of(f"2.1 a 25 1\n{M2}\n{frame}\n")
    assert (err.line, err.column) == (3, column), str(err)
    assert words in str(err)


def test_fap2_after_fap1_points_at_its_own_field():
    both = " ".join(["1", "1"] + ["0"] * 66)
    err = error_of(f"2.1 a 25 1\n{both}\n0 1 2 63 0 8 0 0 0 0 0\n")
    assert err.column == 12 and "expression_select1 = 8" in str(err)


def test_high_level_fields_at_the_edges_read():
    s = read_text(f"2.1 a 25 2\n{M1}\n0 14 0 78 1\n{M2}\n1 6 78 0 0 1 1\n")
    assert s.viseme[0].tolist() == [14, 0, 78, 1] and s.expression[1].tolist() == [6, 78, 0, 0, 1, 1]


@pytest.mark.parametrize("fps, words", [
    ("300", "frame rate 300 is more than the bitstream can carry"),
    ("256", "more than the bitstream can carry"),
    ("1e400", "frame rate inf is not a positive finite number"),
    ("0.01", "frame rate 0.01 is less than the bitstream can carry"),
    ("nan", "frame rate 'nan' is not a number"),
    ("inf", "frame rate 'inf' is not a number"),
])
def test_frame_rates_a_stream_cannot_carry(fps, words):
    err = error_of(f"2.1 a {fps} 1\n{M3}\n0 1\n")
    assert (err.line, err.column) == (1, 7) and words in str(err), str(err)


def test_four_thousand_zeros_is_a_located_error():
    """A 4,301-character token hit int()'s digit limit (a bare ValueError) before."""
    err = error_of(f"2.1 a 25 1\n{M3}\n0 {'0' * 4301}\n")
    assert (err.line, err.column) == (3, 3)
    assert "is 4,301 characters long" in str(err) and "00000000000000000000..." in str(err)
    assert len(str(err)) < 300
    err = error_of(f"2.1 a 25 1\n{M3}\n{'0' * 5000} 1\n")
    assert (err.line, err.column) == (3, 1) and "frame number" in str(err)


@pytest.mark.parametrize("value, ok", [("2147483647", True), ("-2147483648", True), ("+00012", True),
                                       ("2147483648", False), ("-2147483649", False), ("9" * 24, False)])
def test_values_are_int32(value, ok):
    text = f"2.1 a 25 1\n{M3}\n0 {value}\n"
    if ok:
        assert read_text(text).fap_values[0, 2] == int(value)
    else:
        assert "out of range -2147483648..2147483647" in str(error_of(text))


def test_frame_numbers_past_a_day_fail_at_their_line():
    """The 304-byte .fap with frames 0 and 2147483647 made encode run 125 s at 1.19 GB."""
    start = time.perf_counter()
    err = error_of(f"2.1 a 25 2\n{M3}\n0 10\n{M3}\n2147483647 10\n")
    assert time.perf_counter() - start < 1
    assert (err.line, err.column) == (5, 1)
    assert "frame number 2,147,483,647 lies 23,860.9 h into the stream at 25 fps" in str(err)
    assert "24 h" in str(err) and "2,160,000" in err.hint
    last = read_text(f"2.1 a 25 2\n{M3}\n0 10\n{M3}\n2159999 10\n")  # the last frame of 24 h reads
    assert last.skip[0] == 2159998 and len(last) == 2
    assert encode(last)                                               # and encodes, as skip counts
    assert "frame number 2,160,000" in str(error_of(f"2.1 a 25 1\n{M3}\n2160000 1\n"))


def test_gaps_are_skip_counts_not_frames():
    s = read_text(f"2.1 a 25 2\n{M3}\n0 10\n{M3}\n100000 10\n")
    assert len(s) == 2 and s.skip.tolist() == [99999, 0]
    assert s.timestamps[1] == pytest.approx(4000.0)


def test_a_line_without_end_is_bounded(tmp_path):
    path = tmp_path / "long.fap"
    path.write_text("2.1 a 25 1\n" + "0 " * 40000)
    with pytest.raises(FormatError) as info:
        read_fap(path)
    assert info.value.line == 2 and "longer than 65,536 characters" in str(info.value)
    assert str(info.value).startswith(f"{path}:2: ")


# ---- paths and bytes that are not .fap text ---------------------------------------------------


def _cases(tmp_path: Path) -> dict[str, tuple[Path, str]]:
    return make_cases(tmp_path, ".fap", [
        ("empty.fap", b"", "no header"),
        ("utf16.fap", "2.1 a 25 0\n".encode("utf-16"), "UTF-16"),
        ("utf16be.fap", "2.1 a 25 0\n".encode("utf-16-be"), "NUL byte"),          # no BOM: the NULs say it
        ("nul.fap", b"2.1 a\x00 25 0\n", "NUL byte"),
        ("nul-late.fap", f"2.1 a 25 1\n{M3}\n0 1\x00\n".encode(), "NUL byte"),
        ("zeros.fap", b"\x00" * 100_000, ""),                                        # no line end at all
    ], seed=1)


def test_every_bad_path_is_one_format_error_naming_the_file(tmp_path):
    for name, (path, words) in _cases(tmp_path).items():
        for read in (read_fap, lambda p: read_stream(p)[0]):
            with pytest.raises(FormatError) as info:
                read(path)
            err = info.value
            assert type(err) is FormatError and err.path == str(path), name
            assert str(err).startswith(str(path)), name
            assert words in str(err), (name, str(err))


def test_nul_error_points_at_the_byte(tmp_path):
    path = tmp_path / "n.fap"
    path.write_bytes(b"2.1 a\x00 25 0\n")
    with pytest.raises(FormatError) as info:
        read_fap(path)
    assert (info.value.line, info.value.column) == (1, 6)


@pytest.mark.skipif(not os.path.exists("/dev/urandom"), reason="no /dev/urandom on this system")
def test_a_device_is_read_boundedly():
    with pytest.raises(FormatError) as info:
        read_fap("/dev/urandom")
    assert info.value.path == "/dev/urandom"
    with pytest.raises(FormatError, match="/dev/zero"):
        read_fap("/dev/zero")


def test_an_fba_stream_given_as_fap_says_so(tmp_path):
    s = FapStream.empty(2)
    s.source_fps = 25.0
    path = tmp_path / "x.fap"
    path.write_bytes(encode(s))
    with pytest.raises(FormatError, match="NUL byte.*decode"):
        read_fap(path)
    assert len(read_stream(path)[0]) == 2                              # read by content: it decodes


# ---- the writer refuses what the reader would ------------------------------------------------


def test_writer_refuses_fields_and_rates_the_reader_would():
    s = FapStream.empty(3)
    s.source_fps = 25.0
    s.fap_mask[:, 0] = True
    s.viseme[2] = [20, 0, 63, 0]
    with pytest.raises(FormatError, match=r"<stream>:7: frame 2: FAP 1 viseme_select1 = 20 is not a viseme"):
        write_fap(s, io.StringIO())
    s.viseme[2] = [2, 0, 63, 0]
    s.expression[1] = [9, 0, 0, 0, 0, 0]                           # not sent (FAP 2 unmasked): not written
    write_fap(s, io.StringIO())
    s.source_fps = 300.0
    with pytest.raises(FormatError, match="frame rate 300 is more than"):
        write_fap(s, io.StringIO())
    s.source_fps = 25.0
    s.skip[0] = 2_160_000
    with pytest.raises(FormatError, match=r"<stream>:5:1: frame number 2,160,001 is past the 24 h"):
        write_fap(s, io.StringIO())


def test_format_error_is_the_base_error():
    err = FormatError("a.fap", 3, 7, "bad value", "fix it")
    assert isinstance(err, MpegFaError) and isinstance(err, ValueError)
    assert (err.message, err.where, err.hint) == ("bad value", "a.fap:3:7", "fix it")
    assert str(err) == "a.fap:3:7: bad value (fix it)"
    assert FormatError("a.fap", 3, None, "p").where == "a.fap:3"
    whole = FormatError.no_place("a.fap", "no such file")
    assert whole.where == "a.fap" and str(whole) == "a.fap: no such file"
    back = pickle.loads(pickle.dumps(err))
    assert (back.path, back.line, back.column, back.problem, back.hint, str(back)) == \
        ("a.fap", 3, 7, "bad value", "fix it", str(err))


def test_a_long_digit_run_in_a_number_is_refused_at_once(tmp_path):
    """The number pattern matched '4333' several ways, so one long digit run that was not a number took
    quadratic time (8,000 digits: 2.6 s; a 60,000-digit frame rate in a .fap header: minutes). Numbers are
    matched one way only now (masked_text, xface, obj). The alarm ends the old patterns' search."""
    import re
    import signal

    from mpeg4fa.fdp import xface
    from mpeg4fa.formats import masked_text

    def stuck(signum, frame):
        raise TimeoutError("a number pattern backtracked for over 5 s")

    token = "4" * 100_000 + "x"
    path = tmp_path / "rate.fap"
    path.write_text("2.1 x " + token[:60_000] + " 3\n")
    old = signal.signal(signal.SIGALRM, stuck)
    signal.alarm(5)
    try:
        for pattern in (masked_text._FLOAT, xface._FLOAT):
            assert pattern.match(token) is None
        with pytest.raises(FormatError, match="frame rate"):
            read_fap(path)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)
    assert re.fullmatch(masked_text._FLOAT, "12.5e3") and re.fullmatch(xface._FLOAT, " .5 ")
