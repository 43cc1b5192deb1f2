#!/usr/bin/env python3
"""Fuzz every reader with mutated input: only the layer's own error may escape, never a crash or a hang.

Why: the error contract (README, "Architecture") promises that bad input gives one
located error of the layer's type, with what was decoded before the fault kept,
in bounded time and memory. Hand-written bad-input tests cover the faults we
thought of; this covers the ones we did not.

How to run (on demand, bounded in time and in count; ``--jobs N`` runs chunks of cases in N worker
processes, :mod:`fuzz_parallel`)::

    .venv/bin/python tools/fuzz.py --cases 100000 --seconds 1800 --seed 0 \\
        [--target fba,fap,...|new] [--per-target N] [--jobs N] [--json out/fuzz/fuzz.json]
    .venv/bin/python tools/fuzz.py --case text:1234 --seed 0          # one case again, from (target, seed, index)
    .venv/bin/python tools/fuzz.py --replay out/fuzz/crashes/fap-17.bin --target fap --index 17

Targets. The codec and FDP readers (``markup``, ``fdp-json``, ``fdp-xface``, ``fdp-binary``, ``fap``,
``fba``) are seeded from ``tools/fuzz_inputs.py``: the real files in ``../shared/vectors`` (``fba/``,
``fap/``, any FDP file there) when present (``--no-vectors`` leaves them out), plus seeds made with the
library (streams encoded with several coding options, ``write_fap``, ``save_fdp`` in both forms, an Xface
XML written there, markup strings). Each case applies 1-4 mutations (bit flips, byte sets, inserts,
deletes, truncation, chunk duplication, splices of two seeds, extreme 32-bit integers, FBA start codes;
for text formats number-token replacement, line duplication and deletion, encoding damage; XML damage
(encoding declarations, entity bombs, external entities, deep nesting); JSON damage (deep nesting, huge
arrays, NaN, long numbers, valid JSON with wrong content); for the binary FDP, payload damage with the
chunk CRC fixed so the reader looks inside) and calls the library in-process: ``decode`` /
``iter_decode`` / ``read_stream``, ``read_fap`` / ``iter_fap``, ``load_fdp``, ``read_xface_fdp`` +
``to_fdp``, ``parse_markup``. What parses goes on to the next layers: ``resolve`` and ``encode`` ->
``decode`` for streams (also for the frames an ``FbaError`` kept in ``.partial``; decoded FBA must come
back with the same values), a binary and a JSON save -> load for FDPs, and for markup of up to
``SPEECH_CHARS`` characters ``encode_text`` with the silent estimate engine.

The readers of issue 26 item 4 and the text path (``new``: ``text``, ``stdin``, ``visemes``, ``points``,
``manifest``, ``conform``, ``bap``, ``wav``, ``image``, ``obj``, ``gltf``; :mod:`fuzz_readers` says what
each runs) take only seeds made here (:mod:`fuzz_seeds`; never files from ``../shared``) with their own
mutations (WAV headers, PNG chunks with fixed CRCs and decompression bombs, JPEG frames, glTF accessors
and node cycles, GLB chunk lengths, OBJ indices and statements, viseme events at 6 h and by the ten
thousand, manifest paths and cells); ``text`` and ``stdin`` draw generated texts (:mod:`fuzz_text`: every
script, control characters, 1 MB lines, nested and broken tags, RTL marks, emoji; for ``stdin`` in many
encodings) through ``parse_markup`` and ``encode_text`` (estimate engine; a share through espeak-ng).

Each case is *ok* (parsed), *rejected* (an ``MpegFaError`` or the layer's own error type), *crash*
(anything else; deduplicated by target, stage, exception type and the traceback's last frame; the input
saved as ``OUT/crashes/TARGET-INDEX.bin`` with a ``.txt`` beside it giving the traceback and the replay
commands), *hang* (the case ran past ``--case-seconds``, 10 s by default as issue 26 sets, plus 40 us a
byte for the codec targets; the stages of a case share the time), *memory* (``MemoryError`` anywhere in
the exception chain, under an address-space cap ``--memory-gib`` above the start), *peak* (RSS grew more
than ``--peak-mib`` during the case) or *mismatch* (a round trip changed the values, or a layer refused
what the layer before it made). Also counted: rejections whose error names no place, and warnings that
are not an ``MpegFaWarning``. A watchdog thread ends the process with exit status 3 (keeping the input
and printing its replay command) if a case is stuck where the timer signal cannot reach. ``--clock cpu`` counts
the process's own CPU seconds instead of the wall clock's, for a machine shared with other work. Case ``i`` of
a target is drawn from its own generator seeded by ``--seed``, the target and ``i``, so a run is
reproducible. In one process the targets run one after the other, each with ``--per-target`` cases or
an equal share of what is left of ``--cases`` and ``--seconds``. The summary (JSON, and printed) has a
table: per target the cases, each outcome, the largest memory growth of a case and resident memory of
the process (MiB), cases per second of one process. Exit status 1 when anything but ok/rejected was seen.
"""
from __future__ import annotations

