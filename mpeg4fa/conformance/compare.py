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
from mpeg4fa.conformance.rules import rule_of
from mpeg4fa.spec import FAP_PARTNERS, N_FAPS

PASS, FAIL, NOT_SUPPORTED, CRASH, TIMEOUT = "pass", "fail", "not supported", "crash", "timeout"
DIFFERS = "differs"
"""A check of an informative rule (M, or left to the decoder) that the decoder does not meet: reported with
what the decoder did, never a fail."""
STATUSES = (PASS, FAIL, DIFFERS, NOT_SUPPORTED, CRASH, TIMEOUT)
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
    """One check's result: the rule it tests (``spec/conformance_rules.csv``) and, for the report,
    where the largest error was (``worst``) and, for an informative rule, what the decoder did."""

    name: str
    status: str
    message: str = ""
    worst: dict[str, Any] = field(default_factory=dict)
    rule: str = ""

    @property
    def optional(self) -> bool:
        """Whether the decoder may leave this check "not supported" (it reports no such output)."""
        return self.name in OPTIONAL

    @property
    def required(self) -> bool:
        """Whether this check's rule is required (V or S, not left to the decoder): only then can it fail the suite."""
        return rule_of(self.name, {self.name: self.rule} if self.rule else None).required

    def to_json(self) -> dict[str, Any]:
        rule = rule_of(self.name, {self.name: self.rule} if self.rule else None)
        return {"check": self.name, "status": self.status, "message": self.message, "rule": rule.id,
                "confidence": rule.confidence, "required": rule.required,
                **({"worst": self.worst} if self.worst else {})}


def _tolerance(expected: dict, key: str) -> float:
    return float((expected.get("tolerance") or {}).get(key, DEFAULT_TOLERANCE.get(key, 0.0)))


def _worst(diff: np.ndarray) -> tuple[int, ...]:
    return tuple(int(i) for i in np.unravel_index(int(np.argmax(diff)), diff.shape))


TIME_ROUNDING = 1e-9
"""Seconds added to a time stamp tolerance for float rounding: a decoder that truncates 1899.99999 ms to 1899
is off by 1 ms and some 1e-16 s, which a 1 ms resolution must still cover."""
MAX_TIMESTAMP_RESOLUTION = 1e-3
"""Coarsest time stamp resolution a decoder may declare (``timestamp_resolution``, seconds): whole
milliseconds, what integer-millisecond decoders (visage) report; the tolerance becomes that step."""


def timestamp_tolerance(expected: dict, output: DecoderOutput) -> float:
    """0.5 ms (or the expected file's), widened to the decoder's declared resolution up to 1 ms."""
    tol = _tolerance(expected, "timestamps") if "timestamps" in (expected.get("tolerance") or {}) \
        else TIMESTAMP_TOLERANCE
    resolution = output.timestamp_resolution
    if resolution is not None and resolution > 0:
        tol = max(tol, min(float(resolution), MAX_TIMESTAMP_RESOLUTION))
    return tol


def timestamp_frames(expected: dict, frames: int) -> dict[str, np.ndarray]:
    """Frames per timestamp check: ``timestamps``, and ``timestamps_after_time_code`` for the planes after a
    time-coded one that send no time code themselves (how they follow it is not settled: SYNTAX.md 13)."""
    coded = np.zeros(frames, dtype=bool)
    for k in expected.get("time_coded") or ():
        if isinstance(k, int) and 0 <= k < frames:
            coded[k] = True
    after = np.logical_or.accumulate(coded) & ~coded if frames else coded
    out = {"timestamps": ~after}
    if after.any():
        out["timestamps_after_time_code"] = after
    return out


