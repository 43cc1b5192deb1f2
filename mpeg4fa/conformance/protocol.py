"""The decoder protocol: how the runner asks any FBA decoder to decode one vector and reads its answer.

Why a protocol: the suite tests decoders written in any language, so the contract is a command
line and a file, nothing Python-specific (``conformance/README.md`` shows wrappers)::

    DECODER STREAM OUT [--fdp FDP]

``OUT`` ends in ``.json``; the decoder writes there (or to the same name ending ``.csv``)::

    {"timestamps": [n seconds], "shown": [[68 floats] per frame],
     "sent": {"mask": [[68 0/1]], "values": [[68 int]], "viseme": [[4 int]], "expression": [[6 int]]},  # optional
     "feature_points": {"labels": ["2.1", ...], "positions": [[[x, y, z], ...] per frame]},         # optional
     "timestamp_resolution": 0.001}     # optional: seconds per tick of the decoder's clock (0 < r <= 1)

A decoder whose clock counts whole milliseconds declares ``timestamp_resolution`` 0.001 and its time
stamps are compared within 1 ms instead of 0.5 ms (never wider than 1 ms, whatever it declares).

CSV: a header ``t,FAP1,...,FAP68`` then one row per frame of shown values. Exit status 0: decoded;
1: rejected the stream (stderr may say ``bit N``: where the fault was found); anything else, or a
signal: crash; no exit within the timeout: timeout.

:class:`CommandDecoder` runs such a command; :class:`InProcessDecoder` gives the same results from
a Python callable without a subprocess (this project's adapter, and the self-test's faults).
"""
from __future__ import annotations

import csv
import json
import os
import re
import shlex
import signal
import subprocess
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np

from mpeg4fa import jsonio
from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.spec import N_FAPS

DECODED, REJECTED, CRASH, TIMEOUT = "decoded", "rejected", "crash", "timeout"
DEFAULT_TIMEOUT = 20.0
"""Seconds a decoder may take on one vector (the suite's vectors are a few seconds of frames)."""
_BIT = re.compile(r"\bbit\s+(\d{1,18})\b", re.IGNORECASE)


@dataclass
class DecoderOutput:
    """What a decoder said a stream shows, as arrays (``sent`` and ``feature_points`` optional)."""

    timestamps: np.ndarray                      # (n,)
    shown: np.ndarray                           # (n, 68)
    sent: dict[str, np.ndarray] | None = None   # mask (n,68) bool, values (n,68), viseme (n,4), expression (n,6)
    fp_labels: tuple[str, ...] | None = None
    fp_positions: np.ndarray | None = None      # (n, k, 3)
    timestamp_resolution: float | None = None   # seconds per tick of the decoder's clock, if it says (<= 1 ms)

    def __len__(self) -> int:
        return len(self.timestamps)

    def to_json(self) -> dict[str, Any]:
        """The protocol's JSON document for this output."""
        doc: dict[str, Any] = {"timestamps": self.timestamps.tolist(), "shown": self.shown.tolist()}
        if self.sent is not None:
            doc["sent"] = {k: np.asarray(v).astype(int).tolist() for k, v in self.sent.items()}
        if self.fp_labels is not None and self.fp_positions is not None:
            doc["feature_points"] = {"labels": list(self.fp_labels), "positions": self.fp_positions.tolist()}
        if self.timestamp_resolution is not None:
            doc["timestamp_resolution"] = self.timestamp_resolution
        return doc


class Rejected(Exception):
    """Raised by an in-process decoder that refuses a stream (exit status 1 of a command)."""

    def __init__(self, message: str, bit_offset: int | None = None, partial: DecoderOutput | None = None) -> None:
        super().__init__(message)
        self.message = message
        self.bit_offset = bit_offset
        self.partial = partial


@dataclass
class DecoderResult:
    """One run of a decoder on one stream: its status, its output (decoded) or fault place (rejected)."""

    status: str                         # DECODED, REJECTED, CRASH or TIMEOUT
    output: DecoderOutput | None = None  # decoded; for rejected, the frames before the fault if given
    bit_offset: int | None = None
    message: str = ""
    seconds: float = 0.0


# ---- reading a decoder's output ----------------------------------------------------------

