"""Build the whole suite into a folder: faces, streams, expected results and ``manifest.json``.

Expected results never come from this project's decoder: "sent" is what the generator sent (its
values are exact multiples of their steps, checked here, so quantisation loses nothing), timestamps
follow the rule of ``spec/SYNTAX.md`` section 4 from the headers sent, "shown" and feature points come
from :mod:`mpeg4fa.conformance.reference`. The decoder is only run afterwards, as a check: a vector
it disagrees with stops the generator (a bug in a vector or in the codec, never written out).
Output is byte-identical from run to run (sorted keys, fixed rounding, no times or paths inside).
"""
from __future__ import annotations

import json
import math
import shutil
from pathlib import Path
from typing import Any

import numpy as np

from mpeg4fa.conformance import reference
from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.faces import TEMPLATE, read_template, write_faces
from mpeg4fa.conformance.rules import check_rules
from mpeg4fa.conformance.manifest import Face, Manifest, Vector, compact, default_root, sha256
from mpeg4fa.conformance.vectors import Broken, Built, VectorDef, all_vectors
from mpeg4fa.fba import FbaError, FapStream, decode
from mpeg4fa.fba.stream import DEFAULT_FPS
from mpeg4fa.spec import BAP_PRED_SCALE, BAP_QUANT_STEP, QUANT_STEP

DIGITS = 9
"""Decimal places kept for floats in expected files (shown values, positions, tolerances)."""


def _number(x: float) -> float | int:
    """A float as stored: an int when it is one, else rounded to :data:`DIGITS` places; never -0."""
    x = float(x)
    if x.is_integer() and abs(x) < 2 ** 53:
        return int(x)
    return round(x, DIGITS) + 0.0


def _numbers(a: np.ndarray) -> list:
    flat = [_number(x) for x in np.asarray(a, dtype=np.float64).ravel()]
    return np.array(flat, dtype=object).reshape(np.shape(a)).tolist()


def _ints(a: np.ndarray) -> list:
    return np.asarray(a).astype(np.int64).tolist()


def presentation_times(s: FapStream) -> np.ndarray:
    """Timestamps the headers sent imply (SYNTAX.md 4): a time code anchors its plane, otherwise the
    plane follows the one before by (its skip count + 1) frames at the latest rate sent (30 before any)."""
    fps, next_time = DEFAULT_FPS, 0.0
    out = np.zeros(len(s))
    for k in range(len(s)):
        params = s.intra.get(k)
        if params is not None and params.frame_rate is not None:
            fps = params.frame_rate.fps
        t = float(params.time_code.total_seconds) if params is not None and params.time_code is not None else next_time
        out[k] = t
        next_time = t + (int(s.skip[k]) + 1) / fps
    return out


def time_coded(s: FapStream) -> list[int]:
    """Frames whose plane sends a time code (their time is the code's; the frames after them follow it by a
    rule the sources do not settle, so the runner checks those apart: ``timestamps_after_time_code``)."""
    return sorted(k for k, params in s.intra.items() if params is not None and params.time_code is not None)


def _check_lossless(v: VectorDef, s: FapStream) -> None:
    """Every value sent is an exact multiple of its step under the quantiser of its intra period."""
    starts = sorted(s.intra)
    for i, a in enumerate(starts):
        b = starts[i + 1] if i + 1 < len(starts) else len(s)
        p = s.intra[a]
        if p.face is not None and p.face.quant:
            q = p.face.quant
            steps = np.asarray(QUANT_STEP, dtype=np.int64) * q
            rows = s.fap_values[a:b].astype(np.int64)
            bad = s.fap_mask[a:b, 2:] & (rows[:, 2:] % steps[2:] != 0)
            if bad.any() or (s.fap_mask[a:b, 0] & (s.viseme[a:b, 2] % q != 0)).any() \
                    or (s.fap_mask[a:b, 1][:, None] & (s.expression[a:b][:, [1, 3]] % q != 0)).any():
                raise ConformanceError("a value sent is not a multiple of its step: quantisation would lose it",
                                       where=v.id)
        if p.body is not None and p.body.quant:
            steps = np.asarray(BAP_QUANT_STEP, dtype=np.int64) * int(BAP_PRED_SCALE[p.body.quant])
            if (s.bap_mask[a:b] & (s.bap_values[a:b].astype(np.int64) % steps != 0)).any():
                raise ConformanceError("a BAP value sent is not a multiple of its step", where=v.id)


def _sent(s: FapStream) -> dict[str, np.ndarray]:
    mask = s.fap_mask.astype(bool)
    return {"mask": mask.astype(np.int64),
            "values": np.where(mask, s.fap_values, 0).astype(np.int64),
            "viseme": np.where(mask[:, :1], s.viseme, 0).astype(np.int64),
            "expression": np.where(mask[:, 1:2], s.expression, 0).astype(np.int64)}


def _feature_points(neutral: dict[str, np.ndarray], shown: np.ndarray) -> dict[str, Any] | None:
    """Expected positions of every point the shown values drive, with the components the standard pins per
    frame (:func:`reference.checkable`: a decoder may move a point off a FAP's axis, e.g. open_jaw as a
    rotation, so only the axis is checked); None when no component of any frame is pinned."""
    moved = reference.feature_point_positions(neutral, shown)
    pinned = reference.checkable(neutral, shown)
    labels = [label for label in moved if pinned[label].any()]
    if not labels:
        return None
    return {"labels": labels, "checkable": _ints(np.stack([pinned[label] for label in labels], axis=1)),
            "positions": _numbers(np.stack([moved[label] for label in labels], axis=1))}


