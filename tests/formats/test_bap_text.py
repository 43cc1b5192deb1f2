"""The .bap text format (VREng's dialect): reading, writing, face+body split/merge, sniffing, bad input,
and round trips of every real face+body and body-only stream through .bap and back to .fba."""
from __future__ import annotations

import io
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mpeg4fa import spec
from mpeg4fa.errors import MpegFaError
from mpeg4fa.fba import EncodeOptions, decode, encode
from mpeg4fa.fba.stream import BODY, FACE, FapStream
from mpeg4fa.formats import (FormatError, FormatWarning, iter_bap, merge_face_body, read_bap, read_bap_header,
                             read_fap, read_stream, sniff, split_face_body, write_bap, write_fap)

VECTORS = Path(__file__).resolve().parents[2].parent / "shared" / "vectors" / "fba"
ISO = spec.N_ISO_BAPS


def mask_line(baps: set[int], width: int = ISO) -> str:
    """A mask line sending the given (1-based) BAPs."""
    return " ".join("1" if b in baps else "0" for b in range(1, width + 1))


def read_text(text: str) -> FapStream:
    return read_bap(io.StringIO(text), name="t.bap")


def error_of(text: str) -> FormatError:
    with pytest.raises(FormatError) as info:
        read_text(text)
    return info.value


def write_text(stream: FapStream, **kwargs) -> str:
    out = io.StringIO()
    write_bap(stream, out, **kwargs)
    return out.getvalue()


# VREng's layout (our own numbers): its hi.bap has the header '3.2 hello.bap 15 49' and sends the
# shoulders, elbows, wrists, three cervical BAPs and the body rotations 184..186; its 100.bap (3.1)
# ends its mask lines with a space and turns BAP 100 in steps of 17453 (10 degrees at 1e-5 rad).
HI = {32, 33, 34, 35, 36, 37, 38, 39, 42, 43, 44, 45, 46, 47, 69, 70, 71, 184, 185, 186}
VRENG_LIKE = (
    "# a comment before the header\n"
    "3.2 hello.bap 15 49\n"
    f"{mask_line(HI)}\n"
    "0 4100 4110 4120 4130 4140 4150 4160 4170 4180 4190 4200 4210 4220 4230 4240 4250 4260 4270 4280 17\n"
    f"{mask_line(HI - {186})}\n"
    "1 -5000 -5010 -5020 -5030 -5040 -5050 -5060 -5070 -5080 -5090 -5100 -5110 -5120 -5130 -5140 -5150 -5160 -5170 -5180\n"
)
VRENG_31 = "3.1 100.bap 5 37\n" + "".join(f"{mask_line({100})} \n{k} {-17453 * k}\n" for k in range(3))


def test_vreng_layout_reads() -> None:
    s = read_text(VRENG_LIKE)
    assert len(s) == 2 and s.fps == 15 and set(s.object_mask.tolist()) == {BODY}
    assert sorted(np.flatnonzero(s.bap_mask[0]) + 1) == sorted(HI)
    assert s.bap_values[0, 32 - 1] == 4100 and s.bap_values[0, 186 - 1] == 17 and s.bap_values[0, 38 - 1] == 4160 \
        and s.bap_values[0, 47 - 1] == 4230
    assert not s.bap_mask[1, 186 - 1] and s.bap_values[1, 185 - 1] == -5180
    assert not s.fap_mask.any() and not s.bap_mask[:, ISO:].any()
    assert read_bap_header(io.StringIO(VRENG_LIKE)) == ("3.2", "hello.bap", 15.0, 49)


def test_trailing_space_masks_and_both_versions_read_alike() -> None:
    s31 = read_text(VRENG_31)
    assert s31.bap_values[:, 100 - 1].tolist() == [0, -17453, -34906]
    s32 = read_text(VRENG_31.replace("3.1", "3.2", 1))
    assert (s31.bap_values == s32.bap_values).all()  # values as written: nothing is rescaled


def test_crlf_comments_and_blank_lines_read_alike() -> None:
    messy = "\r\n".join(line + "  " for line in VRENG_LIKE.splitlines()) + "\r\n\r\n# end\r\n"
    a, b = read_text(VRENG_LIKE), read_text(messy.replace("\r\n0 4167", "\r\n\r\n# x\r\n0 4167"))
    assert (a.bap_values == b.bap_values).all() and (a.bap_mask == b.bap_mask).all()


