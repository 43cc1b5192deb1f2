"""A decoder's answer against a vector's expected file: one :class:`Check` per thing the suite tests.

Checks, and why each is or is not optional:

* ``timestamps``, ``shown`` (required): when each frame is shown and the 68 values it shows are
  what every decoder must get right; tolerances come from the expected file (``tolerance.shown``,
  FAPU units; timestamps :data:`TIMESTAMP_TOLERANCE` seconds unless ``tolerance.timestamps``);
* ``sent`` (optional): the bitstream-level fields, exact; a decoder need not report them;
* ``feature_points`` (optional): positions in the FDP's units within ``tolerance.feature_points``;
  only for vectors with a face, and a decoder without a face model reports none. An expected file
  may pin only some coordinates (``feature_points.axes`` or ``checkable``: 0/1 per x y z, per label or per
  frame and label, :func:`pinned_axes`):
  the standard fixes a FAP's motion along its direction, a jaw or eyelid arc is the decoder's;
* ``reject`` (required): a malformed stream is refused; ``reject_offset`` (optional) the bit where
  the decoder says it found the fault is within :data:`REJECT_BIT_SLACK` bits of the expected one,
  or its partial output stops at the expected frame (the fault was found in the same frame).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mpeg4fa.conformance.protocol import DECODED, REJECTED, DecoderOutput, DecoderResult

PASS, FAIL, NOT_SUPPORTED, CRASH, TIMEOUT = "pass", "fail", "not supported", "crash", "timeout"
STATUSES = (PASS, FAIL, NOT_SUPPORTED, CRASH, TIMEOUT)
OPTIONAL = ("sent", "feature_points", "reject_offset")
"""Checks a decoder may leave "not supported" without failing the suite."""
TIMESTAMP_TOLERANCE = 5e-4
"""Seconds: far below a frame period at 255 fps (3.9 ms), far above float rounding."""
REJECT_BIT_SLACK = 32
"""Bits either side of the expected fault position that still count as the same place: a decoder
may notice a bad field only after reading the next field or start code (32 bits)."""
DEFAULT_TOLERANCE = {"shown": 1e-6, "feature_points": 1e-6}


@dataclass
class Check:
    """One check's result; ``worst`` says where the largest error was (for the report)."""

    name: str
    status: str
    message: str = ""
    worst: dict[str, Any] = field(default_factory=dict)

    @property
    def optional(self) -> bool:
        return self.name in OPTIONAL

    def to_json(self) -> dict[str, Any]:
        return {"check": self.name, "status": self.status, "message": self.message,
                **({"worst": self.worst} if self.worst else {})}


def _tolerance(expected: dict, key: str) -> float:
    return float((expected.get("tolerance") or {}).get(key, DEFAULT_TOLERANCE.get(key, 0.0)))


def _worst(diff: np.ndarray) -> tuple[int, ...]:
    return tuple(int(i) for i in np.unravel_index(int(np.argmax(diff)), diff.shape))


def check_timestamps(expected: dict, output: DecoderOutput) -> Check:
    want = np.asarray(expected["timestamps"], dtype=np.float64)
    tol = _tolerance(expected, "timestamps") if "timestamps" in (expected.get("tolerance") or {}) \
        else TIMESTAMP_TOLERANCE
    diff = np.abs(output.timestamps - want)
    if not len(diff) or diff.max() <= tol:
        return Check("timestamps", PASS)
    (k,) = _worst(diff)
    return Check("timestamps", FAIL, f"frame {k} at {output.timestamps[k]:.6f} s, expected {want[k]:.6f} s",
                 {"frame": k, "expected": float(want[k]), "got": float(output.timestamps[k]),
                  "error": float(diff[k]), "tolerance": tol})


def check_shown(expected: dict, output: DecoderOutput) -> Check:
    want = np.asarray(expected["shown"], dtype=np.float64).reshape(len(output), -1)
    tol = _tolerance(expected, "shown")
    diff = np.abs(output.shown - want)
    if not diff.size or diff.max() <= tol:
        return Check("shown", PASS)
    k, col = _worst(diff)
    bad = int(np.count_nonzero((diff > tol).any(axis=0)))
    return Check("shown", FAIL, f"FAP {col + 1} at frame {k}: {output.shown[k, col]:g}, expected {want[k, col]:g} "
                 f"({bad} FAP{'s' if bad != 1 else ''} off by more than {tol:g})",
                 {"frame": k, "fap": col + 1, "expected": float(want[k, col]), "got": float(output.shown[k, col]),
                  "error": float(diff[k, col]), "tolerance": tol})


def check_sent(expected: dict, output: DecoderOutput) -> Check:
    if output.sent is None:
        return Check("sent", NOT_SUPPORTED, "the decoder does not report the sent fields")
    want = {k: np.asarray(v, dtype=np.int64) for k, v in expected["sent"].items()}
    got = output.sent
    mask_want, mask_got = want["mask"].astype(bool), got["mask"].astype(bool)
    if (mask_want != mask_got).any():
        k, col = _worst(mask_want != mask_got)
        return Check("sent", FAIL, f"mask of FAP {col + 1} at frame {k}: {int(mask_got[k, col])}, "
                     f"expected {int(mask_want[k, col])}", {"frame": k, "fap": col + 1, "field": "mask"})
    wrong = mask_want & (want["values"] != got["values"])
    wrong[:, :2] = False
    if wrong.any():
        k, col = _worst(wrong)
        return Check("sent", FAIL, f"FAP {col + 1} at frame {k}: sent {int(got['values'][k, col])}, expected "
                     f"{int(want['values'][k, col])}",
                     {"frame": k, "fap": col + 1, "field": "values", "expected": int(want["values"][k, col]),
                      "got": int(got["values"][k, col])})
    for name, column in (("viseme", 0), ("expression", 1)):
        rows = mask_want[:, column] & (want[name] != got[name]).any(axis=1)
        if rows.any():
            k = int(np.argmax(rows))
            return Check("sent", FAIL, f"{name} fields at frame {k}: {got[name][k].tolist()}, expected "
                         f"{want[name][k].tolist()}", {"frame": k, "field": name})
    return Check("sent", PASS)