def _used_columns(sent: dict[str, np.ndarray], shown: np.ndarray) -> list[int]:
    """FAP columns the vector sends or shows anything in (the others are stored implicitly, :func:`compact`)."""
    return np.flatnonzero(sent["mask"].any(axis=0) | (shown != 0).any(axis=0)).tolist()


def expected_decode(v: VectorDef, built: Built, neutral: dict[str, np.ndarray] | None) -> dict[str, Any]:
    s = built.stream
    _check_lossless(v, s)
    sent = _sent(s)
    shown = reference.shown_values(sent["mask"], sent["values"], sent["viseme"], sent["expression"],
                                   s.group_mask_types())
    doc: dict[str, Any] = {"frames": len(s), "fps": s.fps, "timestamps": presentation_times(s).tolist(),
                           "sent": {k: _ints(a) for k, a in sent.items()}, "shown": _numbers(shown),
                           "tolerance": {"shown": reference.TOLERANCE["shown"]}}
    coded = time_coded(s)
    if coded:
        doc["time_coded"] = coded
    if neutral is not None:
        fp = _feature_points(neutral, shown)
        if fp is not None:
            doc["feature_points"] = fp
            doc["tolerance"]["feature_points"] = _number(reference.feature_point_tolerance(neutral))
    _verify_decode(v, built.data, doc)
    return compact(doc, _used_columns(sent, shown))


def _verify_decode(v: VectorDef, data: bytes, doc: dict[str, Any]) -> None:
    """Our decoder must give exactly what was sent (a disagreement is a bug: stop)."""
    try:
        got = decode(data)
    except FbaError as exc:
        raise ConformanceError(f"our decoder rejects a vector meant to decode: {exc}", where=v.id) from None
    sent = _sent(got)
    same = len(got) == doc["frames"] and all(np.array_equal(sent[k], np.asarray(doc["sent"][k])) for k in sent) \
        and np.array_equal(got.timestamps, np.asarray(doc["timestamps"])) and math.isclose(got.fps, doc["fps"])
    if not same:
        raise ConformanceError("our decoder disagrees with what the generator sent", where=v.id)


def expected_reject(v: VectorDef, broken: Broken) -> dict[str, Any]:
    try:
        decode(broken.data)
    except FbaError as exc:
        frames = len(exc.partial) if exc.partial is not None else 0
        if exc.bit_offset != broken.bit_offset or frames != broken.frames_before:
            raise ConformanceError(f"our decoder rejects at bit {exc.bit_offset} after {frames} frames, the vector "
                                   f"argues bit {broken.bit_offset} after {broken.frames_before}", where=v.id) from None
        return {"reject": True, "bit_offset": broken.bit_offset, "frames_before": broken.frames_before}
    raise ConformanceError("our decoder accepts a vector it must reject", where=v.id)


def _dump(doc: dict[str, Any]) -> bytes:
    return (json.dumps(doc, sort_keys=True, separators=(",", ":"), allow_nan=False) + "\n").encode("utf-8")


def generate(out: str | Path | None = None, template: str | Path | None = None) -> Manifest:
    """Write the suite into ``out`` (default: the committed ``conformance/``) and return its manifest.

    Files of an older run under ``out/vectors`` that this run does not make are removed.
    """
    root = Path(out) if out is not None else default_root()
    source = Path(template) if template is not None else default_root() / TEMPLATE
    root.mkdir(parents=True, exist_ok=True)
    points = read_template(source)
    target = root / TEMPLATE
    target.parent.mkdir(parents=True, exist_ok=True)
    if not target.exists() or target.resolve() != source.resolve():
        shutil.copyfile(source, target)
    manifest = Manifest(root)
    faces = write_faces(root, points)
    for name, (spec, _, rel) in faces.items():
        manifest.faces[name] = Face(name, rel, sha256(root / rel), spec.description)
    written = set()
    for v in all_vectors():
        built = v.build()
        stream_rel = f"vectors/{v.id}.fba"
        expected_rel = f"vectors/{v.id}.expected.json"
        if isinstance(built, Broken):
            doc, data = expected_reject(v, built), built.data
        else:
            neutral = faces[v.face][1] if v.face else None
            doc, data = expected_decode(v, built, neutral), built.data
        for rel, payload in ((stream_rel, data), (expected_rel, _dump(doc))):
            path = root / rel
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(payload)
            written.add(path.resolve())
        manifest.vectors.append(Vector(
            id=v.id, group=v.group, confidence=v.confidence, description=v.description, stream=stream_rel,
            sha256=sha256(root / stream_rel), expect=v.expect, expected=expected_rel,
            expected_sha256=sha256(root / expected_rel), face=v.face, rules=v.rules,
            checks=tuple(sorted(check_rules(v.id, v.confidence).items()))))
    for path in sorted((root / "vectors").rglob("*")):
        if path.is_file() and path.resolve() not in written:
            path.unlink()
    manifest.save()
    return manifest
