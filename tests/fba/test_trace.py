"""The bit-level syntax trace (mpeg4fa.fba.trace, ``mpeg4fa info --trace``): it tiles the stream and agrees with decode()."""
from __future__ import annotations

import json
from collections import defaultdict
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.cli import main
from mpeg4fa.fba import EncodeOptions, FapStream, FbaError, decode, demo_stream, encode
from mpeg4fa.fba.stream import END_CODE
from mpeg4fa.fba.trace import Element, trace, window

from .conftest import SKIP_REASON, make_stream, real_vector_paths, vector_id

CONFORMANCE = Path(__file__).resolve().parents[2] / "conformance" / "vectors"
DECODABLE = sorted(p for kind in ("syntax", "semantics", "informative") for p in (CONFORMANCE / kind).glob("*.fba"))


# ---- the checks ---------------------------------------------------------------------------
def assert_tiles(elements: list[Element], end: int | None = None) -> None:
    """Each element starts where the one before ended, from bit 0 (to ``end`` when given)."""
    assert elements and elements[0].offset == 0
    for before, after in zip(elements, elements[1:]):
        assert after.offset == before.end, (before, after)
    assert all(e.width >= 0 for e in elements)
    if end is not None:
        assert elements[-1].end == end


def _fields(elements: list[Element]) -> dict[str, list[int]]:
    out = defaultdict(list)
    for e in elements:
        if e.kind in ("field", "marker"):
            out[e.name].append(e.value)
    return out


def _part_header(els: list[Element], label: str) -> dict[str, list[int]]:
    """The fields of one part's intra header: from its quant to the part's first segment."""
    i = next(j for j, e in enumerate(els) if e.name == f"{label.lower()}_quant")
    j = next(j for j in range(i, len(els)) if els[j].kind == "segment")
    return _fields(els[i:j])


def _check_part_header(f: dict[str, list[int]], params, label: str) -> None:
    assert f[f"{label.lower()}_quant"] == [params.quant]
    assert [f[f"mask type of {label} group {g + 1}"][0] for g in range(len(params.mask_types))] == list(params.mask_types)
    sent = {int(name.rsplit(" ", 1)[1]) - 1: v[0] for name, v in f.items() if name.startswith(f"mask bit of {label} ")}
    for i, bit in sent.items():
        assert bool(bit) == bool(params.mask[i])
    for k, name in enumerate(("i_max", "i_min", "p_max", "p_min")):
        assert f[f"is_{name}_new"] == [int(params.ranges.flags[k])]
        for key, v in f.items():
            if key.startswith(f"new {name} of {label} "):
                assert v == [int(params.ranges.codes[k, int(key.rsplit(" ", 1)[1]) - 1])], key
    assert f["coding_type"] == [params.coding_type]


def assert_agrees(elements: list[Element], stream: FapStream) -> None:
    """Header values, start codes, skips, bits per plane and segment values equal what decode() gives."""
    assert elements[0].kind == "start_code" and elements[0].value == stream.object_start_code
    last = elements[-1] if elements[-1].kind != "trailing" else elements[-2]
    assert last.kind == "start_code" and last.value == END_CODE and last.frame is None
    by_frame: dict[int, list[Element]] = defaultdict(list)
    for e in elements:
        if e.frame is not None:
            by_frame[e.frame].append(e)
    assert sorted(by_frame) == list(range(len(stream)))
    for k, els in by_frame.items():
        codes = [e.value for e in els if e.kind == "start_code"]
        assert codes == ([int(stream.start_code[k])] if stream.start_code[k] else [])
        assert sum(e.width for e in els if e.kind not in ("start_code", "stuffing")) == stream.bits[k]
        f = _fields(els)
        assert f["is_intra"] == [int(k in stream.intra)]
        assert f["fba_object_mask"] == [int(stream.object_mask[k])]
        assert sum(f.get("number_of_frames_to_skip", [])) == stream.skip[k]
        if k in stream.intra:
            p = stream.intra[k]
            fr = p.frame_rate
            assert f["is_frame_rate"] == [int(fr is not None)]
            if fr is not None:
                assert (f["frame_rate"], f["seconds"], f["frequency_offset"]) == (
                    [fr.frame_rate], [fr.seconds], [fr.frequency_offset])
            tc = p.time_code
            assert f["is_time_code"] == [int(tc is not None)]
            if tc is not None:
                assert (f["time_code_hours"], f["time_code_minutes"], f["time_code_seconds"]) == (
                    [tc.hours], [tc.minutes], [tc.seconds])
            for params, label in ((p.face, "FAP"), (p.body, "BAP")):
                if params is not None:
                    _check_part_header(_part_header(els, label), params, label)
        segments = {e.name: e for e in els if e.kind == "segment"}
        for e in segments.values():
            assert len(e.value) == len(e.symbols) == len(e.labels)
            assert e.intra == (k in stream.intra)
        if stream.object_mask[k] & 1:
            faps = segments.pop("FAP segment")
            cols = [int(label.split()[1]) - 1 for label in faps.labels]
            np.testing.assert_array_equal(stream.fap_values[k, cols], faps.value)
            assert set(cols) == set(np.flatnonzero(stream.fap_mask[k][2:]) + 2)
            for name, fap, raw, out in (("FAP 1 (viseme) segment", 0, ("viseme_def",), stream.viseme[k]),
                                        ("FAP 2 (expression) segment", 1, ("init_face", "expression_def"),
                                         stream.expression[k])):
                assert (name in segments) == bool(stream.fap_mask[k, fap])
                if name in segments:
                    seg = segments.pop(name)
                    n = len(seg.value)
                    np.testing.assert_array_equal(out[:n], seg.value)
                    raw_els = [e for e in els if e.name in raw and e.offset >= seg.end][:len(raw)]
                    assert [e.name for e in raw_els] == list(raw)
                    np.testing.assert_array_equal(out[n:], [e.value for e in raw_els])
        if stream.object_mask[k] & 2:
            baps = segments.pop("BAP segment")
            cols = [int(label.split()[1]) - 1 for label in baps.labels]
            np.testing.assert_array_equal(stream.bap_values[k, cols], baps.value)
            assert set(cols) == set(np.flatnonzero(stream.bap_mask[k]))
        assert not segments, segments


