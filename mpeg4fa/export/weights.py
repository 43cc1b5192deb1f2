"""Per-frame weights for today's avatar systems: the 52 ARKit blend shapes and the 15 Oculus/OVR visemes.

Both start from what a decoder shows (:func:`mpeg4fa.decoded.resolve`: held, interpolated,
FAP 1/2 expanded, clamped), so a stream exports as it plays:

* **ARKit** (:func:`arkit_weights`): the weights the ARKit deformer drives the head's sculpted face
  units with (:func:`mpeg4fa.face.deformers.arkit.unit_weights`, from ``face/data/arkit_faps.csv``),
  so an avatar with the 52 standard blend shapes moves as ``--deformer arkit`` shows our head (one
  weight per unit, the sides of a unit driven per side averaged: :mod:`.arkit_units`, shared with
  the glTF export's morph targets). The deformer leaves the
  lids to the feature-point layer, so ``eyeBlinkLeft``/``Right`` are the top lid FAPs
  (``close_t_l_eyelid``, ``close_t_r_eyelid``) over one IRISD0 (1024 IRISD units: the lid covers
  the iris), clipped to 0..1. Blend shapes nothing drives stay 0. Needs a head with the ARKit units
  (the generic head). :func:`viseme_arkit_table` gives every viseme's (both sets') ARKit weights
  at full strength: the viseme -> ARKit map, read off the head.
* **Oculus/OVR** (:func:`oculus_weights`): the 15 visemes' weights per frame, summing to 1. A
  stream that sends FAP 1 and no mouth FAPs gives them straight from FAP 1's fields (``select1``
  weighs ``blend/63``, ``select2`` the rest); any other stream (low-level visemes, Chinese visemes,
  recordings) is fitted: the mouth FAPs of the frame as a non-negative mix of the MPEG-4 viseme
  profiles (``spec/viseme_faps.csv``), silence taking what the mix leaves of 1. The OVR set is the
  MPEG-4 set renamed (``spec/oculus_visemes.csv``).

JSON written by :func:`write_weights_json` (UTF-8, atomic)::

    {"format": "mpeg4fa-arkit-weights" | "mpeg4fa-oculus-weights", "version": 1,
     "fps": 25.0,                       # frames per second of the times below (the stream's, or asked)
     "names": ["eyeBlinkLeft", ...],    # 52 ARKit names (Azure's blend-shape order) or 15 OVR visemes
     "frames": [{"time": 0.0, "weights": [0.0, ...]}, ...]}   # seconds from the first frame; 0..1

``weights[k]`` goes with ``names[k]``; values are rounded to 4 decimals.
"""
from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.optimize import nnls

from mpeg4fa.atomic import atomic_output
from mpeg4fa.decoded import held_high_level, resolve
from mpeg4fa.fba.stream import FapStream
from mpeg4fa.render.timing import presentation_times
from mpeg4fa.spec import FAP_BY_NAME, FAPU, FULL_INTENSITY, VISEMES
from mpeg4fa.spec.avatars import ARKIT_BLENDSHAPES, OCULUS_VISEMES
from mpeg4fa.spec.errors import SpecError
from mpeg4fa.spec.profiles import VISEME_PROFILES

__all__ = ["Weights", "viseme_weights", "oculus_weights", "arkit_weights", "viseme_arkit_table", "write_weights_json",
           "weights_document", "OCULUS_NAMES"]

OCULUS_NAMES = tuple(v.name for v in OCULUS_VISEMES)
"""The 15 OVR viseme names in their index order."""
_MPEG4_NAMES = tuple(v.name for v in VISEMES)
_OVR_ORDER = np.array([_MPEG4_NAMES.index(v.mpeg4) for v in OCULUS_VISEMES])
_PROFILES = np.stack([VISEME_PROFILES["mpeg4"][n] for n in _MPEG4_NAMES]).astype(np.float64)  # (15, 68)
_MOUTH = np.flatnonzero(np.abs(_PROFILES).max(axis=0) > 0)
"""The FAP columns any viseme moves: what the fit looks at."""
_LIDS = {"eyeBlinkLeft": FAP_BY_NAME["close_t_l_eyelid"].number - 1,
         "eyeBlinkRight": FAP_BY_NAME["close_t_r_eyelid"].number - 1}
