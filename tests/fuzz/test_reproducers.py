"""Every crash the fuzzer (``tools/fuzz.py``) or issue 12 found in a reader, rebuilt from a seed made here.

Each test makes a tiny valid input with the library, applies the one damage that
crashed, and checks that the layer's own error (an ``MpegFaError``) comes out,
naming the place: file and line:column for text, bit or byte offset for binary,
fast and without a traceback of some other type.
"""
from __future__ import annotations

import io
import math
import time
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.errors import MpegFaError
from mpeg4fa.fba import FbaError, FrameRate, decode, demo_stream, encode
from mpeg4fa.fdp import Fdp, FdpError, fdp_to_json, load_fdp, read_xface_fdp
from mpeg4fa.formats import FormatError, iter_fap, read_fap, write_fap

try:
    from mpeg4fa.decoded import resolve
except ImportError:  # before the decoder-output package
    from mpeg4fa.face.frames import resolve

SECONDS = 5.0  # every one of these runs in milliseconds; a slow one is a hang in the making


def _fap_lines() -> list[str]:
    """A 5-frame .fap written by the library: header, then mask line and frame line per frame."""
    out = io.StringIO()
    write_fap(decode(encode(demo_stream(seconds=0.2))), out, name="seed.fap")
    return out.getvalue().splitlines()


def _write(tmp_path: Path, name: str, lines: list[str]) -> Path:
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return path


def _replace_token(line: str, index: int, token: str) -> str:
    tokens = line.split()
    tokens[index] = token
    return " ".join(tokens)


def _read_and_use(path: Path) -> None:
    """What ``mpeg4fa encode x.fap`` and ``snapshot x.fap`` do with a .fap: read, resolve, encode."""
    stream = read_fap(path)
    resolve(stream)
    encode(stream)


def _raises_at(call, error: type[MpegFaError], where: str) -> MpegFaError:
    start = time.perf_counter()
    with pytest.raises(error) as info:
        call()
    assert time.perf_counter() - start < SECONDS
    assert isinstance(info.value, MpegFaError)
    assert where in str(info.value), str(info.value)
    return info.value


# ---- .fap text --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("token_index", [0, 3], ids=["frame-number", "value"])
def test_fap_token_of_4301_zeros(tmp_path, token_index):
    """Found by the fuzzer: int() refused a 4,301-digit token with a bare ValueError (the digit limit)."""
    lines = _fap_lines()
    lines[2] = _replace_token(lines[2], token_index, "0" * 4301)
    path = _write(tmp_path, "zeros.fap", lines)
    err = _raises_at(lambda: read_fap(path), FormatError, f"{path}:3:")
    assert err.line == 3 and err.column is not None
    _raises_at(lambda: list(iter_fap(path)), FormatError, f"{path}:3:")  # the streaming reader alike


def test_fap_declaring_300_fps(tmp_path):
    """Issue 12: a .fap at 300 fps reached FrameRate.from_fps through encode as a ValueError."""
    lines = _fap_lines()
    lines[0] = _replace_token(lines[0], 2, "300")
    path = _write(tmp_path, "fast.fap", lines)
    _raises_at(lambda: _read_and_use(path), MpegFaError, f"{path}:1")


def test_fap_huge_frame_gap(tmp_path):
    """Issue 12: frames 0 and 2147483647 made encode run for minutes and write 71.6 MB."""
    lines = _fap_lines()
    lines[-1] = _replace_token(lines[-1], 0, "2147483647")
    path = _write(tmp_path, "gap.fap", lines)
    _raises_at(lambda: _read_and_use(path), MpegFaError, f"{path}:{len(lines)}")


def test_fap_viseme_select_outside_the_table(tmp_path):
    """Issue 12: viseme select 20 read without complaint, then the spec profiles raised a bare ValueError."""
    lines = _fap_lines()
    lines[2] = _replace_token(lines[2], 1, "20")  # frame number, then FAP 1's viseme_select1
    path = _write(tmp_path, "select.fap", lines)
    _raises_at(lambda: _read_and_use(path), MpegFaError, f"{path}:3")


@pytest.mark.parametrize("fps", [300.0, 256.0, 0.0, -5.0, math.nan, math.inf, 1e400])
def test_frame_rate_outside_the_bitstream(fps):
    """Issue 12: FrameRate.from_fps raised a bare ValueError (CLI --fps and .fap headers reach it)."""
    with pytest.raises(FbaError) as info:
        FrameRate.from_fps(fps)
    assert isinstance(info.value, MpegFaError)
    assert "frame rate" in str(info.value)


# ---- Xface .fdp XML ---------------------------------------------------------------------------------------