import argparse
import io
import json
import logging
import os
import random
import re
import resource
import shutil
import signal
import sys
import tempfile
import threading
import time
import traceback
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable, Iterable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fuzz_inputs import ORIGINAL_TARGETS, READER_TARGETS, ROOT, TARGETS, Seed, collect_seeds, draw  # noqa: E402
import fuzz_parallel  # noqa: E402
from fuzz_readers import RUNNERS as READER_RUNNERS, SPEECH_CHARS, Mismatch, stream_layers  # noqa: E402

from mpeg4fa.errors import MpegFaError, MpegFaWarning  # noqa: E402
from mpeg4fa.fba import FbaError, decode, encode, iter_decode  # noqa: E402
from mpeg4fa.fdp import (Fdp, FdpError, fdp_from_bytes, fdp_from_json, fdp_to_bytes, fdp_to_json,  # noqa: E402
                         load_fdp, read_xface_fdp, xface_from_xml)
from mpeg4fa.formats import FormatError, iter_fap, read_fap, read_stream  # noqa: E402
from mpeg4fa.speech.encoder import encode_text  # noqa: E402
from mpeg4fa.speech.errors import MarkupError  # noqa: E402
from mpeg4fa.speech.markup import parse_markup  # noqa: E402

LAYER_ERRORS: dict[str, tuple[type[BaseException], ...]] = {
    "fba": (MpegFaError, FbaError),
    "fap": (MpegFaError, FormatError, FbaError),  # FbaError: the encode stage of `mpeg4fa encode x.fap`
    "fdp-binary": (MpegFaError, FdpError),
    "fdp-json": (MpegFaError, FdpError),
    "fdp-xface": (MpegFaError, FdpError),
    "markup": (MpegFaError, MarkupError),
    **{target: (MpegFaError,) for target in READER_TARGETS},
}
"""What a target may raise on bad input: the base, plus the layer's type until it derives from the base."""
SCALED = frozenset(ORIGINAL_TARGETS) | {"bap"}
"""Targets whose time limit grows with the input (a 64 KB stream decodes, re-encodes and decodes in ~2.5 s);
the others have the issue's flat limit per case."""
VECTORS = ROOT.parent / "shared" / "vectors"
_DIGITS = re.compile(r"[0-9]+")


# ---- the guards: time and memory -----------------------------------------------------------------------------


class _Hang(BaseException):
    """Raised by the timer inside a stage that ran too long (a BaseException: no `except Exception` eats it)."""


_Mismatch = Mismatch
"""A round trip gave different values: a finding, counted with the crashes (:class:`fuzz_readers.Mismatch`)."""


def _on_alarm(signum, frame):
    raise _Hang()


CLOCKS = ("wall", "cpu")
"""What a case's time limit counts: wall-clock seconds (the issue's measure, on a machine of one's own) or the
process's CPU seconds (its own work, C code included, whatever else the machine runs: for a shared machine)."""


class Guard:
    """Per-case time limit (a timer signal; the stages of a case share it) and per-case peak memory
    (VmHWM, reset before each case). ``clock`` "wall": SIGALRM on the wall clock; "cpu": SIGPROF on the
    process's CPU time, so a case is judged by its own work when other processes load the machine."""

    def __init__(self, case_seconds: float, clock: str = "wall") -> None:
        if clock not in CLOCKS:
            raise ValueError(f"clock {clock!r}: one of {', '.join(CLOCKS)}")
        self.case_seconds, self.clock = case_seconds, clock
        self.stage = ""
        cpu = clock == "cpu"
        self._signal = signal.SIGPROF if cpu else signal.SIGALRM
        self._timer = signal.ITIMER_PROF if cpu else signal.ITIMER_REAL
        self.now: Callable[[], float] = time.process_time if cpu else time.monotonic
        self._previous = signal.signal(self._signal, _on_alarm)
        self.peak_ok = _reset_peak()

    def close(self) -> None:
        """Give the signal handler back (the tests run campaigns inside pytest)."""
        signal.setitimer(self._timer, 0)
        signal.signal(self._signal, self._previous)

    def limit_for(self, size: int, target: str = "fba") -> float:
        """A case's time limit: ``case_seconds``, plus 40 us a byte for the codec targets (:data:`SCALED`)."""
        return self.case_seconds + (size * 40e-6 if target in SCALED else 0.0)

    def run(self, stage: str, limit: float, call: Callable[[], object]) -> object:
        self.stage = stage
        signal.setitimer(self._timer, max(limit, 1e-3))
        try:
            return call()
        finally:
            signal.setitimer(self._timer, 0)


