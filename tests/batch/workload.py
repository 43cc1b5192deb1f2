"""Inputs for the batch tests and tools/bench_batch.py, made here: streams, speech, a face mesh, an FDP.

Streams are encoded with the codec from FAP values computed here (the jaw and the lips move on
a sine, each stream with its own phase); the face is the procedural head's skin written as an
OBJ with its feature points (``play --face-mesh``), so nothing needs the generic head.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from mpeg4fa.fba import FapStream, encode
from mpeg4fa.fdp import Fdp, save_fdp
from mpeg4fa.wav import write_pcm16
from procedural_head import build_procedural_head

MOVED = {3: 500.0, 4: -250.0, 5: 250.0, 12: 120.0, 13: 120.0}
"""Low-level FAP -> amplitude (FAPU): open_jaw, the lip midpoints, the lip corners."""


def talk_stream(seconds: float, phase: float = 0.0, fps: float = 25.0) -> FapStream:
    """A stream of ``seconds`` whose jaw and lips open and close about twice a second."""
    n = max(int(round(seconds * fps)), 1)
    s = FapStream.empty(n)
    s.source_fps = fps
    s.timestamps[:] = np.arange(n) / fps
    wave = 0.5 - 0.5 * np.cos(2 * np.pi * 2.0 * np.arange(n) / fps + phase)
    for fap, amplitude in MOVED.items():
        s.fap_mask[:, fap - 1] = True
        s.fap_values[:, fap - 1] = np.round(amplitude * wave)
    return s


def write_stream(path: Path, seconds: float, phase: float = 0.0) -> Path:
    path.write_bytes(encode(talk_stream(seconds, phase)))
    return path


def write_tone(path: Path, seconds: float, rate: int = 16000) -> Path:
    t = np.arange(int(round(seconds * rate))) / rate
    write_pcm16(path, (8000 * np.sin(2 * np.pi * 220 * t)).astype(np.int16), rate)
    return path


def write_face(folder: Path) -> tuple[Path, Path]:
    """The procedural head's skin as ``head.obj`` and its feature points as ``points.json``."""
    head = build_procedural_head()
    lo, hi = head.part_ranges["skin"]
    vertices = head.vertices[lo:hi]
    triangles = head.triangles["skin"] - lo
    points = {label: int(v - lo) for label, v in zip(head.fp_labels, head.fp_vertex) if lo <= v < hi}
    for eye in ("3.5", "3.6"):  # the pupils are on the eyeballs, left out: given as coordinates
        points[eye] = head.fp(eye).tolist()
    obj, pts = folder / "head.obj", folder / "points.json"
    lines = [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in vertices]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in triangles]
    obj.write_text("\n".join(lines) + "\n")
    pts.write_text(json.dumps(points))
    return obj, pts


def write_fdp(path: Path, points: Path, obj: Path, widen: float = 1.08) -> Path:
    """An FDP whose feature points are the mesh's, the face made ``widen`` times wider (x)."""
    from mpeg4fa.fdp import read_obj

    vertices = read_obj(obj).vertices
    given = json.loads(points.read_text())
    labels = sorted(given)
    xyz = np.array([vertices[given[k]] if isinstance(given[k], int) else given[k] for k in labels], float)
    xyz[:, 0] *= widen
    save_fdp(Fdp(labels=tuple(labels), points=xyz), path)
    return path