_LID_SHUT = float(FAPU["IRISD"].divisor)


@dataclass(frozen=True)
class Weights:
    """Per-frame weights: ``values[k, j]`` of ``names[j]`` at ``times[k]`` seconds."""

    kind: str
    """``arkit`` or ``oculus``."""
    names: tuple[str, ...]
    times: np.ndarray
    values: np.ndarray
    fps: float


def _fap1_weights(stream: FapStream) -> np.ndarray:
    """(n, 15) MPEG-4 viseme weights from FAP 1's fields as the decoder holds them."""
    n = len(stream)
    fields = held_high_level(stream)[0]
    bad = np.flatnonzero((fields[:, :2] < 0).any(axis=1) | (fields[:, :2] >= len(_MPEG4_NAMES)).any(axis=1))
    if len(bad):
        k = int(bad[0])
        raise SpecError(f"FAP 1 selects {fields[k, 0]}, {fields[k, 1]}: not visemes (0..{len(_MPEG4_NAMES) - 1})",
                        where=f"frame {k}")
    w1 = np.clip(fields[:, 2] / FULL_INTENSITY, 0.0, 1.0)
    out = np.zeros((n, len(_MPEG4_NAMES)))
    rows = np.arange(n)
    np.add.at(out, (rows, fields[:, 0]), w1)
    np.add.at(out, (rows, fields[:, 1]), 1.0 - w1)
    return out


def _fitted_weights(values: np.ndarray) -> np.ndarray:
    """(n, 15) MPEG-4 viseme weights: each frame's mouth FAPs as a non-negative mix of the profiles."""
    basis = _PROFILES[1:, _MOUTH].T  # (mouth FAPs, 14): every viseme but none
    out = np.zeros((len(values), len(_MPEG4_NAMES)))
    for k, frame in enumerate(values[:, _MOUTH]):
        if np.any(frame):
            out[k, 1:] = nnls(basis, frame)[0]
    total = out.sum(axis=1)
    over = total > 1.0
    out[over] /= total[over, None]
    out[:, 0] = 1.0 - out[:, 1:].sum(axis=1)
    return out


def viseme_weights(stream: FapStream, values: np.ndarray | None = None) -> np.ndarray:
    """(n, 15) weights of the MPEG-4 visemes (``visemes.csv`` order, ``none`` first) at each frame; rows sum to 1.

    From FAP 1 when the stream sends it and no mouth FAP, else fitted (see the module docstring);
    ``values`` is :func:`~mpeg4fa.decoded.resolve` of the stream when the caller has it.
    """
    shown = resolve(stream) if values is None else values
    if not len(stream):
        return np.zeros((0, len(_MPEG4_NAMES)))
    if stream.fap_mask[:, 0].any() and not stream.fap_mask[:, _MOUTH].any():
        return _fap1_weights(stream)
    return _fitted_weights(shown)


def oculus_weights(stream: FapStream, fps: float | None = None) -> Weights:
    """The 15 OVR visemes' weights per frame (``fps``: resampled to that rate, else the stream's frames)."""
    w = viseme_weights(stream)[:, _OVR_ORDER]
    return _resampled(Weights("oculus", OCULUS_NAMES, presentation_times(stream), w, stream.fps), stream, fps)