def _reset_peak() -> bool:
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        return True
    except OSError:
        return False


def _status_bytes(key: str) -> int:
    """A ``/proc/self/status`` size (``VmHWM``, ``VmSize``) in bytes; 0 where there is no /proc."""
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(key + ":"):
                    return int(line.split()[1]) * 1024
    except OSError:
        pass
    return 0


def _peak_bytes() -> int:
    return _status_bytes("VmHWM") or resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def limit_memory(extra_gib: float) -> int | None:
    """Cap the address space at its current size + ``extra_gib``, so a runaway allocation is a MemoryError."""
    base = _status_bytes("VmSize")
    if not base or extra_gib <= 0:
        return None
    cap = base + int(extra_gib * (1 << 30))
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    if hard != resource.RLIM_INFINITY:
        cap = min(cap, hard)
    resource.setrlimit(resource.RLIMIT_AS, (cap, hard))
    return cap


# ---- the targets: what each case runs ------------------------------------------------------------------------


@dataclass
class Case:
    """One case's input and what the target needs around it."""

    data: bytes
    rng: random.Random
    guard: Guard
    tmp: Path
    limit: float
    notes: list[str] = field(default_factory=list)
    fault: tuple[str, BaseException] | None = None
    deadline: float = 0.0

    def __post_init__(self) -> None:
        self.deadline = self.guard.now() + self.limit

    def file(self, suffix: str) -> Path:
        path = self.tmp / f"case{suffix}"
        path.write_bytes(self.data)
        return path

    def stage(self, name: str, call: Callable[[], object]) -> object:
        """Run one stage within what is left of the case's time."""
        try:
            return self.guard.run(name, self.deadline - self.guard.now(), call)
        except BaseException as exc:
            self.fault = (name, exc)  # the stage an exception came from, even if later stages ran
            raise

    def stage_of(self, exc: BaseException | None) -> str:
        return self.fault[0] if self.fault is not None and self.fault[1] is exc else self.guard.stage


def run_fba(case: Case) -> None:
    errors = LAYER_ERRORS["fba"]
    pick = case.rng.random()
    if pick < 0.25:
        frames = case.stage("iter_decode", lambda: sum(1 for _ in iter_decode(io.BytesIO(case.data))))
        case.notes.append(f"{frames} frames")
        return
    if pick < 0.35:  # what `mpeg4fa info/encode FILE` does: the kind from the content
        path = case.file(".fba")
        case.stage("read_stream", lambda: read_stream(path))
        return
    try:
        stream = case.stage("decode", lambda: decode(case.data))
    except FbaError as exc:
        partial = exc.partial
        if partial is None:
            raise _Mismatch("an FbaError from decode() without .partial (the frames before the fault)") from exc
        if len(partial):  # what was decoded before the fault goes on through the next layers
            stream_layers(case, partial, errors, exact=True, label="partial ")
        raise
    stream_layers(case, stream, errors, exact=True)


def run_fap(case: Case) -> None:
    pick = case.rng.random()
    if pick < 0.15:  # a strict text stream: undecodable bytes reach the reader as UnicodeDecodeError
        text = io.TextIOWrapper(io.BytesIO(case.data), encoding="utf-8", newline=None)
        stream = case.stage("read_fap(stream)", lambda: read_fap(text, name="case.fap"))
    elif pick < 0.25:
        path = case.file(".fap")
        case.stage("iter_fap", lambda: sum(1 for _ in iter_fap(path)))
        return
    elif pick < 0.35:
        path = case.file(".fap")
        stream, _ = case.stage("read_stream", lambda: read_stream(path))
    else:
        path = case.file(".fap")
        stream = case.stage("read_fap", lambda: read_fap(path))
    stream_layers(case, stream, LAYER_ERRORS["fap"], exact=False)


