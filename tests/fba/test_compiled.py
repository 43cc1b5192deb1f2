"""The compiled path (mpeg4fa.fba.compiled) against the reference: same frames, same errors, same models.

The pure-Python decoder is the reference; every stream here is decoded both ways and every
field compared, and so is every fault: message, bit offset, frame and the frames before it.
"""
from __future__ import annotations

import io
import random

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from mpeg4fa.conformance.manifest import default_root, load_manifest
from mpeg4fa.fba import EncodeOptions, FbaError, decode, encode, iter_decode
from mpeg4fa.fba import compiled
from mpeg4fa.fba.arith import AdaptiveModel

from .conftest import hyp_settings, make_stream, real_vector_paths, seeds, vector_id

pytestmark = pytest.mark.skipif(not compiled.available(), reason=f"compiled path off: {compiled.why_not()}")

FIELDS = ("fap_mask", "fap_values", "viseme", "expression", "bap_mask", "bap_values", "timestamps",
          "object_mask", "skip", "start_code", "bits")


def both(source, **kw):
    """(python, compiled) results: a stream, or the FbaError."""
    out = []
    for backend in ("python", "compiled"):
        try:
            out.append(decode(source() if callable(source) else source, backend=backend, **kw))
        except FbaError as exc:
            out.append(exc)
    return out


def assert_same_stream(a, b):
    assert len(a) == len(b)
    for name in FIELDS:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert a.intra.keys() == b.intra.keys() and a.object_start_code == b.object_start_code
    for k in a.intra:
        assert repr(a.intra[k]) == repr(b.intra[k])


def assert_same(source):
    a, b = both(source)
    assert type(a) is type(b), (a, b)
    if isinstance(a, FbaError):
        assert (a.message, a.bit_offset, a.frame) == (b.message, b.bit_offset, b.frame)
        assert (a.partial is None) == (b.partial is None)
        if a.partial is not None:
            assert_same_stream(a.partial, b.partial)
    else:
        assert_same_stream(a, b)
    return a


# ---- the models ----------------------------------------------------------------------------
@hyp_settings(30)
@given(n=st.integers(1, 3721), symbols=st.lists(st.integers(0, 10 ** 6), min_size=1, max_size=400),
       skew=st.booleans())
def test_fenwick_models_match_the_reference_model(n, symbols, skew):
    """Search and cumulative counts agree with the reference table, through halvings."""
    from mpeg4fa.fba.compiled import kernels as model

    ref = AdaptiveModel(n)
    foff, toff, freq, tree, total = model.uniform_bank(np.array([n]))
    top = int(model.highest_power_of_two(n))
    sequence = [(s % 3 if skew else s) % n for s in symbols] * (60 if skew else 1)
    for s in sequence:
        cum = ref.cum()
        assert total[0] == cum[0]
        for target in {0, int(cum[0]) - 1, int(cum[s + 1]), int(cum[s]) - 1}:
            want = int(np.searchsorted(ref.neg, -target)) - 1       # the reference's symbol for target
            got, before = model.find(tree, toff[0], n, top, int(total[0]) - target)
            assert got == want and int(cum[0]) - before == cum[got]
        ref.update(s)
        model.count(freq, foff[0], tree, toff[0], n, total, 0, s)
    np.testing.assert_array_equal(freq, ref.cum()[:-1] - ref.cum()[1:])


# ---- streams -------------------------------------------------------------------------------
@pytest.mark.parametrize("path", real_vector_paths(), ids=vector_id)
def test_real_vectors_decode_the_same(path):
    assert_same(path)


def test_real_vectors_are_there_or_skipped():
    if not real_vector_paths():
        pytest.skip("../shared/vectors not present")
    assert len(real_vector_paths()) >= 31


MANIFEST = load_manifest(default_root())


@pytest.mark.parametrize("vector", MANIFEST.vectors, ids=lambda v: v.id)
def test_conformance_vectors_decode_the_same(vector):
    assert_same(MANIFEST.path(vector.stream))


@hyp_settings(40)
@given(seed=seeds, n=st.integers(1, 60), quant=st.integers(0, 31), period=st.sampled_from([None, 0, 1, 4, 17]),
       body=st.booleans(), face=st.booleans(), high=st.booleans(), optimize=st.booleans())
