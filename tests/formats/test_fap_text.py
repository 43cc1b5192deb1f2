"""Plain-text .fap reader/writer: real Xface files, generated files, and every error case."""
from __future__ import annotations

import io
import pickle
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mpeg4fa.fba.stream import FapStream, FrameRate, CodingParams
from mpeg4fa.formats import FormatError, FormatWarning, iter_fap, read_fap, write_fap

VECTORS = Path(__file__).resolve().parents[2].parent / "shared" / "vectors"
XFACE_NAME = r"C:\Users\balci\Work\FACE\exml2fap\files\TempFile"


def xface(name: str) -> Path:
    if not VECTORS.is_dir():
        pytest.skip("../shared/vectors not present: real .fap samples unavailable")
    return VECTORS / "fap" / f"xface-{name}.fap"


def mask_line(faps: set[int], width: int = 68) -> str:
    """A mask line with a 1 for each FAP number in ``faps`` (1-based)."""
    return " ".join("1" if i in faps else "0" for i in range(1, width + 1))


def read_text(text: str) -> FapStream:
    return read_fap(io.StringIO(text), name="t.fap")


def write_text(stream: FapStream, **kwargs) -> str:
    out = io.StringIO()
    write_fap(stream, out, **kwargs)
    return out.getvalue()


def assert_same_frames(a: FapStream, b: FapStream) -> None:
    for field in ("fap_mask", "fap_values", "viseme", "expression", "skip", "object_mask"):
        np.testing.assert_array_equal(getattr(a, field), getattr(b, field), err_msg=field)
    np.testing.assert_allclose(a.timestamps, b.timestamps, rtol=0, atol=1e-12)
    assert a.source_fps == b.source_fps


# ---- real files ---------------------------------------------------------------------


@pytest.mark.parametrize("name", ["joy", "anger"])
def test_xface_file_parses(name: str) -> None:
    s = read_fap(xface(name))
    assert len(s) == 108
    assert s.fps == 25 and s.source_fps == 25
    np.testing.assert_array_equal(s.skip, 0)
    np.testing.assert_allclose(s.timestamps, np.arange(108) / 25)
    np.testing.assert_array_equal(s.object_mask, 1)
    assert not s.fap_mask[:, :2].any()
    np.testing.assert_array_equal(s.fap_values[:, :2], 0)
    np.testing.assert_array_equal(s.fap_values[~s.fap_mask], 0)


def test_xface_anger_mask_and_value_counts() -> None:
    path = xface("anger")
    s = read_fap(path)
    assert (s.fap_mask.sum(axis=1) == 48).all()
    # independent count: every frame line carries its frame number + one value per mask 1
    lines = [line.split() for line in path.read_text().splitlines()[1:]]
    for k, (mask, frame) in enumerate(zip(lines[0::2], lines[1::2])):
        assert int(frame[0]) == k
        assert len(frame) - 1 == mask.count("1") == int(s.fap_mask[k].sum())
        np.testing.assert_array_equal(s.fap_values[k][s.fap_mask[k]], [int(v) for v in frame[1:]])
    # first frame line: "0 0 10 10 0 0 ..." -> FAP 3 = 0, FAP 4 = 10, FAP 5 = 10, FAP 6 = 0
    np.testing.assert_array_equal(s.fap_values[0, 2:6], [0, 10, 10, 0])


@pytest.mark.parametrize("name", ["joy", "anger"])
def test_xface_round_trip_is_lossless(name: str, tmp_path: Path) -> None:
    path = xface(name)
    original = read_fap(path)
    out = tmp_path / "copy.fap"
    write_fap(original, out, name=XFACE_NAME)
    assert_same_frames(original, read_fap(out))
    # and the text is the original with CRLF -> LF and trailing spaces removed
    expected = "".join(line.rstrip() + "\n" for line in path.read_text().splitlines())
    assert out.read_bytes() == expected.encode()


def test_iter_fap_agrees_with_read_fap() -> None:
    path = xface("joy")
    s = read_fap(path)
    records = list(iter_fap(path))
    assert [r.frame_number for r in records] == list(range(108))
    for k, (number, mask, values, viseme, expression) in enumerate(records):
        np.testing.assert_array_equal(mask, s.fap_mask[k])
        np.testing.assert_array_equal(values, s.fap_values[k])
        assert mask.shape == (68,) and values.shape == (68,) and viseme.shape == (4,) and expression.shape == (6,)