def _fdp_round_trip(case: Case, fdp: Fdp) -> None:
    try:
        again = case.stage("save-binary", lambda: fdp_from_bytes(fdp_to_bytes(fdp)))
        if not again == fdp:
            raise _Mismatch("binary save -> load changed the FDP")
    except FdpError as exc:
        case.notes.append(f"binary writer refused: {exc}")
    try:
        again = case.stage("save-json", lambda: fdp_from_json(fdp_to_json(fdp)))
        if not again == fdp:
            raise _Mismatch("JSON save -> load changed the FDP")
    except FdpError as exc:
        case.notes.append(f"JSON writer refused: {exc}")


def run_fdp_file(case: Case) -> None:
    path = case.file(".fdp")
    fdp = case.stage("load_fdp", lambda: load_fdp(path))
    _fdp_round_trip(case, fdp)


def run_fdp_json(case: Case) -> None:
    if case.rng.random() < 0.2:  # text in hand: no UTF-8 decoding step
        text = case.data.decode("utf-8", "replace")
        fdp = case.stage("fdp_from_json(str)", lambda: fdp_from_json(text, "case.json"))
    else:
        path = case.file(".json")
        fdp = case.stage("load_fdp", lambda: load_fdp(path))
    _fdp_round_trip(case, fdp)


def run_fdp_xface(case: Case) -> None:
    if case.rng.random() < 0.2:
        text = case.data.decode("utf-8", "surrogateescape")
        xface = case.stage("xface_from_xml(str)", lambda: xface_from_xml(text, "case.fdp"))
    else:
        path = case.file(".fdp")
        xface = case.stage("read_xface_fdp", lambda: read_xface_fdp(path))
    sizes = {}
    for entry in xface.entries:
        sizes[entry.submesh] = max(sizes.get(entry.submesh, 0), entry.index + 1)
    meshes = {name: np.zeros((min(n, 4096) - (case.rng.random() < 0.2), 3)) for name, n in sizes.items()}
    if meshes and case.rng.random() < 0.2:
        meshes.pop(case.rng.choice(sorted(meshes)))
    fdp = case.stage("to_fdp", lambda: xface.to_fdp(meshes))
    _fdp_round_trip(case, fdp)


def run_markup(case: Case) -> None:
    text = case.data.decode("utf-8", case.rng.choice(("replace", "surrogateescape", "ignore")))
    markup = case.stage("parse_markup", lambda: parse_markup(text, name="case.txt"))
    for tag in markup.tags:  # what the encoder relies on
        if not 0 <= tag.offset <= len(markup.text) or not 0 <= tag.intensity <= 63 or not tag.seconds >= 0:
            raise _Mismatch(f"tag out of bounds: {tag}")
    # the next layer, `mpeg4fa encode TEXT --engine estimate`, on texts of a script's size: its work grows
    # with the speech's length (1 MB of text is a day of speech), which is volume, not damage
    if len(text) <= SPEECH_CHARS and case.rng.random() < 0.3:
        encoded = case.stage("encode_text", lambda: encode_text(text, engine="estimate", name="case.txt"))
        try:
            data = case.stage("encode", lambda: encode(encoded.stream))
            case.stage("redecode", lambda: decode(data))
        except FbaError as exc:
            raise _Mismatch(f"the codec refuses what encode_text made: {exc}") from exc


RUNNERS: dict[str, Callable[[Case], None]] = {
    "fba": run_fba, "fap": run_fap, "fdp-binary": run_fdp_file, "fdp-json": run_fdp_json,
    "fdp-xface": run_fdp_xface, "markup": run_markup, **READER_RUNNERS,
}


# ---- running and recording -----------------------------------------------------------------------------------


def _chain(exc: BaseException) -> Iterable[BaseException]:
    seen = set()
    while exc is not None and id(exc) not in seen:
        seen.add(id(exc))
        yield exc
        exc = exc.__cause__ or exc.__context__  # type: ignore[assignment]


def _last_frame(exc: BaseException) -> str:
    frames = traceback.extract_tb(exc.__traceback__)
    if not frames:
        return "?"
    last = frames[-1]
    try:
        where = Path(last.filename).resolve().relative_to(ROOT).as_posix()
    except ValueError:
        where = last.filename
    return f"{where}:{last.lineno} in {last.name}"


def _project_frame(exc: BaseException) -> str:
    """The innermost frame in the package (``mpeg4fa/...``): where the fault is routed when the last frame is
    in the standard library or a dependency."""
    for frame in reversed(traceback.extract_tb(exc.__traceback__)):
        try:
            where = Path(frame.filename).resolve().relative_to(ROOT).as_posix()
        except ValueError:
            continue
        if where.startswith("mpeg4fa/"):
            return f"{where}:{frame.lineno} in {frame.name}"
    return ""


