"""decode() holds a documented number of frames at most, in memory proportional to frames (issue 26
item 7: a 300 KB stream of tiny frames peaked at 469 MB); decoder and fastpath import one way."""
from __future__ import annotations

import ast
import mmap
from pathlib import Path

import numpy as np
import pytest

import mpeg4fa.fba as fba
from mpeg4fa.fba import EncodeOptions, FapStream, FbaError, decode, encode, iter_decode
from mpeg4fa.fba.limits import MAX_DECODE_FRAMES
from mpeg4fa.fba.stacking import StreamBuilder


def holds_only_its_rows(a: np.ndarray) -> bool:
    """``a`` is the whole of the memory under it (not a view into a larger block that stays alive)."""
    base = a
    while isinstance(base, np.ndarray) and base.base is not None:
        base = base.base
    return (len(base) if isinstance(base, mmap.mmap) else base.nbytes) == a.nbytes


def tiny_frames(n: int) -> bytes:
    """``n`` frames of about 6 bits each: one FAP, a value of -1, 0 or 1."""
    s = FapStream.empty(n)
    s.fap_mask[:, 2] = True
    s.fap_values[:, 2] = np.arange(n) % 3 - 1
    s.timestamps[:] = np.arange(n) / 25.0
    return encode(s, EncodeOptions(fps=25, intra_period=0))


@pytest.mark.parametrize("backend", ["python", "auto"])
def test_more_frames_than_the_ceiling_is_one_error_with_the_partial_stream(backend):
    data = tiny_frames(3000)
    assert len(decode(data, backend=backend, max_frames=3000)) == 3000
    with pytest.raises(FbaError, match="more than 2,000 frames") as info:
        decode(data, backend=backend, max_frames=2000)
    assert "iter_decode" in info.value.hint and len(info.value.partial) >= 2000
    assert sum(1 for _ in iter_decode(data, backend=backend)) == 3000  # no ceiling when streaming
    assert MAX_DECODE_FRAMES == 1 << 21


def test_builder_blocks_hold_only_their_rows():
    builder = StreamBuilder()
    for k in range(5):
        builder.add(fap_mask=np.ones(68, bool), fap_values=np.full(68, k, np.int32), viseme=np.zeros(4, np.int32),
                    expression=np.zeros(6, np.int32), timestamp=k / 25)
    stream = builder.build()
    assert len(stream) == 5 and stream.fap_values[:, 0].tolist() == [0, 1, 2, 3, 4]
    assert stream.fap_values.flags.writeable and holds_only_its_rows(stream.fap_values)


def test_decoder_and_fastpath_import_one_way():
    folder = Path(fba.__file__).parent
    imported = {node.module for node in ast.walk(ast.parse((folder / "decoder.py").read_text()))
                if isinstance(node, ast.ImportFrom) and node.module}
    assert not any("fastpath" in m or "decoding" in m for m in imported)