def check_feature_points(expected: dict, output: DecoderOutput) -> Check:
    if output.fp_labels is None or output.fp_positions is None:
        return Check("feature_points", NOT_SUPPORTED, "the decoder does not report feature points")
    fp = expected["feature_points"]
    labels = list(fp["labels"])
    index = {label: i for i, label in enumerate(output.fp_labels)}
    missing = [label for label in labels if label not in index]
    if missing:
        return Check("feature_points", FAIL, f"no position for feature point{'s' if len(missing) > 1 else ''} "
                     f"{', '.join(missing[:8])}{' ...' if len(missing) > 8 else ''}", {"missing": missing})
    want = np.asarray(fp["positions"], dtype=np.float64).reshape(len(output), len(labels), 3)
    got = output.fp_positions[:, [index[label] for label in labels]]
    tol = _tolerance(expected, "feature_points")
    dist = np.linalg.norm((got - want) * pinned_axes(fp, len(output)), axis=2)
    if not dist.size or dist.max() <= tol:
        return Check("feature_points", PASS)
    k, j = _worst(dist)
    return Check("feature_points", FAIL, f"{labels[j]} at frame {k} is {dist[k, j]:.4g} from where expected "
                 f"(tolerance {tol:g})", {"frame": k, "label": labels[j], "expected": want[k, j].tolist(),
                                          "got": got[k, j].tolist(), "error": float(dist[k, j]), "tolerance": tol})


def pinned_axes(fp: dict, frames: int) -> np.ndarray:
    """``(n, k, 3)`` 0/1: which coordinates of each expected point are checked (all, unless the expected
    file says: ``axes`` or ``checkable``, per label ``(k, 3)`` or per frame and label ``(n, k, 3)``)."""
    k = len(fp["labels"])
    given = fp.get("axes", fp.get("checkable"))
    if given is None:
        return np.ones((frames, k, 3))
    axes = np.asarray(given, dtype=np.float64)
    return np.broadcast_to(axes.reshape(k, 3)[None] if axes.ndim == 2 else axes.reshape(frames, k, 3), (frames, k, 3))


def compare_decoded(expected: dict, output: DecoderOutput) -> list[Check]:
    """Every check a decodable vector has, for an output the decoder gave."""
    names = ["timestamps", "sent", "shown"] + (["feature_points"] if expected.get("feature_points") else [])
    n = int(expected.get("frames", len(expected["shown"])))
    if len(output) != n:
        message = f"{len(output)} frames decoded, expected {n}"
        return [Check(name, FAIL, message, {"frames": len(output), "expected_frames": n}) for name in names]
    checks = {"timestamps": check_timestamps, "sent": check_sent, "shown": check_shown,
              "feature_points": check_feature_points}
    return [checks[name](expected, output) for name in names]


def compare_rejected(expected: dict, result: DecoderResult) -> list[Check]:
    """The checks of a vector the decoder must reject."""
    if result.status == DECODED:
        frames = len(result.output) if result.output is not None else 0
        return [Check("reject", FAIL, f"decoded ({frames} frames) a stream it must reject"),
                Check("reject_offset", FAIL, "no fault reported")]
    want = int(expected["bit_offset"])
    slack = int(expected.get("bit_slack", REJECT_BIT_SLACK))
    got = result.bit_offset
    partial = len(result.output) if result.output is not None else None
    detail = {"expected": want, "got": got, "slack": slack, "frames_before": expected.get("frames_before"),
              "partial_frames": partial}
    if got is None:
        offset = Check("reject_offset", NOT_SUPPORTED, "the decoder does not say where the fault is", detail)
    elif abs(got - want) <= slack or (partial is not None and partial == expected.get("frames_before")
                                       and got >= want - slack):
        offset = Check("reject_offset", PASS, f"bit {got} (expected {want})", detail)
    else:
        offset = Check("reject_offset", FAIL, f"fault reported at bit {got}, expected bit {want} "
                       f"(+-{slack})", detail)
    return [Check("reject", PASS, result.message), offset]


def compare(expected: dict, expect: str, result: DecoderResult) -> list[Check]:
    """All checks of one vector for one decoder run (crash and timeout mark every check)."""
    if result.status in (CRASH, TIMEOUT):
        names = ["reject", "reject_offset"] if expect == "reject" else \
            ["timestamps", "sent", "shown"] + (["feature_points"] if expected.get("feature_points") else [])
        return [Check(name, result.status, result.message) for name in names]
    if expect == "reject":
        return compare_rejected(expected, result)
    if result.status == REJECTED:
        where = f" at bit {result.bit_offset}" if result.bit_offset is not None else ""
        names = ["timestamps", "sent", "shown"] + (["feature_points"] if expected.get("feature_points") else [])
        return [Check(name, FAIL, f"rejected a valid stream{where}: {result.message}") for name in names]
    assert result.output is not None
    return compare_decoded(expected, result.output)