def _array(value: Any, shape_tail: tuple[int, ...], what: str, where: str, dtype=np.float64) -> np.ndarray:
    try:
        array = np.asarray(value, dtype=dtype)
    except (TypeError, ValueError, OverflowError):
        raise ConformanceError(f"{what} is not an array of numbers", where=where) from None
    if array.size == 0:
        array = array.reshape((0, *shape_tail))
    if array.shape[1:] != shape_tail or (dtype is np.float64 and not np.isfinite(array).all()):
        raise ConformanceError(f"{what} has shape {array.shape} (or values not finite); expected (n, "
                               f"{', '.join(map(str, shape_tail))})", where=where)
    return array


def output_from_json(doc: Any, where: str = "decoder output") -> DecoderOutput:
    """A :class:`DecoderOutput` from the protocol's JSON document; ConformanceError naming what is wrong."""
    if not isinstance(doc, dict) or "shown" not in doc or "timestamps" not in doc:
        raise ConformanceError('expected an object with "timestamps" and "shown"', where=where)
    shown = _array(doc["shown"], (N_FAPS,), '"shown"', where)
    timestamps = _array(doc["timestamps"], (), '"timestamps"', where)
    if len(timestamps) != len(shown):
        raise ConformanceError(f'{len(timestamps)} timestamps for {len(shown)} frames of "shown"', where=where)
    sent = None
    if doc.get("sent") is not None:
        given = doc["sent"]
        widths = {"mask": N_FAPS, "values": N_FAPS, "viseme": 4, "expression": 6}
        if not isinstance(given, dict) or set(widths) - set(given):
            raise ConformanceError('"sent" needs "mask", "values", "viseme" and "expression"', where=where)
        sent = {k: _array(given[k], (w,), f'"sent.{k}"', where, dtype=np.int64) for k, w in widths.items()}
        if any(len(v) != len(shown) for v in sent.values()):
            raise ConformanceError('"sent" has a different number of frames than "shown"', where=where)
    labels = positions = None
    if doc.get("feature_points") is not None:
        fp = doc["feature_points"]
        if not isinstance(fp, dict) or not isinstance(fp.get("labels"), list):
            raise ConformanceError('"feature_points" needs "labels" and "positions"', where=where)
        labels = tuple(str(label) for label in fp["labels"])
        positions = _array(fp.get("positions"), (len(labels), 3), '"feature_points.positions"', where)
        if len(positions) != len(shown):
            raise ConformanceError('"feature_points" has a different number of frames than "shown"', where=where)
    resolution = doc.get("timestamp_resolution")
    if resolution is not None and (isinstance(resolution, bool) or not isinstance(resolution, (int, float))
                                   or not 0 < resolution <= 1.0):
        raise ConformanceError('"timestamp_resolution" must be seconds per tick, above 0 and at most 1 '
                               '(e.g. 0.001: whole milliseconds)', where=where)
    return DecoderOutput(timestamps, shown, sent, labels, positions,
                         None if resolution is None else float(resolution))


def output_from_csv(text: str, where: str = "decoder output") -> DecoderOutput:
    """A :class:`DecoderOutput` from the CSV form (``t,FAP1..FAP68`` per frame: shown values only)."""
    try:
        rows = [row for row in csv.reader(text.splitlines()) if row and any(cell.strip() for cell in row)]
    except csv.Error as exc:  # a field over csv's limit (128 KiB), a NUL...
        raise ConformanceError(f"not valid CSV: {exc}", where=where) from None
    if not rows:
        raise ConformanceError("empty CSV", where=where)
    header = [cell.strip().lower() for cell in rows[0]]
    if header != ["t"] + [f"fap{i}" for i in range(1, N_FAPS + 1)]:
        raise ConformanceError("the CSV header must be t,FAP1,...,FAP68", where=where)
    table = _array([[cell.strip() for cell in row] for row in rows[1:]] or np.zeros((0, N_FAPS + 1)),
                   (N_FAPS + 1,), "the CSV rows", where)
    return DecoderOutput(table[:, 0].copy(), table[:, 1:].copy())


