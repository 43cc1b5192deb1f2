#!/usr/bin/env python
"""The design's bit library, measured: ``bitstring`` against the codec's own :class:`BitReader`.

A script run on demand, not a test (``bitstring`` is not a dependency of the project;
install the pinned version into the venv first)::

    .venv/bin/pip install bitstring==5.0.0
    .venv/bin/python tools/bench_bits.py [--vectors DIR] [--repeat N] [--json OUT]

The same work is done both ways, in one process pinned to one core, best of N:

1. **header fields**: every fixed-width field and marker bit of every stream's plane
   headers (where and how wide, from ``mpeg4fa.fba.trace``), each read at its offset
   (fields/s); the values must equal the trace's;
2. **bits one at a time**: every bit of every arithmetic-coded segment, read in order as
   the arithmetic decoder consumes them (bits/s): ``buf[p]`` over the reader's unpacked
   bytes, against ``Bits[p]`` indexing and ``Reader.read_value('bool')``;
3. **whole decode**: the reference decoder (``backend="python"``) over a :class:`BitReader`
   and over a bitstring-backed subclass of it (``Bits`` as the buffer, fields through
   ``Bits`` slices), in arithmetic-coded symbols/s; both must give the same frames. For
   context, the compiled path (``decode(backend="compiled")``), whose numba kernels read the
   reader's unpacked bytes as a numpy array, a buffer ``Bits`` cannot be.

The streams are the real ones in ``--vectors`` (default ``../shared/vectors/fba``), else
the committed conformance vectors (``conformance/vectors/syntax``). It prints a table and
writes the figures as JSON (``bench_bits.json`` in the current directory unless ``--json``).
Exit status 1 when a check failed.
"""
from __future__ import annotations

import argparse
import json
import platform
import sys
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

import numpy as np  # noqa: E402

try:
    import bitstring  # noqa: E402
    from bitstring import Bits, Reader  # noqa: E402
except ImportError:  # pragma: no cover - an on-demand tool
    sys.exit("bench_bits.py needs bitstring: .venv/bin/pip install bitstring==5.0.0")

from mpeg4fa import __version__ as MPEG4FA_VERSION  # noqa: E402
from mpeg4fa.fba import decode  # noqa: E402
from mpeg4fa.fba.bits import BitReader  # noqa: E402
from mpeg4fa.fba.decoder import _Decoder  # noqa: E402
from mpeg4fa.fba.trace import trace  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_codec import best_time, pin_one_core  # noqa: E402  (the codec bench's timing and pinning)

REAL = REPO.parent / "shared" / "vectors" / "fba"
GENERATED = REPO / "conformance" / "vectors" / "syntax"


class BitsReader(BitReader):
    """A :class:`BitReader` whose buffer is a ``bitstring.Bits``: what the hot path would be on bitstring.

    ``decode_segment`` and ``peek_start_code`` index ``buf[p]`` (a ``bool`` from ``Bits``), fields
    are ``Bits`` slices read as unsigned integers; bytes sources only (no file window).
    """

    def __init__(self, data: bytes) -> None:
        super().__init__(b"")
        self.buf = Bits.from_bytes(bytes(data))

    def read(self, n: int, what: str = "a field") -> int:
        self.require(n, what)
        p = self.p
        self.p = p + n
        return self.buf[p:p + n].u if n else 0

    def digits(self, n: int) -> bytes:
        p = self.p
        self.p = p + n
        return self.buf[p:p + n].bin.encode()


class Work:
    """What each measurement reads, taken once from the syntax trace of every stream."""

    def __init__(self, paths: list[Path]) -> None:
        self.streams: list[tuple[bytes, list[tuple[int, int, int]], list[tuple[int, int]], int]] = []
        for path in paths:
            data = path.read_bytes()
            fields, spans, symbols = [], [], 0
            for e in trace(data):
                if e.kind in ("field", "marker") and e.width:
                    fields.append((e.offset, e.width, e.value))
                elif e.kind == "segment":
                    spans.append((e.offset, e.end))
                    symbols += len(e.symbols)
            self.streams.append((data, fields, spans, symbols))
        self.n_fields = sum(len(s[1]) for s in self.streams)
        self.n_bits = sum(b - a for s in self.streams for a, b in s[2])
        self.n_symbols = sum(s[3] for s in self.streams)


# ---- 1. header fields ---------------------------------------------------------------------
def fields_bitreader(work: Work) -> list[int]:
    out = []
    for data, fields, _, _ in work.streams:
        r = BitReader(data)
        for offset, width, _ in fields:
            r.p = offset
            out.append(r.read(width))
    return out


def fields_bitstring(work: Work) -> list[int]:
    out = []
    for data, fields, _, _ in work.streams:
        rd = Reader(Bits.from_bytes(data))
        for offset, width, _ in fields:
            rd.pos = offset
            out.append(rd.read_value(f"u{width}"))
    return out


def fields_bitstring_slices(work: Work) -> list[int]:
    out = []
    for data, fields, _, _ in work.streams:
        bits = Bits.from_bytes(data)
        for offset, width, _ in fields:
            out.append(bits[offset:offset + width].u)
    return out


# ---- 2. bits one at a time ----------------------------------------------------------------
def bits_bitreader(work: Work) -> int:
    ones = 0
    for data, _, spans, _ in work.streams:
        buf = BitReader(data).buf
        for a, b in spans:
            p = a
            while p < b:
                ones += buf[p]
                p += 1
    return ones