def test_296_entry_masks_send_extension_baps() -> None:
    s = read_text(f"3.1 x 30 1\n{mask_line({1, 296}, spec.N_BAPS)}\n0 5 -7\n")
    assert s.bap_values[0, 0] == 5 and s.bap_values[0, -1] == -7 and s.bap_mask[0].sum() == 2


def test_gaps_become_skips_and_iter_agrees() -> None:
    text = f"3.1 x 10 9\n{mask_line({3})}\n2 1\n{mask_line({3})}\n5 2\n{mask_line({3})}\n6 3\n"
    s = read_text(text)
    assert s.skip.tolist() == [2, 0, 0] and s.timestamps.tolist() == [0.2, 0.5, 0.6]
    assert [r.frame_number for r in iter_bap(io.StringIO(text))] == [2, 5, 6]


def body_stream(n: int = 12, extension: bool = False, seed: int = 0) -> FapStream:
    rng = np.random.default_rng(seed)
    s = FapStream.empty(n, object_mask=BODY)
    sent = [0, 31, 37, 180, 183] + ([200, spec.N_BAPS - 1] if extension else [])
    s.bap_mask[:, sent] = True
    s.bap_mask[n // 2:, 37] = False  # a mask change mid-stream
    s.bap_values[:, sent] = rng.integers(-40, 40, size=(n, len(sent))) * spec.BAP_QUANT_STEP[sent]
    s.bap_values[~s.bap_mask] = 0
    s.skip[3] = 2
    s.source_fps = 25.0
    return s


def test_writer_layout_and_width() -> None:
    text = write_text(body_stream(), name="walk.bap")
    lines = text.splitlines()
    assert lines[0] == "3.1 walk.bap 25 14" and len(lines) == 1 + 2 * 12
    assert len(lines[1].split()) == ISO and lines[2].split()[0] == "0" and lines[8].split()[0] == "3" and lines[10].split()[0] == "6"
    wide = write_text(body_stream(extension=True)).splitlines()
    assert len(wide[1].split()) == spec.N_BAPS
    assert len(write_text(body_stream(), width=spec.N_BAPS).splitlines()[1].split()) == spec.N_BAPS


@pytest.mark.parametrize("extension", [False, True])
def test_round_trip_is_lossless(extension: bool) -> None:
    s = body_stream(extension=extension)
    back = read_text(write_text(s, version="3.2"))
    for field in ("bap_mask", "bap_values", "skip", "object_mask"):
        assert (getattr(back, field) == getattr(s, field)).all(), field
    assert back.fps == s.fps


@st.composite
def body_streams(draw) -> FapStream:
    n = draw(st.integers(0, 5))
    s = FapStream.empty(n, object_mask=BODY)
    s.source_fps = draw(st.sampled_from([25.0, 30.0, 15.0, 12.5, 29.97]))
    width = draw(st.sampled_from([ISO, spec.N_BAPS]))
    sent = draw(st.lists(st.integers(0, width - 1), max_size=12, unique=True))
    int32 = st.integers(-(2**31), 2**31 - 1)
    for k in range(n):
        s.bap_mask[k, sent] = draw(st.lists(st.booleans(), min_size=len(sent), max_size=len(sent)))
        s.bap_values[k, sent] = draw(st.lists(int32, min_size=len(sent), max_size=len(sent)))
        s.skip[k] = draw(st.integers(0, 3)) if k < n - 1 else 0
    s.bap_values[~s.bap_mask] = 0  # what .bap can hold: unmasked values are not written
    s.timestamps[:] = np.concatenate([[0], np.cumsum(s.skip[:-1] + 1)]) / s.source_fps if n else []
    return s


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(body_streams(), st.sampled_from(["3.1", "3.2"]))
def test_round_trip_property(s: FapStream, version: str) -> None:
    back = read_text(write_text(s, version=version))
    for field in ("bap_mask", "bap_values", "skip", "object_mask", "timestamps"):
        assert np.array_equal(getattr(back, field), getattr(s, field)), field


@settings(max_examples=50, deadline=None)
@given(st.text(alphabet="01 -+.#x\n\r\t9", max_size=600))
def test_garbage_raises_only_format_error(text: str) -> None:
    try:
        read_text("3.1 g 25 1\n" + text)
    except FormatError:
        pass


def test_writer_refuses_what_it_cannot_write(tmp_path: Path) -> None:
    with pytest.raises(FormatError, match="BAP 201"):
        write_text(body_stream(extension=True), width=ISO)
    with pytest.raises(FormatError, match="version"):
        write_text(body_stream(), version="2.1")
    with pytest.raises(FormatError, match="300 entries"):
        write_text(body_stream(), width=300)
    target = tmp_path / "x.bap"
    with pytest.raises(FormatError):
        write_bap(body_stream(extension=True), target, width=ISO)
    assert not target.exists()


def face_body_stream(n: int = 10) -> FapStream:
    s = body_stream(n)
    s.object_mask[:] = FACE | BODY
    s.fap_mask[:, [2, 18]] = True
    s.fap_values[:, 2] = np.arange(n) * 10 * spec.QUANT_STEP[2]  # on the fap_quant 1 grid: exact through .fba
    s.fap_values[:, 18] = -np.arange(n) * 4 * spec.QUANT_STEP[18]
    return s


def test_writer_warns_when_faps_are_dropped() -> None:
    with pytest.warns(FormatWarning, match="FAPs are dropped"):
        write_text(face_body_stream())
    face, body = split_face_body(face_body_stream())
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        write_text(body)
        write_fap(face, io.StringIO())


def test_split_and_merge_rebuild_the_stream() -> None:
    s = face_body_stream()
    face, body = split_face_body(s)
    assert not face.bap_mask.any() and not body.fap_mask.any()
    f_out, b_out = io.StringIO(), io.StringIO()
    write_fap(face, f_out)
    write_bap(body, b_out)
    merged = merge_face_body(read_fap(io.StringIO(f_out.getvalue())), read_bap(io.StringIO(b_out.getvalue())))
    for field in ("fap_mask", "fap_values", "bap_mask", "bap_values", "skip", "object_mask"):
        assert (getattr(merged, field) == getattr(s, field)).all(), field
    decoded = _through_fba(merged)
    assert (decoded.bap_values == s.bap_values).all() and (decoded.fap_values[:, [2, 18]] == s.fap_values[:, [2, 18]]).all()
    assert set(decoded.object_mask.tolist()) == {FACE | BODY}


def test_merge_matches_frames_by_number_and_refuses_other_rates() -> None:
    face = read_fap(io.StringIO("2.1 f 10 3\n" + " ".join(["0", "0", "1"] + ["0"] * 65) + "\n0 7\n"
                                + " ".join(["0", "0", "1"] + ["0"] * 65) + "\n2 9\n"))
    body = read_text(f"3.1 b 10 3\n{mask_line({5})}\n1 340\n{mask_line({5})}\n2 510\n")
    m = merge_face_body(face, body)
    assert m.object_mask.tolist() == [FACE, BODY, FACE | BODY]
    assert m.fap_values[:, 2].tolist() == [7, 0, 9] and m.bap_values[:, 4].tolist() == [0, 340, 510]
    with pytest.raises(FormatError, match="frame rate 25 differs") as info:
        merge_face_body(face, read_text(f"3.1 b 25 1\n{mask_line({5})}\n0 1\n"), body_label="b.bap")
    assert info.value.where == "b.bap:1"


def test_sniff_and_read_stream_know_bap(tmp_path: Path) -> None:
    path = tmp_path / "any.txt"
    path.write_text("\ufeff# made by hand\n\n" + VRENG_LIKE.split("\n", 1)[1])
    assert sniff(path) == "bap"
    stream, kind = read_stream(path)
    assert kind == "bap" and len(stream) == 2
    fap = tmp_path / "f.bap"
    fap.write_text("2.1 f 25 0\n")
    assert sniff(fap) == "fap"  # the content decides, not the name


def _through_fba(stream: FapStream) -> FapStream:
    """Encode (planning intra headers, as for text input) and decode again."""
    return decode(encode(stream, EncodeOptions()))


# ---- bad input: one located error each --------------------------------------------------------

M5 = mask_line({5})


@pytest.mark.parametrize("text, line, column, words", [
    ("", 1, None, "the file has no header"),
    ("# only a comment\n", 2, None, "the file has no header"),
    ("2.1 face.fap 25 1\n", 1, 1, "unsupported .bap version '2.1'"),
    ("3.1 a 25\n", 1, 9, "the header has 3 fields, expected 4"),
    ("3.1 a 0 1\n", 1, 7, "frame rate"),
    (f"3.1 a 25 1\n{M5}\n", 3, None, "the file ends after the mask line at line 2"),
    (f"3.1 a 25 1\n{M5}\n0 1\n{M5}\n", 5, None, "the file ends after the mask line at line 4"),
    (f"3.1 a 25 1\n{M5}\n0\n", 3, 2, "frame 0 has 0 values, expected 1"),
    (f"3.1 a 25 1\n{M5}\n0 1 2\n", 3, 5, "frame 0 has 2 values, expected 1"),
    (f"3.1 a 25 1\n{M5.replace('1', '2')}\n0 1\n", 2, 9, "mask entry 5 is '2', expected 0 or 1"),
    (f"3.1 a 25 1\n{M5} 0 0\n0 1\n", 2, 2 * ISO + 1, f"the mask line has {ISO + 2} entries, expected {ISO} or "),
    (f"3.1 a 25 1\n0 0 0 0 1\n0 1\n", 2, 10, "the mask line has 5 entries"),
    (f"3.1 a 25 1\n{M5}\n0 2147483648\n", 3, 3, "value 2147483648 is out of range"),
    (f"3.1 a 25 1\n{M5}\n0 -2147483649\n", 3, 3, "value -2147483649 is out of range"),
    (f"3.1 a 25 1\n{M5}\n0 1.5\n", 3, 3, "value '1.5' is not an integer"),
    (f"3.1 a 25 2\n{M5}\n3 1\n{M5}\n3 1\n", 5, 1, "frame number 3 does not increase"),
    ("3.1 a 25 1\nx\x00\n", 2, 2, "NUL byte: this is not a text .bap file"),
])
def test_error_location(text: str, line: int, column: int | None, words: str) -> None:
    err = error_of(text)
    assert (err.line, err.column) == (line, column), str(err)
    assert words in err.problem and err.hint and isinstance(err, MpegFaError)
    assert str(err).startswith(f"t.bap:{line}" + (f":{column}" if column else "") + ": ")


def test_truncated_file_is_one_located_error(tmp_path: Path) -> None:
    good = write_text(body_stream())
    path = tmp_path / "cut.bap"
    path.write_text(good[: len(good) * 2 // 3])  # cut in the middle of a line
    with pytest.raises(FormatError) as info:
        read_bap(path)
    assert info.value.path == str(path) and info.value.line is not None


def test_missing_file_and_directory(tmp_path: Path) -> None:
    with pytest.raises(FormatError, match="no such file"):
        read_bap(tmp_path / "none.bap")
    with pytest.raises(FormatError, match="directory"):
        read_bap(tmp_path)


# ---- real streams ---------------------------------------------------------------------------

REAL = ["angry_0.fba", "thinking_0.fba", "basicMotion.FBA"] + [f"yes_{k}.fba" for k in range(6)] + \
    [f"no_{k}.fba" for k in range(5)]


@pytest.mark.parametrize("name", REAL)
def test_real_stream_round_trips_through_bap(name: str, tmp_path: Path) -> None:
    path = VECTORS / name
    if not path.is_file():
        pytest.skip(f"../shared/vectors not present: {path} is a real face+body or body-only stream")
    s = decode(path)
    assert s.bap_mask.any()
    face, body = split_face_body(s)
    bap = tmp_path / "x.bap"
    write_bap(body, bap)
    back = read_bap(bap)
    assert (back.bap_mask == s.bap_mask).all() and (back.bap_values == s.bap_values).all()
    if (s.object_mask & FACE).any():
        fap = tmp_path / "x.fap"
        write_fap(face, fap)
        back = merge_face_body(read_fap(fap), back)
    again = _through_fba(back)
    assert (again.bap_mask == s.bap_mask).all() and (again.bap_values == s.bap_values).all()
    assert (again.object_mask == s.object_mask).all()