def check_timestamps(expected: dict, output: DecoderOutput, frames: np.ndarray | None = None,
                     name: str = "timestamps") -> Check:
    want = np.asarray(expected["timestamps"], dtype=np.float64)
    tol = timestamp_tolerance(expected, output)
    diff = np.abs(output.timestamps - want)
    if frames is not None:
        diff = np.where(frames, diff, 0.0)
    if not len(diff) or diff.max() <= tol + TIME_ROUNDING:
        return Check(name, PASS)
    (k,) = _worst(diff)
    late = int(np.count_nonzero(diff > tol + TIME_ROUNDING))
    return Check(name, FAIL, f"frame {k} at {output.timestamps[k]:.6f} s, expected {want[k]:.6f} s "
                 f"({late} frame{'s' if late != 1 else ''} off by more than {tol * 1e3:g} ms)",
                 {"frame": k, "expected": float(want[k]), "got": float(output.timestamps[k]),
                  "error": float(diff[k]), "tolerance": tol, "frames_off": late})


_PARTNER = np.zeros((N_FAPS, N_FAPS), dtype=bool)
for _fap, _partners in enumerate(np.asarray(FAP_PARTNERS)):
    for _p in _partners:
        if _p >= 0:
            _PARTNER[int(_p), _fap] = True  # column _fap's partner _p: sent _p may be copied to _fap


def shown_cells(expected: dict) -> dict[str, np.ndarray]:
    """The ``shown`` matrix split by the rule each value depends on (``(n, 68)`` masks, only the non-empty ones):

    * ``shown``: FAPs sent in the frame (and columns 0, 1): the value decoded;
    * ``shown_high_level``: every low-level value in and after a frame that sends FAP 1 or 2 (profiles);
    * ``shown_partner``: unsent FAPs whose left/right or inner/outer counterpart is sent in the frame;
    * ``shown_held``: unsent FAPs sent in an earlier frame (hold under mask type 1, [M]);
    * ``shown_never_sent``: FAPs not sent so far.
    """
    mask = np.asarray(expected["sent"]["mask"]).astype(bool)
    n = len(mask)
    cls = np.zeros(mask.shape, dtype=np.int8)
    if n:
        before = np.zeros_like(mask)
        before[1:] = np.logical_or.accumulate(mask, axis=0)[:-1]
        unsent = ~mask
        cls[unsent & ~before] = 4
        cls[unsent & before] = 3
        cls[unsent & ((mask.astype(np.int32) @ _PARTNER.astype(np.int32)) > 0)] = 2
        high = np.logical_or.accumulate(mask[:, 0] | mask[:, 1])
        cls[high, 2:] = 1
        cls[:, :2] = 0
    names = ("shown", "shown_high_level", "shown_partner", "shown_held", "shown_never_sent")
    return {name: cls == i for i, name in enumerate(names) if name == "shown" or (cls == i).any()}


def _did(name: str, expected: dict, output: DecoderOutput, cells: np.ndarray, bad: np.ndarray) -> str:
    """What the decoder did on an informative rule's cells, in words (for the report)."""
    got = output.shown
    if name == "shown_partner":
        mask = np.asarray(expected["sent"]["mask"]).astype(bool)
        partner_value = np.zeros_like(got)
        for col in range(N_FAPS):
            for p in np.flatnonzero(_PARTNER[:, col]):
                take = mask[:, p] & (partner_value[:, col] == 0)
                partner_value[take, col] = got[take, p]
        copied = bad & (np.abs(got - partner_value) <= 1e-6)
        if copied.any() and copied.sum() == bad.sum():
            return "the decoder copies the sent counterpart's value to the unsent FAP"
    if name == "shown_held":
        return "the decoder does not hold the last sent value"
    if name == "shown_never_sent":
        return "the decoder shows a non-zero value for a FAP never sent"
    return ""