# ---- generated files: layout quirks -------------------------------------------------

QUIRKY = (
    "# made by hand\r\n"
    "\r\n"
    "2.1 AU Interpolation_1.fap 10 99 \t\r\n"
    "# first frame starts at 3\r\n"
    + mask_line({1, 2, 3, 68}, width=69) + " \r\n"
    + "3 5 7 40 1 2 63 4 10 1 0 -12 99 \r\n"
    + "\r\n"
    + mask_line({19}, width=68) + "\t\r\n"
    + "   # indented comment between mask and frame line\r\n"
    + "4 -300\r\n"
    + mask_line(set(), width=70) + "\r\n"
    + "9\r\n"
)


def test_quirky_file_fields() -> None:
    s = read_text(QUIRKY)
    assert len(s) == 3 and s.source_fps == 10
    np.testing.assert_array_equal(s.viseme[0], [5, 7, 40, 1])
    np.testing.assert_array_equal(s.expression[0], [2, 63, 4, 10, 1, 0])
    assert s.fap_values[0, 2] == -12 and s.fap_values[0, 67] == 99
    assert s.fap_values[1, 18] == -300
    np.testing.assert_array_equal(s.viseme[1:], 0)
    np.testing.assert_array_equal(s.fap_mask.sum(axis=1), [4, 1, 0])
    np.testing.assert_array_equal(s.skip, [0, 4, 0])              # 4 -> 9 skips 5..8
    np.testing.assert_allclose(s.timestamps, [0.3, 0.4, 0.9])
    np.testing.assert_array_equal(s.object_mask, 1)


def test_quirky_file_round_trips_with_zero_based_numbers() -> None:
    s = read_text(QUIRKY)
    text = write_text(s, name="x.fap")
    lines = text.split("\n")
    assert lines[0] == "2.1 x.fap 10 7"                             # 0, 1, 6 -> 7 frames
    assert [lines[i].split()[0] for i in (2, 4, 6)] == ["0", "1", "6"]
    again = read_text(text)
    for field in ("fap_mask", "fap_values", "viseme", "expression", "skip"):
        np.testing.assert_array_equal(getattr(s, field), getattr(again, field))


def test_lf_and_crlf_read_alike() -> None:
    assert_same_frames(read_text(QUIRKY), read_text(QUIRKY.replace("\r\n", "\n")))


@pytest.mark.parametrize("version", ["1.1", "2.0", "2.1", "2.2"])
def test_all_versions_read_the_same(version: str) -> None:
    s = read_text(f"{version} v.fap 25 1\n{mask_line({3, 4})}\n0 100 -100\n")
    np.testing.assert_array_equal(s.fap_values[0, 2:4], [100, -100])  # 2.0 not divided by 20


def test_float_fps_and_header_count_not_trusted() -> None:
    s = read_text(f"2.1 a 29.97 500\n{mask_line({3})}\n0 1\n{mask_line({3})}\n2 2\n")
    assert len(s) == 2 and s.source_fps == pytest.approx(29.97)
    np.testing.assert_allclose(s.timestamps, [0, 2 / 29.97])
    np.testing.assert_array_equal(s.skip, [1, 0])


def test_header_only_gives_empty_stream() -> None:
    s = read_text("# nothing yet\n2.1 empty.fap 30 0\n# still nothing\n")
    assert len(s) == 0 and s.source_fps == 30
    assert read_text("2.1 a 30 12\n").n_frames == 0                  # count disagrees: no error


def test_iter_fap_is_lazy() -> None:
    missing = iter_fap("/no/such/dir/file.fap")                       # nothing opened yet
    with pytest.raises(FormatError, match="file.fap: no such file"):
        next(missing)
    source = io.StringIO(f"2.1 a 25 3\n{mask_line({3})}\n0 1\n{mask_line({3})}\n1 2\n{mask_line({3})}\n2 x\n")
    records = iter_fap(source, name="lazy.fap")
    assert next(records).frame_number == 0
    assert next(records).frame_number == 1                            # the bad line is not read yet
    with pytest.raises(FormatError):
        next(records)


def test_path_is_named_in_errors(tmp_path: Path) -> None:
    path = tmp_path / "bad.fap"
    path.write_text("9.9 a 25 1\n")
    with pytest.raises(FormatError) as info:
        read_fap(path)
    assert info.value.path == str(path)
    assert str(info.value).startswith(f"{path}:1:1: unsupported .fap version '9.9' (")
    assert "1.1, 2.0, 2.1, 2.2" in str(info.value)