def read_output(out: Path) -> DecoderOutput | None:
    """The output a decoder wrote at ``out`` (``.json``) or beside it (``.csv``); None if it wrote neither."""
    csv_path = out.with_suffix(".csv")
    try:
        if out.is_file():
            doc = jsonio.loads(_read_capped(out), str(out), max_bytes=MAX_OUTPUT_BYTES, max_depth=MAX_DEPTH,
                               error=_located, what="a decoder's output (the protocol's JSON)")
            return output_from_json(doc, str(out))
        if csv_path.is_file():
            text = jsonio.decode_utf8(_read_capped(csv_path), str(csv_path), _located, "a decoder's CSV output")
            return output_from_csv(text, str(csv_path))
    except OSError as exc:
        raise ConformanceError(f"cannot read the decoder's output: {exc}", where=str(out)) from None
    return None


MAX_OUTPUT_BYTES = 256 << 20
"""Largest decoder output read (256 MiB): 68 values and 84 points a frame for far longer than any vector."""
MAX_DEPTH = 8
"""Deepest nesting of the output JSON read (it needs 5: feature point positions)."""


def _read_capped(path: Path) -> bytes:
    """The file's bytes, refused past :data:`MAX_OUTPUT_BYTES` before more is read."""
    with open(path, "rb") as fh:
        data = fh.read(MAX_OUTPUT_BYTES + 1)
    if len(data) > MAX_OUTPUT_BYTES:
        raise ConformanceError(f"the decoder's output is over {MAX_OUTPUT_BYTES >> 20} MiB", where=str(path))
    return data


def _located(path: str, line: int | None, column: int | None, problem: str, hint: str) -> ConformanceError:
    """A :class:`ConformanceError` at ``path:line:column`` (how :mod:`mpeg4fa.jsonio` reports)."""
    where = path if line is None else f"{path}:{line}" if column is None else f"{path}:{line}:{column}"
    return ConformanceError(problem, where=where, hint=hint)


def write_output(output: DecoderOutput, out: Path) -> None:
    """Write ``output`` in the protocol's form chosen by ``out``'s suffix (``.json`` or ``.csv``)."""
    out = Path(out)
    if out.suffix.lower() == ".csv":
        header = ["t"] + [f"FAP{i}" for i in range(1, N_FAPS + 1)]
        lines = [",".join(header)] + [",".join(repr(float(x)) for x in (t, *row))
                                      for t, row in zip(output.timestamps, output.shown)]
        out.write_text("\n".join(lines) + "\n", encoding="utf-8")
    else:
        out.write_text(json.dumps(output.to_json()), encoding="utf-8")


def bit_from_text(text: str) -> int | None:
    """The fault's bit offset a decoder printed (``bit N`` anywhere in its message), or None."""
    match = _BIT.search(text or "")
    return int(match.group(1)) if match else None


# ---- decoders -----------------------------------------------------------------------------

class CommandDecoder:
    """An external decoder: ``command STREAM OUT [--fdp FDP]`` run as a subprocess with a timeout."""

    def __init__(self, command: str) -> None:
        try:
            self.argv = shlex.split(command)
        except ValueError as exc:  # an unclosed quote or a trailing backslash
            raise ConformanceError(f"the decoder command {command!r} cannot be split into words: {exc}",
                                   where="--decoder", hint="close its quotes, as a shell would need") from None
        if not self.argv:
            raise ConformanceError("the decoder command is empty", where="--decoder")
        self.name = command

    def __call__(self, stream: Path, fdp: Path | None, timeout: float = DEFAULT_TIMEOUT) -> DecoderResult:
        with tempfile.TemporaryDirectory(prefix="mpeg4fa-conform-") as tmp:
            out = Path(tmp) / "out.json"
            argv = [*self.argv, str(stream), str(out)] + (["--fdp", str(fdp)] if fdp is not None else [])
            started = time.perf_counter()
            with open(Path(tmp) / "stderr", "w+b") as err:
                try:
                    returncode = run_in_own_group(argv, err, timeout)
                except OSError as exc:
                    return DecoderResult(CRASH, message=f"cannot run {self.argv[0]}: {exc.strerror or exc}")
                seconds = time.perf_counter() - started
                if returncode is None:
                    return DecoderResult(TIMEOUT, message=f"no answer within {timeout:g} s (its process group was "
                                         "ended)", seconds=seconds)
                stderr = read_bounded(err)
            return self._result(returncode, out, stderr, seconds)

    @staticmethod
    def _result(returncode: int, out: Path, stderr: str, seconds: float) -> DecoderResult:
        """Judge an exit status, the decoder's stderr and what it wrote at ``out``."""
        lines = stderr.strip().splitlines()
        tail = lines[-1][:500] if lines else ""
        if returncode not in (0, 1):
            how = f"signal {-returncode}" if returncode < 0 else f"exit status {returncode}"
            return DecoderResult(CRASH, message=f"{how}{': ' + tail if tail else ''}", seconds=seconds)
        try:
            output = read_output(out)
        except ConformanceError as exc:
            if returncode == 1:
                output = None
            else:
                return DecoderResult(CRASH, message=f"unreadable output: {exc}", seconds=seconds)
        if returncode == 1:
            return DecoderResult(REJECTED, output, bit_from_text(stderr), tail, seconds)
        if output is None:
            return DecoderResult(CRASH, message="exit status 0 but no output written", seconds=seconds)
        return DecoderResult(DECODED, output, seconds=seconds)