def arkit_weights(stream: FapStream, face, fps: float | None = None) -> Weights:
    """The 52 ARKit blend shapes' weights per frame on ``face`` (a :class:`~mpeg4fa.face.FaceModel` whose head
    carries the ARKit units), as its ARKit deformer drives them (see the module docstring)."""
    from mpeg4fa.export.arkit_units import arkit_units

    units = arkit_units(face)
    values = resolve(stream)
    missing = sorted(set(units.names) - set(ARKIT_BLENDSHAPES))
    if missing:
        raise SpecError(f"the head's face units {missing} are no ARKit blend shapes",
                        where="spec/arkit_blendshapes.csv", hint="name the units as ARKit does")
    out = np.zeros((len(values), len(ARKIT_BLENDSHAPES)))
    if len(values):
        out[:, [ARKIT_BLENDSHAPES.index(n) for n in units.names]] = units.weights(values)
    for name, column in _LIDS.items():
        out[:, ARKIT_BLENDSHAPES.index(name)] = np.clip(values[:, column] / _LID_SHUT, 0.0, 1.0)
    return _resampled(Weights("arkit", ARKIT_BLENDSHAPES, presentation_times(stream), out, stream.fps), stream, fps)


def viseme_arkit_table(face) -> dict[tuple[str, str], np.ndarray]:
    """``(set, viseme)`` -> its 52 ARKit weights at full strength on ``face``, for every viseme of every set
    (``mpeg4`` and ``zh``): the map for driving an ARKit avatar from viseme events, as the head shows them."""
    names = [(set_name, viseme) for set_name, visemes in VISEME_PROFILES.items() for viseme in visemes]
    frames = np.stack([VISEME_PROFILES[s][v] for s, v in names]).astype(np.float64)
    stream = FapStream.empty(len(names))
    stream.source_fps = 1.0
    stream.timestamps[:] = np.arange(len(names))
    moved = np.flatnonzero(np.abs(frames).max(axis=0) > 0)
    stream.fap_mask[:, moved] = True
    stream.fap_values[:, moved] = frames[:, moved]
    weights = arkit_weights(stream, face).values
    return {key: weights[k] for k, key in enumerate(names)}


def _resampled(weights: Weights, stream: FapStream, fps: float | None) -> Weights:
    """At ``fps`` the frame each output tick shows (the player's schedule: :func:`mpeg4fa.render.timing.schedule`)."""
    if fps is None or not len(stream):
        return weights
    from mpeg4fa.render.timing import MAX_HELD_FRAMES, schedule

    plan = schedule(stream, fps, max_frames=MAX_HELD_FRAMES)  # every tick's weights are held, then written
    return Weights(weights.kind, weights.names, np.arange(plan.n_frames) / plan.fps, weights.values[plan.source],
                   plan.fps)


def weights_document(weights: Weights) -> dict:
    """The JSON document of :func:`write_weights_json` as a dict."""
    values = np.round(weights.values, 4) + 0.0  # + 0.0: no -0.0 in the file
    return {"format": f"mpeg4fa-{weights.kind}-weights", "version": 1, "fps": float(weights.fps),
            "names": list(weights.names),
            "frames": [{"time": round(float(t), 6), "weights": row.tolist()} for t, row in zip(weights.times, values)]}


_WRITE_ROWS = 4096
"""Frames turned into JSON text at a time: the text of a whole long export never sits in memory at once."""


def write_weights_json(weights: Weights, path: str | os.PathLike) -> None:
    """Write the weights as JSON (schema in the module docstring), atomically; the same bytes as
    ``json.dumps(weights_document(weights), separators=(",", ":"))`` and a newline, written a block of frames at a
    time (a million frames, the schedule's most, built as one document took 3.3 GB)."""
    head = weights_document(Weights(weights.kind, weights.names, weights.times[:0], weights.values[:0], weights.fps))
    opening = json.dumps(head, separators=(",", ":"))
    assert opening.endswith('"frames":[]}')
    with atomic_output(path) as partial, open(partial, "w", encoding="utf-8") as out:
        out.write(opening[:-2])
        for start in range(0, len(weights.times), _WRITE_ROWS):
            block = Weights(weights.kind, weights.names, weights.times[start:start + _WRITE_ROWS],
                            weights.values[start:start + _WRITE_ROWS], weights.fps)
            rows = json.dumps(weights_document(block)["frames"], separators=(",", ":"))[1:-1]
            out.write(("," if start else "") + rows)
        out.write("]}\n")