def _located(exc: BaseException) -> bool:
    """Does the error say where (bit offset, line, byte, a place in ``where``)?"""
    for name in ("bit_offset", "line", "offset", "where"):
        if getattr(exc, name, None) not in (None, "", ()):
            return True
    return False


@dataclass
class Finding:
    kind: str  # crash, hang, memory, peak, mismatch
    key: str
    target: str
    stage: str
    type: str
    message: str
    frame: str
    count: int = 1
    first_case: int = 0
    reproducer: str = ""
    replay: str = ""
    project_frame: str = ""
    """The innermost frame in ``mpeg4fa/`` (where to route it when ``frame`` is in a library)."""


@dataclass
class Tally:
    cases: int = 0
    ok: int = 0
    rejected: int = 0
    crashes: int = 0
    hangs: int = 0
    memory: int = 0
    peak: int = 0
    mismatches: int = 0
    unlocated: int = 0
    seconds: float = 0.0
    slowest: float = 0.0
    slowest_case: str = ""
    peak_mib: float = 0.0
    """Largest growth of resident memory during one case (MiB)."""
    rss_mib: float = 0.0
    """Largest resident memory of the process during a case (MiB): the fuzzer's own imports included."""
    slowest_wall: float = 0.0
    """Longest case on the wall clock (s): ``slowest`` is on the guard's clock, which may be CPU time."""