# ---- writer -------------------------------------------------------------------------


def small_stream() -> FapStream:
    s = FapStream.empty(3)
    s.source_fps = 25.0
    s.fap_mask[0, [0, 1, 2]] = True
    s.viseme[0] = [3, 4, 20, 1]
    s.expression[0] = [1, 60, 2, 3, 0, 1]
    s.fap_values[0, 2] = -7
    s.fap_mask[1, 47] = True
    s.fap_values[1, 47] = 12345
    s.fap_values[2, 10] = 99                                          # not masked: not written
    s.skip[:] = [0, 2, 0]
    return s


def test_writer_layout() -> None:
    text = write_text(small_stream(), name="gen.fap")
    assert text == (
        "2.1 gen.fap 25 5\n"
        f"{mask_line({1, 2, 3})}\n0 3 4 20 1 1 60 2 3 0 1 -7\n"
        f"{mask_line({48})}\n1 12345\n"
        f"{mask_line(set())}\n4\n"
    )
    assert "\r" not in text and " \n" not in text


def test_writer_defaults_and_fps(tmp_path: Path) -> None:
    s = small_stream()
    s.source_fps = 29.97
    path = tmp_path / "named.fap"
    write_fap(s, path, version="2.2")
    assert path.read_text().splitlines()[0] == "2.2 named.fap 29.97 5"
    s.intra[0] = CodingParams(frame_rate=FrameRate(30))               # an intra rate wins over source_fps
    assert write_text(s).splitlines()[0] == "2.1 stream.fap 30 5"


def test_writer_warns_when_baps_are_dropped() -> None:
    s = small_stream()
    s.bap_mask[1, 5] = True
    with pytest.warns(FormatWarning, match="BAPs are dropped"):
        write_text(s)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_text(small_stream())                                    # no BAPs, no warning


def test_writer_rejects_what_it_cannot_write(tmp_path: Path) -> None:
    with pytest.raises(FormatError, match="version '3.0'"):
        write_text(small_stream(), version="3.0")
    with pytest.raises(FormatError, match="name"):
        write_text(small_stream(), name="two\nlines")
    bad = small_stream()
    bad.skip[1] = -1
    path = tmp_path / "never.fap"
    with pytest.raises(FormatError) as info:
        write_fap(bad, path)
    assert (info.value.line, info.value.column) == (5, 1)             # frame 1's frame line
    assert not path.exists()                                          # checked before writing


def test_write_empty_stream() -> None:
    s = FapStream.empty(0)
    s.source_fps = 25.0
    text = write_text(s, name="e.fap")
    assert text == "2.1 e.fap 25 0\n"
    assert len(read_text(text)) == 0


# ---- property: write -> read is lossless ---------------------------------------------


@st.composite
def streams(draw) -> FapStream:
    n = draw(st.integers(0, 6))
    s = FapStream.empty(n)
    s.source_fps = draw(st.sampled_from([25.0, 30.0, 12.5, 29.97, 60.0]))
    int32 = st.integers(-(2**31), 2**31 - 1)
    for k in range(n):
        s.fap_mask[k] = draw(st.lists(st.booleans(), min_size=68, max_size=68))
        s.fap_values[k, 2:] = draw(st.lists(int32, min_size=66, max_size=66))
        select, level, flag = st.integers(0, 14), st.integers(0, 78), st.integers(0, 1)
        s.viseme[k] = [draw(select), draw(select), draw(level), draw(flag)]
        s.expression[k] = [draw(st.integers(0, 6)), draw(level), draw(st.integers(0, 6)), draw(level), draw(flag),
                           draw(flag)]
        s.skip[k] = draw(st.integers(0, 3)) if k < n - 1 else 0
    # what .fap can hold: unmasked values and fields are not written
    s.fap_values[~s.fap_mask] = 0
    s.viseme[~s.fap_mask[:, 0]] = 0
    s.expression[~s.fap_mask[:, 1]] = 0
    s.timestamps[:] = np.concatenate([[0], np.cumsum(s.skip[:-1] + 1)]) / s.source_fps if n else []
    return s


@settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(streams())
def test_round_trip_property(s: FapStream) -> None:
    assert_same_frames(s, read_text(write_text(s, name="p.fap")))


