"""Deliberately broken decoders, made from this project's own, for the suite's self-test.

Each fault is a mistake real FBA decoders make (issue 13): a suite that passes them is not
testing anything. A faulty decoder decodes with :mod:`.adapter` and then goes wrong in one place:

* in the **stream** it decoded (values in the wrong columns, a wrong quantiser step, no
  interpolation, the frame rate): then the sent fields, the shown values and the feature points
  all carry the mistake;
* in the **shown values** (a sign flipped on one FAP): shown values and feature points;
* in the **geometry** only (a FAPU measured wrong, AU off by 10x, FAP 19 scaled with MNS): the
  values are right, the feature points move by the wrong amount.

Feature points (when the vector has a face) come from the suite's reference model
(:func:`mpeg4fa.conformance.reference.feature_point_positions`) fed with the values the faulty
decoder would move the face by, so a fault is caught (or not) by the same rules the expected
files follow, without the face engine and whether or not the generic head is installed;
``feature_points="engine"`` poses this project's face engine instead (needs the head).
"""
from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path
from typing import Callable

import numpy as np

from mpeg4fa.conformance.adapter import decode_stream, face_feature_points, sent_fields, shown
from mpeg4fa.conformance.protocol import DecoderOutput, InProcessDecoder
from mpeg4fa.fba import FapStream
from mpeg4fa.spec import FAP_PARTNERS, FAPS, QUANT_STEP

SIGN_FLIPPED_FAP = 5
"""raise_b_midlip: bidirectional, one point (2.3), sent by the semantics vectors."""
_COLUMNS_WITH = {unit: np.array([k for k, f in enumerate(FAPS) if f.fapu == unit]) for unit in ("IRISD", "AU")}


@dataclass(frozen=True)
class Fault:
    """A named mistake: ``stream`` changes the decoded stream, ``shown`` the shown values,
    ``geometry(values, fapu)`` the values the face is moved by (``fapu``: the face's units)."""

    name: str
    description: str
    stream: Callable[[FapStream], FapStream] | None = None
    shown: Callable[[np.ndarray], np.ndarray] | None = None
    geometry: Callable[[np.ndarray, dict[str, float]], np.ndarray] | None = None


# ---- the mistakes -------------------------------------------------------------------------

def _swap_left_right(stream: FapStream) -> FapStream:
    """Every sided FAP's value lands in its counterpart's column (the decoder's table has l/r swapped)."""
    perm = np.where(FAP_PARTNERS[:, 0] >= 0, FAP_PARTNERS[:, 0], np.arange(len(FAP_PARTNERS)))
    out = stream.copy()
    out.fap_mask, out.fap_values = stream.fap_mask[:, perm].copy(), stream.fap_values[:, perm].copy()
    return out


def _quant_without_table(stream: FapStream) -> FapStream:
    """Dequantised with ``fap_quant`` alone, the per-FAP step (QUANT_STEP) left out."""
    out = stream.copy()
    quant = np.zeros(len(stream), dtype=np.int64)
    for start in sorted(stream.intra):
        if stream.intra[start].face is not None:
            quant[start:] = stream.intra[start].face.quant
    steps = np.asarray(QUANT_STEP, dtype=np.int64)
    wrong = (quant[:, None] > 0) & (steps[None, :] != 1)
    out.fap_values = np.where(wrong, np.rint(stream.fap_values / steps[None, :]), stream.fap_values).astype(
        stream.fap_values.dtype)
    return out


def _hold_not_interpolate(stream: FapStream) -> FapStream:
    """Mask type 2 read as 1: an unsent FAP holds instead of copying its counterpart."""
    out = stream.copy()

    def hold(types):
        return tuple(1 if t == 2 else t for t in types)

    for k, params in out.intra.items():
        if params.face is not None:
            out.intra[k] = replace(params, face=replace(params.face, mask_types=hold(params.face.mask_types)))
    if out.mask_types is not None:
        out.mask_types = hold(out.mask_types)
    return out


def _ntsc_as_zero(stream: FapStream) -> FapStream:
    """1000/1001 in integer arithmetic is 0: with the offset flag the frame rate is 0, every frame at t = 0."""
    rates = [p.frame_rate for p in stream.intra.values() if p.frame_rate is not None]
    if not any(r.frequency_offset for r in rates):
        return stream
    out = stream.copy()
    out.timestamps = np.zeros_like(stream.timestamps)
    return out