def check(data: bytes) -> list[Element]:
    elements = list(trace(data))
    assert_tiles(elements, len(data) * 8)
    assert_agrees(elements, decode(data))
    return elements


# ---- generated streams --------------------------------------------------------------------
def _generated() -> dict[str, bytes]:
    all_faps = np.ones(68, dtype=bool)
    some = np.zeros(68, dtype=bool)
    some[[2, 3, 18, 47, 50]] = True
    baps = np.zeros(296, dtype=bool)
    baps[[0, 5, 180, 200]] = True
    skipped = make_stream(5, 30, fap_mask=some)
    skipped.skip[9] = 20  # 15 + 5: a chunk of 15 continues the count
    skipped.timestamps[:] = np.concatenate([np.arange(10), np.arange(30, 50)]) / 25.0
    return {
        "demo": encode(demo_stream(), EncodeOptions(fap_quant=1)),
        "all-faps": encode(make_stream(1, 24, fap_mask=all_faps), EncodeOptions(fap_quant=1, intra_period=10)),
        "face-body": encode(make_stream(2, 20, fap_mask=some, bap_mask=baps), EncodeOptions(intra_period=7)),
        "body": encode(make_stream(3, 12, bap_mask=baps, bap_quant=3)),
        "start-codes-time-codes": encode(make_stream(4, 15, fap_mask=some),
                                         EncodeOptions(start_codes=True, time_codes=True, intra_period=5)),
        "skips": encode(skipped, EncodeOptions(fap_quant=2)),
        "quant-0": encode(make_stream(6, 10, fap_mask=some, fap_quant=0), EncodeOptions(fap_quant=0)),
    }


GENERATED = _generated()


@pytest.mark.parametrize("name", sorted(GENERATED))
def test_generated_stream(name):
    elements = check(GENERATED[name])
    kinds = {e.kind for e in elements}
    assert {"start_code", "field", "marker", "segment"} <= kinds


def test_stuffing_and_skips_are_listed():
    elements = check(GENERATED["start-codes-time-codes"])
    assert any(e.kind == "stuffing" for e in elements)
    planes = int(np.count_nonzero(decode(GENERATED["start-codes-time-codes"]).start_code))
    assert planes > 1 and sum(e.kind == "start_code" for e in elements) == planes + 2
    assert any(e.name == "time_code_hours" for e in elements)
    assert any(e.name == "number_of_frames_to_skip" and e.value == 15 for e in check(GENERATED["skips"]))


@pytest.mark.parametrize("path", DECODABLE, ids=lambda p: f"{p.parent.name}/{p.name}")
def test_conformance_vector(path):
    check(path.read_bytes())


REAL = real_vector_paths()


@pytest.mark.skipif(not REAL, reason=SKIP_REASON)
@pytest.mark.parametrize("path", REAL, ids=vector_id)
def test_real_stream(path):
    check(path.read_bytes())


def test_reads_files_and_keeps_trailing_bytes(tmp_path):
    data = GENERATED["face-body"]
    path = tmp_path / "x.fba"
    path.write_bytes(data + b"\x00\x00")
    elements = list(trace(path))
    assert_tiles(elements, len(data) * 8 + 16)
    assert elements[-1].kind == "trailing" and elements[-1].width == 16
    with open(path, "rb") as fh:
        assert list(trace(fh)) == elements