def _xface(declaration: str = '<?xml version="1.0" encoding="UTF-8"?>', doctype: str = "") -> bytes:
    body = ("<xfdp>\n  <head><fapu ES0=\"69\" MW0=\"50\"/></head>\n"
            "  <fdp affects=\"skin\" index=\"1\" name=\"2.1\"><indices>0 1</indices></fdp>\n</xfdp>\n")
    return "\n".join(part for part in (declaration, doctype, body) if part).encode("utf-8")


def test_xface_seed_reads(tmp_path):
    path = tmp_path / "face.fdp"
    path.write_bytes(_xface())
    assert read_xface_fdp(path).points == {"2.1": ("skin", 1)}


@pytest.mark.parametrize("encoding", ["x-unknown-9", "A" * 300, ""], ids=["unknown", "long", "empty"])
def test_xface_unknown_encoding(tmp_path, encoding):
    """Found by the fuzzer (and issue 12): an unknown encoding declaration escaped as LookupError."""
    path = tmp_path / "face.fdp"
    path.write_bytes(_xface(f'<?xml version="1.0" encoding="{encoding}"?>'))
    _raises_at(lambda: read_xface_fdp(path), FdpError, f"{path}:1")


@pytest.mark.parametrize("encoding", ["utf-32", "UTF-16"])
def test_xface_multibyte_encoding_declared_on_utf8_bytes(tmp_path, encoding):
    """Found by the fuzzer: expat's "multi-byte encodings are not supported" escaped as a bare ValueError."""
    path = tmp_path / "face.fdp"
    path.write_bytes(_xface(f'<?xml version="1.0" encoding="{encoding}"?>'))
    _raises_at(lambda: read_xface_fdp(path), FdpError, f"{path}:1")


def test_xface_entity_bomb_is_not_expanded(tmp_path):
    """Billion laughs: ten levels of ten references each would be 10**10 characters; refused at the DTD."""
    entities = ['<!ENTITY a "aaaaaaaaaa">'] + [f'<!ENTITY {chr(98 + k)} "{("&" + chr(97 + k) + ";") * 10}">'
                                               for k in range(9)]
    doctype = "<!DOCTYPE xfdp [\n" + "\n".join(entities) + "\n]>"
    path = tmp_path / "bomb.fdp"
    path.write_bytes(_xface(doctype=doctype).replace(b"<indices>0 1", b"<indices>&j; 0 1"))
    _raises_at(lambda: read_xface_fdp(path), FdpError, f"{path}:2")


def test_xface_external_entity_is_not_read(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("42", encoding="utf-8")
    doctype = f'<!DOCTYPE xfdp [ <!ENTITY ext SYSTEM "{secret.as_uri()}"> ]>'
    path = tmp_path / "ext.fdp"
    path.write_bytes(_xface(doctype=doctype).replace(b"<indices>0 1", b"<indices>&ext; 0 1"))
    _raises_at(lambda: read_xface_fdp(path), FdpError, f"{path}:2")


# ---- FDP JSON ---------------------------------------------------------------------------------------------


def test_fdp_json_nested_too_deeply(tmp_path):
    """Deep nesting must be a located FdpError, not RecursionError."""
    text = fdp_to_json(Fdp.from_points({"2.1": (0.0, 1.0, 2.0)}, name="deep"))
    path = tmp_path / "deep.json"
    path.write_text(text.replace('"name"', '"x": ' + "[" * 100_000 + "]" * 100_000 + ', "name"', 1),
                    encoding="utf-8")
    err = _raises_at(lambda: load_fdp(path), FdpError, f"{path}:")
    assert err.line is not None


def test_fdp_json_huge_number(tmp_path):
    text = fdp_to_json(Fdp.from_points({"2.1": (0.0, 1.0, 2.0)}))
    path = tmp_path / "long.json"
    path.write_text(text.replace("1.0", "9" * 5000, 1), encoding="utf-8")
    _raises_at(lambda: load_fdp(path), FdpError, f"{path}:")


# ---- FBA: the codec keeps what it decoded -----------------------------------------------------------------


def test_fba_truncated_keeps_the_frames_before():
    """The codec's standard, the one the fuzzer holds every reader to: located error, partial frames kept."""
    data = encode(demo_stream(seconds=0.4))
    full = decode(data)
    err = _raises_at(lambda: decode(data[: len(data) // 2]), FbaError, "at bit")
    assert err.bit_offset is not None and 0 < len(err.partial) < len(full)
    np.testing.assert_array_equal(err.partial.fap_values, full.fap_values[: len(err.partial)])