def _ntsc_ignored(stream: FapStream) -> FapStream:
    """The frequency_offset flag ignored: frames timed at the nominal rate (30, not 30000/1001)."""
    rates = [p.frame_rate for p in stream.intra.values() if p.frame_rate is not None]
    if not any(r.frequency_offset for r in rates):
        return stream
    out = stream.copy()
    out.timestamps = stream.timestamps * (1000 / 1001)
    return out


def _flip_sign(values: np.ndarray) -> np.ndarray:
    out = values.copy()
    out[:, SIGN_FLIPPED_FAP - 1] *= -1
    return out


def _scale(columns: np.ndarray, factor: Callable[[dict[str, float]], float]):
    def geometry(values: np.ndarray, fapu: dict[str, float]) -> np.ndarray:
        out = values.copy()
        ratio = factor(fapu)
        if np.isfinite(ratio):
            out[:, columns] *= ratio
        return out
    return geometry


def _ratio(wrong: str, right: str) -> Callable[[dict[str, float]], float]:
    return lambda fapu: fapu.get(wrong, np.nan) / fapu.get(right, np.nan)


FAULTS: dict[str, Fault] = {f.name: f for f in (
    Fault("fapu-es-for-irisd", "IRISD FAPs (eyelids, pupils) scaled with ES instead of IRISD",
          geometry=_scale(_COLUMNS_WITH["IRISD"], _ratio("ES0", "IRISD0"))),
    Fault("left-right-swapped", "left and right FAPs swapped", stream=_swap_left_right),
    Fault("sign-flipped", f"FAP {SIGN_FLIPPED_FAP} shown with the opposite sign", shown=_flip_sign),
    Fault("quant-step", "dequantised with fap_quant alone (the per-FAP step left out)", stream=_quant_without_table),
    Fault("au-10x", "angles in units of 1e-4 rad (AU off by 10x)",
          geometry=_scale(_COLUMNS_WITH["AU"], lambda fapu: 10.0)),
    Fault("fap19-mns", "FAP 19 scaled with MNS instead of IRISD",
          geometry=_scale(np.array([18]), _ratio("MNS0", "IRISD0"))),
    Fault("ntsc-zero", "1000/1001 computed as 0 (timestamps of 29.97-type rates)", stream=_ntsc_as_zero),
    Fault("ntsc-ignored", "the 1000/1001 frequency offset left out (29.97 timed as 30)", stream=_ntsc_ignored),
    Fault("hold-not-interpolate", "mask type 2 (interpolate) read as hold", stream=_hold_not_interpolate),
)}


# ---- as decoders ----------------------------------------------------------------------------

def _neutral(fdp: Path) -> dict[str, np.ndarray]:
    from mpeg4fa.fdp import load_fdp

    face = load_fdp(fdp)
    return {label: np.asarray(face.points[i], dtype=np.float64) for i, label in enumerate(face.labels)}


def reference_feature_points(fdp: Path, values: np.ndarray) -> tuple[tuple[str, ...], np.ndarray]:
    """Feature points the suite's reference model gives for a face moved by ``values``."""
    from mpeg4fa.conformance.reference import feature_point_positions

    points = feature_point_positions(_neutral(fdp), values)
    labels = tuple(points)
    positions = np.stack([points[label] for label in labels], axis=1) if labels else np.zeros((len(values), 0, 3))
    return labels, positions


def faulty_decoder(name: str, *, feature_points: str = "reference") -> InProcessDecoder:
    """This project's decoder with fault ``name`` planted (see :data:`FAULTS`)."""
    fault = FAULTS[name]

    def decode(stream_path: Path, fdp: Path | None) -> DecoderOutput:
        stream = decode_stream(stream_path)
        if fault.stream is not None:
            stream = fault.stream(stream)
        values = shown(stream)
        if fault.shown is not None:
            values = fault.shown(values)
        output = DecoderOutput(stream.timestamps.astype(np.float64), values, sent_fields(stream))
        if fdp is not None:
            moved = values
            if fault.geometry is not None:
                from mpeg4fa.conformance.reference_fapu import fapu_from_points

                moved = fault.geometry(values, fapu_from_points(_neutral(fdp)))
            source = reference_feature_points if feature_points == "reference" else face_feature_points
            output.fp_labels, output.fp_positions = source(fdp, moved)
        return output

    return InProcessDecoder(decode, name=f"mpeg4fa with fault {name}")