def test_random_streams_decode_the_same(seed, n, quant, period, body, face, high, optimize):
    rng = np.random.default_rng(seed)
    fap_mask = rng.random(68) < rng.choice([0.1, 0.5, 1.0]) if face or not body else None
    if fap_mask is not None and not high:
        fap_mask[:2] = False
    bap_mask = rng.random(296) < 0.2 if body else None
    s = make_stream(seed, n, fap_mask=fap_mask, bap_mask=bap_mask, fap_quant=quant)
    data = encode(s, EncodeOptions(fap_quant=quant, intra_period=period, optimize=optimize,
                                   start_codes=bool(seed % 2), skip_repeats=bool(seed % 3 == 0)))
    assert_same(data)
    for cut in sorted({1, len(data) // 3, len(data) // 2, len(data) - 1}):  # truncated anywhere
        assert_same(data[:cut])


def _corpus() -> list[bytes]:
    out = [MANIFEST.path(v.stream).read_bytes() for v in MANIFEST.vectors[::7]]
    out += [p.read_bytes() for p in real_vector_paths()[:6]]
    return out


def test_damaged_streams_fail_the_same_way():
    """Bit flips, byte changes and cuts: the same error at the same bit with the same frames before it."""
    rng = random.Random(1234)
    corpus = _corpus()
    errors = 0
    for _ in range(600):
        data = bytearray(rng.choice(corpus))
        for _ in range(rng.randint(1, 3)):
            kind = rng.random()
            i = rng.randrange(len(data))
            if kind < 0.5:
                data[i] ^= 1 << rng.randrange(8)
            elif kind < 0.8:
                data[i] = rng.randrange(256)
            else:
                del data[i:i + rng.randint(1, 40)]
            if not data:
                data = bytearray(b"\x00")
        errors += isinstance(assert_same(bytes(data)), FbaError)
    assert errors > 200  # most damage is found, and found alike


@pytest.mark.parametrize("chunk", [1, 3, 64, 4096])
def test_file_windows_of_any_size_give_the_same_stream(monkeypatch, chunk):
    """A file is read in windows; the compiled path must stop and go on at their edges."""
    from mpeg4fa.fba import bits, decoder

    monkeypatch.setattr(decoder, "BitReader", lambda src: bits.BitReader(src, chunk_bytes=chunk))
    paths = [MANIFEST.path(v.stream) for v in MANIFEST.vectors if v.expect == "decode"][::5]
    paths += real_vector_paths()[:3]
    for path in paths:
        data = path.read_bytes()
        monkeypatch.undo()
        whole = decode(data, backend="python")
        monkeypatch.setattr(decoder, "BitReader", lambda src: bits.BitReader(src, chunk_bytes=chunk))
        assert_same_stream(whole, decode(io.BytesIO(data), backend="compiled"))
        cut = data[: len(data) * 2 // 3]
        a, b = both(lambda: io.BytesIO(cut))
        assert type(a) is type(b) and (not isinstance(a, FbaError) or
                                       (a.message, a.bit_offset, a.frame) == (b.message, b.bit_offset, b.frame))


def test_iter_decode_gives_the_same_frames():
    data = encode(make_stream(5, 40, fap_mask=np.ones(68, dtype=bool), bap_mask=np.random.default_rng(5).random(296) < 0.3),
                  EncodeOptions(intra_period=9))
    for a, b in zip(iter_decode(data, backend="python"), iter_decode(data, backend="compiled"), strict=True):
        assert a.index == b.index and a.is_intra == b.is_intra and a.bits == b.bits
        for name in ("fap_mask", "fap_values", "viseme", "expression", "bap_mask", "bap_values"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        assert (a.timestamp, a.skip, a.start_code, a.object_mask) == (b.timestamp, b.skip, b.start_code, b.object_mask)


def test_backend_choice(monkeypatch):
    data = encode(make_stream(1, 3, fap_mask=np.ones(68, dtype=bool)))
    with pytest.raises(ValueError, match="backend"):
        decode(data, backend="fast")
    monkeypatch.setenv(compiled.ENV, "python")
    assert not compiled.available() and "MPEG4FA_CODEC" in compiled.why_not()
    with pytest.raises(FbaError, match="cannot run here"):
        decode(data, backend="compiled")
    assert len(decode(data)) == 3  # auto falls back to the reference


# ---- the encoder ---------------------------------------------------------------------------
def encode_both(stream, options=None):
    out = []
    for backend in ("python", "compiled"):
        try:
            out.append(encode(stream, options, backend=backend))
        except FbaError as exc:
            out.append(exc)
    a, b = out
    assert type(a) is type(b), (a, b)
    if isinstance(a, FbaError):
        assert (a.message, a.bit_offset, a.frame) == (b.message, b.bit_offset, b.frame)
    else:
        assert a == b
    return a


@pytest.mark.parametrize("vector", [v for v in MANIFEST.vectors if v.expect == "decode"], ids=lambda v: v.id)
def test_conformance_vectors_encode_the_same(vector):
    s = decode(MANIFEST.path(vector.stream))
    encode_both(s)  # (hand-made vectors, e.g. an end code with no stuffing, need not re-encode to their bytes)
    encode_both(s, EncodeOptions(optimize=True))
    encode_both(s, EncodeOptions(fap_quant=2, intra_period=5, start_codes=True))


@pytest.mark.parametrize("path", real_vector_paths(), ids=vector_id)
def test_real_vectors_encode_the_same(path):
    s = decode(path)
    assert encode_both(s) == path.read_bytes()
    encode_both(s, EncodeOptions(optimize=True, skip_repeats=True))


@hyp_settings(40)
@given(seed=seeds, n=st.integers(1, 50), quant=st.integers(0, 31), period=st.sampled_from([None, 0, 1, 3, 11]),
       body=st.booleans(), high=st.booleans(), optimize=st.booleans(), repeats=st.booleans())
def test_random_streams_encode_the_same(seed, n, quant, period, body, high, optimize, repeats):
    rng = np.random.default_rng(seed)
    fap_mask = rng.random(68) < rng.choice([0.1, 0.5, 1.0])
    if not high:
        fap_mask[:2] = False
    s = make_stream(seed, n, fap_mask=fap_mask, bap_mask=rng.random(296) < 0.2 if body else None, fap_quant=quant)
    encode_both(s, EncodeOptions(fap_quant=quant, intra_period=period, optimize=optimize, skip_repeats=repeats,
                                 start_codes=bool(seed % 2), time_codes=bool(seed % 3)))


def test_encoder_faults_are_the_same():
    """A change outside the coded range, a raw bit that is not a bit, a P frame with a part no intra set up."""
    s = decode(encode(make_stream(3, 12, fap_mask=np.ones(68, dtype=bool), bap_mask=np.ones(296, dtype=bool)),
                      EncodeOptions(intra_period=0)))
    wide = s.copy()
    wide.fap_values[7, 40] += 5000                      # FAP 41 jumps beyond its P range
    assert "FAP 41: change from the previous frame" in encode_both(wide).message
    body = s.copy()
    body.bap_values[5, 3] += 10 ** 6
    assert "BAP" in encode_both(body).message
    raw = s.copy()
    raw.viseme[4, 3] = 2                                # viseme_def is one bit
    assert encode_both(raw).message == "viseme_def = 2 does not fit in 1 bits"
    mask = s.copy()
    mask.object_mask[6] = 5
    assert "fba_object_mask = 5" in encode_both(mask).message
    face_only = decode(encode(make_stream(4, 6, fap_mask=np.ones(68, dtype=bool)), EncodeOptions(intra_period=0)))
    face_only.object_mask[3] = 3                         # body data in a P frame, no body intra
    assert "body data in a predicted frame" in encode_both(face_only).message


@hyp_settings(40)
@given(seed=seeds, n=st.integers(2, 80), q=st.integers(0, 8))
def test_closed_loop_levels_match_the_reference(seed, n, q):
    from mpeg4fa.fba.encoder import _period_levels

    rng = np.random.default_rng(seed)
    values = rng.integers(-3000, 3000, (n, 68)).astype(np.int32)
    qstep = np.asarray(rng.integers(0, 5, 68), dtype=np.int64) * q
    a, b = int(rng.integers(0, n - 1)), n
    np.testing.assert_array_equal(_period_levels(values, qstep, a, b, compiled=True),
                                  _period_levels(values, qstep, a, b, compiled=False))