@settings(max_examples=50, deadline=None)
@given(st.text(alphabet="01 -+.#x\n\r\t9", max_size=300))
def test_garbage_raises_only_format_error(text: str) -> None:
    try:
        read_text("2.1 g 25 1\n" + text)
    except FormatError:
        pass


# ---- errors: one per case, with line and column ---------------------------------------

M3 = mask_line({3})                                       # one value per frame line
M12 = mask_line({1, 2})                                   # 4 + 6 values per frame line


@pytest.mark.parametrize(
    "text, line, column, words",
    [
        ("", 1, None, "no header"),
        ("# only\n\n# comments\n", 4, None, "no header"),
        ("# c\n3.0 a 25 1\n", 2, 1, "unsupported .fap version '3.0'"),
        ("2.1 a 25\n", 1, 9, "3 fields, expected 4"),
        ("2.1 a x 1\n", 1, 7, "frame rate 'x'"),
        ("2.1 a 0 1\n", 1, 7, "frame rate 0 is not a positive finite number"),
        ("2.1 a -25 1\n", 1, 7, "frame rate -25 is not a positive finite number"),
        ("2.1 a nan 1\n", 1, 7, "frame rate 'nan'"),
        ("2.1 a 25 1.5\n", 1, 10, "frame count '1.5' is not an integer"),
        ("2.1 a 25 -1\n", 1, 10, "frame count -1 is out of range"),
        (f"2.1 a 25 1\n{M3.replace('1', '2')}\n0 1\n", 2, 5, "mask entry 3 is '2'"),
        (f"2.1 a 25 1\n{M3} x\n0 1\n", 2, 137, "mask entry 69 is 'x'"),
        (f"2.1 a 25 1\n{M3[:-2]}\n0 1\n", 2, 134, "67 entries, expected 68"),
        (f"2.1 a 25 1\n{M3}\n", 3, None, "ends after the mask line at line 2"),
        (f"2.1 a 25 1\n{M3}\n# c\n\n", 5, None, "ends after the mask line at line 2"),
        (f"2.1 a 25 1\n{M3}\n0 1.5\n", 3, 3, "value '1.5' is not an integer"),
        (f"2.1 a 25 1\n{M3}\n0 1_000\n", 3, 3, "value '1_000' is not an integer"),
        (f"2.1 a 25 1\n{M3}\n0 2147483648\n", 3, 3, "out of range"),
        (f"2.1 a 25 1\n{M3}\n0 {'9' * 5000}\n", 3, 3, "value 99999999999999999999... is 5,000 characters long"),
        (f"2.1 a 25 1\n{M3}\n0\n", 3, 2, "has 0 values, expected 1"),
        (f"2.1 a 25 1\n{M12}\n0 1 2 3 4 5 6 7 8 9\n", 3, 20, "has 9 values, expected 10"),
        (f"2.1 a 25 1\n{M3}\n0 1 2 3\n", 3, 5, "has 3 values, expected 1"),
        (f"2.1 a 25 1\n{M3}\n0.0 1\n", 3, 1, "frame number '0.0' is not an integer"),
        (f"2.1 a 25 1\n{M3}\n-1 1\n", 3, 1, "frame number -1 is out of range"),
        (f"2.1 a 25 2\n{M3}\n4 1\n{M3}\n4 1\n", 5, 1, "frame number 4 does not increase"),
        (f"2.1 a 25 2\n{M3}\n4 1\n{M3}\n2 1\n", 5, 1, "frame number 2 does not increase"),
    ],
)
def test_error_location(text: str, line: int, column: int | None, words: str) -> None:
    with pytest.raises(FormatError) as info:
        read_text(text)
    err = info.value
    assert (err.line, err.column) == (line, column), str(err)
    assert words in str(err)
    where = f"t.fap:{line}" if column is None else f"t.fap:{line}:{column}"
    assert str(err).startswith(where + ": ") and str(err).endswith(")")


def test_format_error_is_a_value_error_and_pickles() -> None:
    err = FormatError("a.fap", 3, None, "something is wrong", "fix it")
    assert isinstance(err, ValueError)
    assert str(err) == "a.fap:3: something is wrong (fix it)"
    again = pickle.loads(pickle.dumps(err))
    assert (again.path, again.line, again.column, str(again)) == ("a.fap", 3, None, str(err))
    assert str(FormatError("a.fap", 1, 7, "bad", "good")) == "a.fap:1:7: bad (good)"