def bits_bitstring_index(work: Work) -> int:
    ones = 0
    for data, _, spans, _ in work.streams:
        buf = Bits.from_bytes(data)
        for a, b in spans:
            p = a
            while p < b:
                ones += buf[p]
                p += 1
    return ones


def bits_bitstring_reader(work: Work) -> int:
    ones = 0
    for data, _, spans, _ in work.streams:
        rd = Reader(Bits.from_bytes(data))
        for a, b in spans:
            rd.pos = a
            for _ in range(b - a):
                ones += rd.read_value("bool")
    return ones


# ---- 3. whole decode ----------------------------------------------------------------------
def decode_with(reader_type) -> list:
    frames = []
    for data, _, _, _ in WORK.streams:
        frames.extend((f.fap_values.tolist(), f.viseme.tolist(), f.expression.tolist(), f.bap_values.tolist(),
                       f.bits) for f in _Decoder(reader_type(data)).frames())
    return frames


def main(argv: list[str] | None = None) -> int:
    global WORK
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--vectors", type=Path, default=REAL)
    ap.add_argument("--repeat", type=int, default=5, help="best of N (default 5)")
    ap.add_argument("--json", type=Path, default=Path("bench_bits.json"))
    args = ap.parse_args(argv)
    pinned = pin_one_core()
    folder = args.vectors if args.vectors.is_dir() else GENERATED
    paths = sorted(p for p in folder.rglob("*") if p.is_file() and p.suffix.lower() == ".fba")
    WORK = work = Work(paths)
    print(f"mpeg4fa {MPEG4FA_VERSION}, bitstring {bitstring.__version__}, Python {platform.python_version()}, "
          f"{pinned}; {len(paths)} streams from {folder} (best of {args.repeat})")
    print(f"work: {work.n_fields} header fields, {work.n_bits} segment bits, {work.n_symbols} symbols\n")

    ok = True
    expected_fields = [v for _, fields, _, _ in work.streams for _, _, v in fields]
    rows = []

    def row(test: str, impl: str, seconds: float, count: int, unit: str, correct: bool) -> None:
        nonlocal ok
        ok &= correct
        rows.append({"test": test, "implementation": impl, "seconds": seconds, "count": count,
                     "per_second": count / seconds, "unit": unit, "correct": correct})

    for impl, fn in (("BitReader.read", fields_bitreader), ("bitstring Reader.read_value", fields_bitstring),
                     ("bitstring Bits[a:b].u", fields_bitstring_slices)):
        t, got = best_time(lambda fn=fn: fn(work), args.repeat)
        row("header fields", impl, t, work.n_fields, "fields/s", got == expected_fields)
    ones = None
    for impl, fn in (("BitReader buf[p]", bits_bitreader), ("bitstring Bits[p]", bits_bitstring_index),
                     ("bitstring Reader.read_value('bool')", bits_bitstring_reader)):
        t, got = best_time(lambda fn=fn: fn(work), args.repeat)
        ones = got if ones is None else ones
        row("bits one at a time", impl, t, work.n_bits, "bits/s", got == ones)
    reference = None
    for impl, reader_type in (("reference decoder on BitReader", BitReader),
                              ("reference decoder on BitsReader (bitstring)", BitsReader)):
        t, got = best_time(lambda rt=reader_type: decode_with(rt), args.repeat)
        reference = got if reference is None else reference
        row("whole decode", impl, t, work.n_symbols, "symbols/s", got == reference)
    # context: the compiled path reads the BitReader's unpacked bytes as a numpy array, which Bits is not
    t, got = best_time(lambda: [decode(data, backend="compiled") for data, _, _, _ in work.streams], args.repeat)
    same = [row_ for s_ in got for row_ in s_.fap_values.tolist()] == [f[0] for f in reference]
    row("whole decode", "decode(backend='compiled') (numba, context)", t, work.n_symbols, "symbols/s", same)

    print(f"{'test':<20} {'implementation':<46} {'seconds':>9} {'per second':>14}  {'vs BitReader':>12}  check")
    base: dict[str, float] = {}
    for r in rows:
        base.setdefault(r["test"], r["per_second"])
        r["relative"] = r["per_second"] / base[r["test"]]
        print(f"{r['test']:<20} {r['implementation']:<46} {r['seconds']:>9.4f} "
              f"{r['per_second']:>10,.0f} {r['unit'].split('/')[0]:<4}  {r['relative']:>11.2f}x  "
              f"{'ok' if r['correct'] else 'FAIL'}")
    result = {"mpeg4fa": MPEG4FA_VERSION, "bitstring": bitstring.__version__, "python": platform.python_version(),
              "machine": platform.machine(), "pinned": pinned, "repeat": args.repeat, "streams": len(paths),
              "folder": str(folder), "header_fields": work.n_fields, "segment_bits": work.n_bits,
              "symbols": work.n_symbols, "rows": rows, "checks_passed": ok}
    args.json.parent.mkdir(parents=True, exist_ok=True)
    args.json.write_text(json.dumps(result, indent=2) + "\n")
    print(f"\nwrote {args.json}")
    return 0 if ok else 1


WORK: Work


if __name__ == "__main__":
    sys.exit(main())