def test_window_and_laziness():
    elements = list(trace(GENERATED["all-faps"]))
    part = list(window(trace(GENERATED["all-faps"]), 3, 5))
    assert part == [e for e in elements if e.frame in (3, 4)]
    assert list(window(elements, 0, 1))[0].frame is None  # the object start code comes with frame 0
    assert list(window(elements, 22))[-1].value == END_CODE


# ---- damaged streams ----------------------------------------------------------------------
def _faulty(data: bytes) -> tuple[list[Element], FbaError]:
    got: list[Element] = []
    with pytest.raises(FbaError) as info:
        for e in trace(data):
            got.append(e)
    with pytest.raises(FbaError) as by_decode:
        decode(data)
    assert (info.value.message, info.value.bit_offset, info.value.frame) == (
        by_decode.value.message, by_decode.value.bit_offset, by_decode.value.frame)
    return got, info.value


@pytest.mark.parametrize("cut", [3, 10, 41, 100, 333])
def test_truncated_stream_lists_everything_before_the_fault(cut):
    data = GENERATED["face-body"]
    full = list(trace(data))
    got, err = _faulty(data[:cut])
    assert got == full[:len(got)]
    assert all(e.end <= cut * 8 for e in got)
    if cut < 4:  # shorter than the object start code: nothing to list
        assert not got and err.bit_offset == 0
        return
    assert_tiles(got)
    assert got[-1].end <= err.bit_offset <= cut * 8
    assert full[len(got)].end > cut * 8 or full[len(got)].offset <= err.bit_offset  # the element cut off


@pytest.mark.parametrize("marker", ["marker bit of group 1 mask", "marker bit of new i_max ranges"])
def test_bad_marker_bit_is_the_error_after_the_good_fields(marker):
    data = GENERATED["demo"]
    full = list(trace(data))
    target = next(e for e in full if e.name == marker)
    bits = np.unpackbits(np.frombuffer(data, dtype=np.uint8))
    bits[target.offset] = 0
    got, err = _faulty(np.packbits(bits).tobytes())
    assert err.bit_offset == target.offset and "marker bit" in err.message
    assert got == full[:full.index(target)]


# ---- the command --------------------------------------------------------------------------
@pytest.fixture()
def stream_file(tmp_path):
    path = tmp_path / "t.fba"
    path.write_bytes(GENERATED["start-codes-time-codes"])
    return path


def test_cli_text(stream_file, capsys):
    assert main(["info", "--trace", str(stream_file)]) == 0
    lines = capsys.readouterr().out.splitlines()
    elements = list(trace(stream_file))
    rows = [line for line in lines[1:] if not line.startswith("-- frame")]
    assert len(rows) == len(elements)
    assert [int(r.split()[0]) for r in rows] == [e.offset for e in elements]
    assert [int(r.split()[1]) for r in rows] == [e.width for e in elements]
    assert sum(line.startswith("-- frame") for line in lines) == 15
    assert "0x000001BA" in rows[0] and "0x000001B1" in rows[-1]


def test_cli_json_frames(stream_file, capsys):
    assert main(["info", "--trace", "--json", "--frames", "2:4", str(stream_file)]) == 0
    got = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert got == [e.as_dict() for e in trace(stream_file) if e.frame in (2, 3)]


def test_cli_truncated_stream(tmp_path, capsys):
    path = tmp_path / "cut.fba"
    path.write_bytes(GENERATED["face-body"][:100])
    assert main(["info", "--trace", str(path)]) == 1
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("mpeg4fa info: error: ") and " at bit " in err[0]
    assert "Traceback" not in captured.err
    with pytest.raises(FbaError) as info:
        decode(path)
    assert f"at bit {info.value.bit_offset} " in err[0]
    assert len(captured.out.splitlines()) > 10
    assert main(["info", "--trace", "--json", str(path)]) == 1
    last = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert last == {"error": info.value.message, "bit_offset": info.value.bit_offset, "frame": info.value.frame}


def test_cli_options(stream_file, tmp_path, capsys):
    assert main(["info", "--frames", "1:2", str(stream_file)]) == 2
    with pytest.raises(SystemExit) as bad:
        main(["info", "--trace", "--frames", "4:2", str(stream_file)])
    assert bad.value.code == 2
    fap = tmp_path / "x.fap"
    fap.write_text("2.1 x 25 1\n0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 "
                   "0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0\n")
    assert main(["info", "--trace", str(fap)]) == 1
    assert "is not a binary .fba stream" in capsys.readouterr().err
    empty = tmp_path / "empty.bin"  # fuzz of 2026-12-07: an empty or random file was called "a .fap text file"
    empty.write_bytes(b"")
    assert main(["info", "--trace", str(empty)]) == 1
    err = capsys.readouterr().err
    assert "empty.bin: is not a binary .fba stream" in err and ".fap text file" not in err