STDERR_KEEP = 64 << 10
"""Bytes of a decoder's stderr read from each end (its first ``bit N`` and its last line): a decoder that
prints megabytes costs the runner no more than this."""


def run_in_own_group(argv: list[str], stderr, timeout: float) -> int | None:
    """Run ``argv`` in a new session (its own process group), stderr to the file ``stderr``, stdout discarded;
    its exit status, or None when it ran past ``timeout``. Either way the whole group is ended afterwards,
    so a wrapper's children do not outlive the run."""
    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=stderr,
                            start_new_session=True)
    try:
        return proc.wait(timeout=timeout)
    except subprocess.TimeoutExpired:
        return None
    finally:
        _end_group(proc)


def _end_group(proc: subprocess.Popen) -> None:
    try:
        os.killpg(proc.pid, signal.SIGKILL)
    except (ProcessLookupError, PermissionError):
        pass
    try:
        proc.wait(timeout=5)
    except subprocess.TimeoutExpired:  # pragma: no cover - SIGKILL not delivered
        pass


def read_bounded(fh) -> str:
    """The first and last :data:`STDERR_KEEP` bytes of an open file, as text."""
    fh.seek(0, os.SEEK_END)
    size = fh.tell()
    fh.seek(0)
    if size <= 2 * STDERR_KEEP:
        data = fh.read()
    else:
        head = fh.read(STDERR_KEEP)
        fh.seek(size - STDERR_KEEP)
        data = head + f"\n[... {size - 2 * STDERR_KEEP} bytes left out ...]\n".encode() + fh.read()
    return data.decode("utf-8", "replace")


class InProcessDecoder:
    """A Python decoder with the protocol's meaning and no subprocess: ``decode(stream, fdp) -> DecoderOutput``
    returns the output, raises :class:`Rejected` to refuse the stream; any other exception is a crash.
    The timeout is judged after the call (it cannot be interrupted)."""

    def __init__(self, decode: Callable[[Path, Path | None], DecoderOutput], name: str = "in-process") -> None:
        self.decode = decode
        self.name = name

    def __call__(self, stream: Path, fdp: Path | None, timeout: float = DEFAULT_TIMEOUT) -> DecoderResult:
        started = time.perf_counter()
        try:
            output = self.decode(stream, fdp)
        except Rejected as exc:
            return DecoderResult(REJECTED, exc.partial, exc.bit_offset, exc.message, time.perf_counter() - started)
        except Exception as exc:  # noqa: BLE001 - a crash of the decoder under test is a result, not an error
            return DecoderResult(CRASH, message=f"{type(exc).__name__}: {exc}", seconds=time.perf_counter() - started)
        seconds = time.perf_counter() - started
        if seconds > timeout:
            return DecoderResult(TIMEOUT, message=f"took {seconds:.1f} s (limit {timeout:g} s)", seconds=seconds)
        return DecoderResult(DECODED, output, seconds=seconds)


Decoder = Callable[[Path, "Path | None", float], DecoderResult]
"""What the runner calls: ``decoder(stream, fdp, timeout) -> DecoderResult`` (either class above)."""