class Campaign:
    """Runs cases, classifies them, keeps the tallies and the distinct findings, saves reproducers."""

    def __init__(self, seed: int, out: Path, guard: Guard, peak_limit: int, tmp: Path, replay_flags: str = "") -> None:
        self.seed, self.out, self.guard, self.peak_limit, self.tmp = seed, out, guard, peak_limit, tmp
        self.replay_flags = replay_flags  # what a replay needs to draw the same seeds (--no-vectors, --vectors)
        self.tallies: dict[str, Tally] = {}
        self.findings: dict[str, Finding] = {}
        self.unlocated: dict[str, str] = {}
        self.warnings: dict[str, str] = {}
        self.reasons: dict[str, int] = {}
        self.current: tuple[str, int, bytes, float] | None = None
        self.case_started = 0.0  # wall clock (the watchdog's)
        self.case_clock = 0.0  # the guard's clock

    def case_rng(self, target: str, index: int) -> random.Random:
        return random.Random((self.seed * 64 + TARGETS.index(target)) * (1 << 40) + index)

    def run_case(self, target: str, index: int, seeds: list[Seed]) -> str:
        rng = self.case_rng(target, index)
        data, origin = draw(rng, target, seeds)
        return self.run_input(target, index, data, rng, origin)

    def run_input(self, target: str, index: int, data: bytes, rng: random.Random, origin: str) -> str:
        tally = self.tallies.setdefault(target, Tally())
        limit = self.guard.limit_for(len(data), target)
        case = Case(data, rng, self.guard, self.tmp, limit)
        self.current, self.case_started, self.case_clock = (target, index, data, limit), time.monotonic(), \
            self.guard.now()
        if self.guard.peak_ok:
            _reset_peak()  # VmHWM := VmRSS now, so the growth below is this case's own
        before = _status_bytes("VmRSS")
        outcome, exc = "ok", None
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                RUNNERS[target](case)
            except _Hang as e:
                outcome, exc = "hang", e
            except LAYER_ERRORS[target] as e:
                outcome, exc = ("memory" if any(isinstance(x, MemoryError) for x in _chain(e)) else "rejected"), e
            except MemoryError as e:
                outcome, exc = "memory", e
            except _Mismatch as e:
                outcome, exc = "mismatch", e
            except RecursionError as e:
                outcome, exc = "crash", e
            except Exception as e:  # noqa: BLE001 - anything else escaping is what we are looking for
                outcome, exc = "crash", e
        elapsed, wall = self.guard.now() - self.case_clock, time.monotonic() - self.case_started
        self.current = None
        stage = case.stage_of(exc)
        tally.cases += 1
        tally.seconds += elapsed
        tally.slowest_wall = max(tally.slowest_wall, wall)
        if elapsed > tally.slowest:
            tally.slowest, tally.slowest_case = elapsed, f"case {index}: {origin} ({len(data)} bytes, {outcome})"
        for w in caught:
            if not issubclass(w.category, MpegFaWarning):
                key = f"{w.category.__name__} {Path(str(w.filename)).name}:{w.lineno}"
                self.warnings.setdefault(key, f"{target}: {str(w.message)[:200]}")
        high = _peak_bytes()
        peak = high - before if self.guard.peak_ok else 0
        tally.peak_mib = max(tally.peak_mib, peak / 2**20)
        tally.rss_mib = max(tally.rss_mib, high / 2**20)
        if outcome in ("ok", "rejected") and elapsed > limit + 1.0:
            # the timer could not interrupt it (C code, or a callback that swallowed the exception)
            tally.hangs += 1
            self._record("hang", target, index, data, None, origin, elapsed, stage,
                         f"the case ran {elapsed:.1f} s, past its {limit:.1f} s (it ended {outcome}; the timer "
                         "could not interrupt it)")
            return "hang"
        if outcome == "rejected":
            tally.rejected += 1
            text = _DIGITS.sub("N", getattr(exc, "message", None) or str(exc))[:90]
            reason = f"{target} {stage}: {type(exc).__name__}: {text}"
            self.reasons[reason] = self.reasons.get(reason, 0) + 1
            if not _located(exc):
                tally.unlocated += 1
                self.unlocated.setdefault(f"{target} {type(exc).__name__} {_last_frame(exc)}", str(exc)[:300])
        elif outcome == "ok":
            tally.ok += 1
        else:
            counter = {"hang": "hangs", "memory": "memory", "mismatch": "mismatches", "crash": "crashes"}[outcome]
            setattr(tally, counter, getattr(tally, counter) + 1)
            self._record(outcome, target, index, data, exc, origin, elapsed, stage)
        if peak > self.peak_limit and outcome in ("ok", "rejected"):
            tally.peak += 1
            self._record("peak", target, index, data, None, origin, elapsed, stage, f"peak {peak / 2**20:.0f} MiB")
        return outcome

    def replay_command(self, target: str, index: int) -> str:
        """The command that runs case ``index`` of ``target`` again, drawn afresh from (target, seed, index)."""
        return f".venv/bin/python tools/fuzz.py --case {target}:{index} --seed {self.seed}{self.replay_flags}"

    def _record(self, kind: str, target: str, index: int, data: bytes, exc: BaseException | None, origin: str,
                elapsed: float, stage: str, message: str = "") -> None:
        if exc is not None and kind == "hang":
            limit = self.guard.limit_for(len(data), target)
            frame, etype = _last_frame(exc), "hang"
            message = f"the case ran past {limit:.1f} s{' of CPU' if self.guard.clock == 'cpu' else ''} (in stage {stage})"
        elif exc is not None:
            frame, etype, message = _last_frame(exc), type(exc).__name__, str(exc)[:300]
        else:
            frame, etype = "", kind
        key = f"{kind}|{target}|{stage}|{etype}|{frame}"
        found = self.findings.get(key)
        if found is not None:
            found.count += 1
            return
        path = self.out / "crashes" / f"{target}-{index}.bin"  # (target, seed, index) names a case
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
        tb = "".join(traceback.format_exception(exc)) if exc is not None else ""
        replay = self.replay_command(target, index)
        path.with_suffix(".txt").write_text(
            f"kind: {kind}\ntarget: {target}\nstage: {stage}\ncase: {index} (--seed {self.seed})\n"
            f"origin: {origin}\nseconds: {elapsed:.3f}\nreplay: {replay}\n"
            f"replay the saved input: .venv/bin/python tools/fuzz.py --replay {path} --target {target} "
            f"--index {index} --seed {self.seed}{self.replay_flags}\n\n{message}\n\n{tb}", encoding="utf-8")
        self.findings[key] = Finding(kind, key, target, stage, etype, message, frame, 1, index,
                                     path.relative_to(ROOT).as_posix() if path.is_relative_to(ROOT) else str(path),
                                     replay, _project_frame(exc) if exc is not None else "")


def _watchdog(campaign: Campaign, report: Callable[[str], None]) -> None:
    """End the run when a case is stuck where the timer signal cannot reach (C code): keep the reproducer. The
    limit is three times the case's own (at least 30 s) on the guard's clock; with the CPU clock also twenty
    times on the wall clock (a case blocked without working); exit status 3 tells a coordinator (``--jobs``)."""
    guard = campaign.guard
    while True:
        time.sleep(0.5)
        current = campaign.current
        if current is None:
            continue
        target, index, data, limit = current
        wall = time.monotonic() - campaign.case_started
        stuck = guard.now() - campaign.case_clock if guard.clock == "cpu" else wall
        if campaign.current is current and (stuck > max(30.0, 3 * limit) or wall > max(200.0, 20 * limit)):
            path = campaign.out / "crashes" / f"{target}-stuck-{index}.bin"
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_bytes(data)
            report(f"STUCK: case {index} of {target} stuck in stage {guard.stage} for {stuck:.0f} s ({guard.clock}) "
                   f"(not interruptible); input saved to {path}; replay: "
                   f"{campaign.replay_command(target, index)}")
            os._exit(3)


