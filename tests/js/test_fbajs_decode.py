"""fba.js decodes every stream as the Python reference decoder does: values, masks, times, errors, streaming."""
from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from .conftest import ROOT, SHARED, compare, js_decode

CONFORMANCE = sorted((ROOT / "conformance" / "vectors").glob("*/*.fba"))


def shared_streams() -> list[Path]:
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent: the real streams from other systems are not on this machine")
    return sorted(p for p in SHARED.rglob("*") if p.suffix.lower() == ".fba")


def test_spec_tables_are_current():
    """spec.js is what tools/fbajs_spec.py writes from spec/ now (never retyped, never stale)."""
    run = subprocess.run([sys.executable, str(ROOT / "tools" / "fbajs_spec.py"), "--check"],
                         capture_output=True, text=True)
    assert run.returncode == 0, run.stderr


def test_real_streams_match_python():
    paths = shared_streams()
    assert len(paths) >= 30
    got = js_decode(paths)
    for path in paths:
        compare(path, got[str(path)])


def test_conformance_vectors_match_python():
    """Every conformance vector, the reject ones included (same message, bit and frame)."""
    assert len(CONFORMANCE) >= 150
    got = js_decode(CONFORMANCE)
    for path in CONFORMANCE:
        compare(path, got[str(path)])


@pytest.fixture(scope="module")
def damaged(tmp_path_factory) -> list[Path]:
    """Truncations and bit flips of a few streams: the error paths, each checked against Python."""
    out = tmp_path_factory.mktemp("damaged")
    sources = [p for p in CONFORMANCE if "reject" not in p.parts][:6]
    if SHARED.is_dir():
        sources += [SHARED / "yes_0.fba", SHARED / "en" / "car-unlock.FBA"]
    rng = np.random.default_rng(31)
    paths = []
    for s, src in enumerate(sources):
        data = src.read_bytes()
        for j, cut in enumerate(sorted(set(rng.integers(1, len(data), 6).tolist()))):
            p = out / f"{s}-cut{j}.fba"
            p.write_bytes(data[:cut])
            paths.append(p)
        for j in range(8):
            flipped = bytearray(data)
            bit = int(rng.integers(0, len(data) * 8))
            flipped[bit // 8] ^= 0x80 >> (bit % 8)
            p = out / f"{s}-flip{j}.fba"
            p.write_bytes(bytes(flipped))
            paths.append(p)
    for name, data in (("empty", b""), ("jpeg", b"\xff\xd8\xff\xe0" + bytes(20)), ("wav", b"RIFF\0\0\0\0WAVEfmt "),
                       ("short", b"\x00\x00\x01")):
        p = out / f"{name}.fba"
        p.write_bytes(data)
        paths.append(p)
    return paths


def test_damaged_streams_fail_as_python(damaged):
    got = js_decode(damaged)
    for path in damaged:
        compare(path, got[str(path)])


@pytest.fixture(scope="module")
def streamed(damaged) -> tuple[list[Path], dict]:
    paths = [p for p in CONFORMANCE if "syntax" in p.parts][::6] + damaged[::5]
    return paths, js_decode(paths)


@pytest.mark.parametrize("chunk", [1, 7, 1000])
def test_streaming_input_gives_the_same_frames(streamed, chunk):
    """Bytes in pieces (1, 7, 1000 at a time): the same frames and the same faults as the whole file."""
    paths, whole = streamed
    pieces = js_decode(paths, chunk=chunk)
    for path in paths:
        a, b = whole[str(path)], pieces[str(path)]
        assert a["frames"] == b["frames"], path
        assert a["error"] == b["error"], path


def test_shown_values_match_resolve():
    """shown.js shows what mpeg4fa.decoded.resolve shows: hold, interpolate, FAP 1/2 profiles, clamps."""
    import warnings

    from mpeg4fa.decoded import ClampWarning, resolve

    from .conftest import python_decode

    paths = [p for p in CONFORMANCE if "reject" not in p.parts]
    if SHARED.is_dir():
        paths += sorted(p for p in SHARED.rglob("*") if p.suffix.lower() == ".fba")
    got = js_decode(paths, shown=True)
    for path in paths:
        stream, error = python_decode(path)
        assert error is None, path
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ClampWarning)
            want = resolve(stream)
        np.testing.assert_array_equal(np.array(got[str(path)]["shown"]).reshape(want.shape), want, err_msg=str(path))


def test_streaming_across_model_halvings(tmp_path):
    """A stream long enough that every adaptive model halves its counts (a total of 16383 comes after
    some 16,350 P frames): fba.js decodes it as Python does, whole and in pieces. In pieces, a plane cut
    short by the end of the bytes so far is decoded again: its counts taken back, or the models copied
    before it where it halves them; pieces of 1 byte cut every plane, the halving ones included."""
    from mpeg4fa.fba import EncodeOptions, FapStream, encode

    n = 16600
    rng = np.random.default_rng(31)
    s = FapStream.empty(n)
    s.source_fps = 25.0
    s.timestamps[:] = np.arange(n) / 25.0
    cols = [0, 1, 2, 3, 18, 47]  # FAP 1, FAP 2, jaw, a lip, a head rotation (step 128): tight and wide
    s.fap_mask[:, cols] = True
    for c in cols[2:]:
        walk = np.clip(np.cumsum(rng.integers(-3, 4, n)), -300, 300)
        s.fap_values[:, c] = walk * (128 if c == 47 else 1)
    s.viseme[:, 0], s.viseme[:, 1] = rng.integers(0, 15, n), rng.integers(0, 15, n)
    s.viseme[:, 2] = rng.integers(0, 64, n)
    s.expression[:, 0], s.expression[:, 2] = rng.integers(0, 7, n), rng.integers(0, 7, n)
    s.expression[:, 1], s.expression[:, 3] = rng.integers(0, 64, n), rng.integers(0, 64, n)
    path = tmp_path / "long.fba"
    path.write_bytes(encode(s, EncodeOptions(fap_quant=1, intra_period=0)))
    whole = js_decode([path])[str(path)]
    compare(path, whole)
    for chunk in (1, 97):
        pieces = js_decode([path], chunk=chunk)[str(path)]
        assert pieces["error"] is None and pieces["frames"] == whole["frames"], chunk