def check_shown(expected: dict, output: DecoderOutput, cells: np.ndarray | None = None, name: str = "shown") -> Check:
    want = np.asarray(expected["shown"], dtype=np.float64).reshape(len(output), -1)
    tol = _tolerance(expected, "shown")
    diff = np.abs(output.shown - want)
    if cells is not None:
        diff = np.where(cells, diff, 0.0)
    if not diff.size or diff.max() <= tol:
        return Check(name, PASS)
    k, col = _worst(diff)
    bad = diff > tol
    n_faps = int(np.count_nonzero(bad.any(axis=0)))
    did = _did(name, expected, output, cells if cells is not None else np.ones_like(bad), bad)
    return Check(name, FAIL, f"FAP {col + 1} at frame {k}: {output.shown[k, col]:g}, expected {want[k, col]:g} "
                 f"({n_faps} FAP{'s' if n_faps != 1 else ''}, {int(bad.sum())} values off by more than {tol:g})"
                 + (f"; {did}" if did else ""),
                 {"frame": k, "fap": col + 1, "expected": float(want[k, col]), "got": float(output.shown[k, col]),
                  "error": float(diff[k, col]), "tolerance": tol, "values_off": int(bad.sum()),
                  "faps_off": [int(c) + 1 for c in np.flatnonzero(bad.any(axis=0))],
                  **({"decoder_did": did} if did else {})})


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


def check_names(expected: dict, expect: str) -> list[str]:
    """The checks a vector gives, from its expected file alone (so a crash marks them all the same)."""
    if expect == "reject":
        return ["reject", "reject_offset"]
    frames = len(expected["timestamps"]) if expected.get("timestamps") is not None else 0
    names = [*timestamp_frames(expected, frames), "sent", *shown_cells(expected)]
    return names + (["feature_points"] if expected.get("feature_points") else [])


def compare_decoded(expected: dict, output: DecoderOutput) -> list[Check]:
    """Every check a decodable vector has, for an output the decoder gave."""
    names = check_names(expected, "decode")
    n = int(expected.get("frames", len(expected["shown"])))
    if len(output) != n:
        message = f"{len(output)} frames decoded, expected {n}"
        return [Check(name, FAIL, message, {"frames": len(output), "expected_frames": n}) for name in names]
    checks = [check_timestamps(expected, output, frames, name)
              for name, frames in timestamp_frames(expected, n).items()]
    checks.append(check_sent(expected, output))
    checks += [check_shown(expected, output, cells, name) for name, cells in shown_cells(expected).items()]
    if expected.get("feature_points"):
        checks.append(check_feature_points(expected, output))
    return checks


def compare_rejected(expected: dict, result: DecoderResult) -> list[Check]:
    """The checks of a vector the decoder must reject."""
    if result.status == DECODED:
        frames = len(result.output) if result.output is not None else 0
        return [Check("reject", FAIL, f"decoded ({frames} frames) a stream it must reject", {"frames": frames}),
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


def compare(expected: dict, expect: str, result: DecoderResult, rules: dict[str, str] | None = None) -> list[Check]:
    """All checks of one vector for one decoder run (crash and timeout mark every check), each naming
    its rule: the vector's ``rules`` (check name -> rule id), else :data:`mpeg4fa.conformance.rules.BASE_RULES`."""
    names = check_names(expected, expect)
    if result.status in (CRASH, TIMEOUT):
        checks = [Check(name, result.status, result.message) for name in names]
    elif expect == "reject":
        checks = compare_rejected(expected, result)
    elif result.status == REJECTED:
        where = f" at bit {result.bit_offset}" if result.bit_offset is not None else ""
        checks = [Check(name, FAIL, f"rejected a valid stream{where}: {result.message or '(no message)'}",
                        {"rejected": True}) for name in names]
    else:
        assert result.output is not None
        checks = compare_decoded(expected, result.output)
    whole = expect != "reject" and (result.status == REJECTED or any("expected_frames" in c.worst for c in checks))
    main = rule_of("shown", rules).id if whole else None
    for check in checks:  # a valid stream refused or cut short fails the rule the vector is about, not partners
        check.rule = main or rule_of(check.name, rules).id
        if check.status == FAIL and not check.required:
            check.status = DIFFERS
    return checks
