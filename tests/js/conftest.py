"""Helpers for the fba.js tests: run Node on many files at once and compare with the Python decoder."""
from __future__ import annotations

import functools
import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
DUMP = Path(__file__).with_name("dump.mjs")
SHARED = ROOT.parent / "shared" / "vectors" / "fba"
NODE = shutil.which("node")


def need_node() -> str:
    if NODE is None:
        pytest.skip("node is not installed (Debian: apt-get install nodejs): fba.js is tested in Node")
    return NODE


def js_decode(paths: list[Path], chunk: int = 0, shown: bool = False) -> dict[str, dict]:
    """fba.js's answer per path (one Node process for all of them); ``chunk`` feeds bytes in pieces,
    ``shown`` adds the values shown.js shows."""
    cmd = [need_node(), str(DUMP)] + (["--shown"] if shown else []) + (["--chunk", str(chunk)] if chunk else []) \
        + [str(p) for p in paths]
    run = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    out = {}
    for line in run.stdout.splitlines():
        doc = json.loads(line)
        out[doc["path"]] = doc
    return out


@functools.lru_cache(maxsize=None)
def python_decode(path: Path):
    """(stream, error) from the Python reference decoder; on a fault the stream is the partial one."""
    from mpeg4fa.fba import FbaError, decode

    try:
        return decode(path, backend="python"), None
    except FbaError as exc:
        return exc.partial, exc


def compare(path: Path, js: dict) -> None:
    """Assert fba.js decoded ``path`` as the Python decoder does: frames, fields, times, errors."""
    stream, error = python_decode(path)
    frames = js["frames"]
    n = 0 if stream is None else len(stream)
    assert len(frames) == n, f"{path}: {len(frames)} frames in JS, {n} in Python"
    if error is None:
        assert js["error"] is None, f"{path}: JS refused it: {js['error']}"
        assert js["osc"] == stream.object_start_code
    else:
        assert js["error"] is not None, f"{path}: JS decoded what Python refuses: {error}"
        assert js["error"]["text"] == str(error), path
        assert (js["error"]["bit"], js["error"]["frame"]) == (error.bit_offset, error.frame), path
    if not n:
        return
    np.testing.assert_array_equal([f["t"] for f in frames], stream.timestamps, err_msg=str(path))
    for name, key in (("fap_mask", "mask"), ("fap_values", "values"), ("viseme", "viseme"),
                      ("expression", "expression")):
        np.testing.assert_array_equal(np.array([f[key] for f in frames]), getattr(stream, name).astype(np.int64),
                                      err_msg=f"{path}: {name}")
    for name, key in (("object_mask", "om"), ("skip", "skip"), ("start_code", "sc"), ("bits", "bits")):
        np.testing.assert_array_equal([f[key] for f in frames], getattr(stream, name), err_msg=f"{path}: {name}")
    assert [k for k, f in enumerate(frames) if f["intra"]] == sorted(stream.intra), path
    for k, f in enumerate(frames):
        cols = np.flatnonzero(stream.bap_mask[k])
        assert [c for c, _ in f["baps"]] == cols.tolist(), f"{path} frame {k}: BAP mask"
        assert [v for _, v in f["baps"]] == stream.bap_values[k, cols].tolist(), f"{path} frame {k}: BAP values"