# ---- the command ---------------------------------------------------------------------------------------------


def _summary(campaign: Campaign, args: argparse.Namespace, elapsed: float, seeds: dict[str, list[Seed]],
             memory_cap: int | None) -> dict:
    summary = {
        "seed": args.seed, "seconds": round(elapsed, 1), "case_seconds": args.case_seconds,
        "memory_cap_bytes": memory_cap, "peak_limit_mib": args.peak_mib, "jobs": 1, "first": args.first,
        "clock": args.clock,
        "vectors": str(args.vectors) if args.vectors and args.vectors.is_dir() else None,
        "seeds": {t: [s.name for s in seeds[t]] for t in campaign.tallies},
        "targets": {t: vars(campaign.tallies[t]) for t in TARGETS if t in campaign.tallies},
        "findings": [vars(f) for f in campaign.findings.values()],
        "unlocated_errors": campaign.unlocated,
        "stray_warnings": campaign.warnings,
        "top_rejections": dict(sorted(campaign.reasons.items(), key=lambda kv: -kv[1])[:40]),
        "python": sys.version.split()[0],
    }
    summary["table"] = fuzz_parallel.table_rows(summary)
    return summary


def _replay_flags(args: argparse.Namespace) -> str:
    if args.vectors is None:
        return " --no-vectors"
    return "" if args.vectors == VECTORS else f" --vectors {args.vectors}"


def _show(campaign: Campaign, outcome: str, target: str) -> None:
    print(f"{target}: {outcome}")
    for finding in campaign.findings.values():
        print(f"  {finding.type} at {finding.frame} (stage {finding.stage}): {finding.message}")
        text = (ROOT / finding.reproducer if not Path(finding.reproducer).is_absolute() else Path(finding.reproducer))
        print(text.with_suffix(".txt").read_text(encoding="utf-8").split("\n\n", 2)[-1])


def _replay(args: argparse.Namespace, guard: Guard, tmp: Path) -> int:
    """``--replay FILE``: the saved bytes through ``--target``; with ``--index`` the case's own random choices."""
    target = args.target[0]
    data = Path(args.replay).read_bytes()
    campaign = Campaign(args.seed, tmp / "replay", guard, args.peak_mib << 20, tmp, _replay_flags(args))
    if args.index is not None:
        rng = campaign.case_rng(target, args.index)
        draw(rng, target, collect_seeds(args.vectors)[target])  # the draw's random calls, then the case's own
    else:
        rng = random.Random(0)
    outcome = campaign.run_input(target, args.index or 0, data, rng, str(args.replay))
    _show(campaign, outcome, target)
    return 0 if outcome in ("ok", "rejected") else 1


def _one_case(args: argparse.Namespace, guard: Guard, tmp: Path) -> int:
    """``--case TARGET:INDEX``: that case drawn again from (target, seed, index) and run, findings shown."""
    target, index = args.case
    campaign = Campaign(args.seed, tmp / "replay", guard, args.peak_mib << 20, tmp, _replay_flags(args))
    outcome = campaign.run_case(target, index, collect_seeds(args.vectors)[target])
    _show(campaign, outcome, target)
    return 0 if outcome in ("ok", "rejected") else 1


def _case_arg(text: str) -> tuple[str, int]:
    target, _, index = text.rpartition(":")
    if target not in TARGETS or not index.isdigit():
        raise argparse.ArgumentTypeError(f"{text!r}: TARGET:INDEX with TARGET one of {', '.join(TARGETS)}")
    return target, int(index)


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--cases", type=int, default=100_000, help="total cases over all targets (default 100000)")
    p.add_argument("--per-target", type=int, default=None, help="cases per target (instead of a share of --cases)")
    p.add_argument("--seconds", type=float, default=1800.0, help="total time budget (default 1800)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--first", type=int, default=0, help="index of the first case of each target (default 0)")
    p.add_argument("--target", default=",".join(TARGETS), help="comma-separated: " + ",".join(TARGETS)
                   + "; 'new' for the readers of issue 26 (" + ",".join(READER_TARGETS) + ")")
    p.add_argument("--target-seconds", type=float, default=None, help="at most this long on one target")
    p.add_argument("--jobs", type=int, default=None,
                   help="worker processes running chunks of cases in parallel (1: one at a time, still in workers, "
                   "so a case stuck in C code ends only its chunk); default: all in this process")
    p.add_argument("--chunk", type=int, default=5000, help="with --jobs: cases of one target per worker run")
    p.add_argument("--json", type=Path, default=None, help="write the summary here (default out/fuzz/fuzz.json)")
    p.add_argument("--out", type=Path, default=ROOT / "out" / "fuzz", help="reproducers go to OUT/crashes")
    p.add_argument("--vectors", type=Path, default=VECTORS, help="real files to seed from (default ../shared/vectors)")
    p.add_argument("--no-vectors", action="store_true", help="only the seeds made here")
    p.add_argument("--case-seconds", type=float, default=10.0,
                   help="time limit of a case (default 10, the issue's; plus 40 us a byte for the codec targets)")
    p.add_argument("--clock", choices=CLOCKS, default="wall",
                   help="what --case-seconds counts: wall (default) or cpu, the process's own CPU time (a machine "
                   "shared with other work, where the wall clock measures the neighbours)")
    p.add_argument("--memory-gib", type=float, default=2.0, help="address space allowed above the start")
    p.add_argument("--peak-mib", type=int, default=256, help="a case whose peak RSS grows more than this is reported")
    p.add_argument("--replay", type=Path, default=None, help="run one input file through --target and show the outcome")
    p.add_argument("--index", type=int, default=None, help="with --replay: the case's index (its random choices)")
    p.add_argument("--case", type=_case_arg, default=None, metavar="TARGET:INDEX",
                   help="draw case INDEX of TARGET again (with --seed) and run it")
    p.add_argument("--quiet", action="store_true")
    args = p.parse_args(argv)
    names = [t.strip() for t in args.target.split(",") if t.strip()]
    args.target = [t for name in names for t in (READER_TARGETS if name == "new" else (name,))]
    unknown = [t for t in args.target if t not in TARGETS]
    if unknown:
        p.error(f"unknown target {unknown[0]!r}; known: {', '.join(TARGETS)}")
    if args.jobs is not None and args.jobs < 1 or args.chunk < 1:
        p.error("--jobs and --chunk are at least 1")
    if args.no_vectors:
        args.vectors = None
    return args


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    say = (lambda *_: None) if args.quiet else (lambda text: print(text, file=sys.stderr, flush=True))
    if args.jobs is not None and args.replay is None and args.case is None:
        return fuzz_parallel.run(args, Path(__file__).resolve(), say)
    logging.getLogger("trimesh").setLevel(logging.CRITICAL)  # a damaged mesh is our finding, not a log line
    tmp = Path(tempfile.mkdtemp(prefix="mpeg4fa-fuzz-", dir="/dev/shm" if os.path.isdir("/dev/shm") else None))
    guard = Guard(args.case_seconds, args.clock)
    try:
        if args.replay is not None:
            return _replay(args, guard, tmp)
        if args.case is not None:
            return _one_case(args, guard, tmp)
        seeds = collect_seeds(args.vectors)
        memory_cap = limit_memory(args.memory_gib)
        campaign = Campaign(args.seed, args.out, guard, args.peak_mib << 20, tmp, _replay_flags(args))
        threading.Thread(target=_watchdog, args=(campaign, say), daemon=True).start()
        targets = [t for t in TARGETS if t in args.target]
        start, interrupted = time.monotonic(), False
        try:
            for k, target in enumerate(targets):
                left = len(targets) - k
                done = sum(t.cases for t in campaign.tallies.values())
                cases = args.per_target if args.per_target is not None else (args.cases - done) // left
                until = time.monotonic() + min((args.seconds - (time.monotonic() - start)) / left,
                                               args.target_seconds or float("inf"))
                say(f"{target}: up to {cases} cases from {args.first}, {max(until - time.monotonic(), 0):.0f} s, "
                    f"{len(seeds[target])} seeds")
                index = args.first
                while index < args.first + cases and time.monotonic() < until:
                    campaign.run_case(target, index, seeds[target])
                    index += 1
        except KeyboardInterrupt:  # Ctrl-C: keep what was found so far
            interrupted = True
            say("interrupted: writing what was found so far")
        elapsed = time.monotonic() - start
        summary = _summary(campaign, args, elapsed, seeds, memory_cap)
        summary["interrupted"] = interrupted
        path = args.json or args.out / "fuzz.json"
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(summary, indent=2, default=str), encoding="utf-8")
        if not args.quiet:
            print(fuzz_parallel.report(summary, path))
        bad = sum(t.crashes + t.hangs + t.memory + t.peak + t.mismatches for t in campaign.tallies.values())
        return 1 if bad else 0
    finally:
        guard.close()
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    sys.exit(main())
