#!/usr/bin/env python3
"""Fuzz the conformance runner with mutated decoder answers and suite files: a verdict, never a crash.

Why: a conformance tool exists to report wrong answers; an answer that crashes the runner (a matplotlib
traceback on a frame count, a ``RecursionError`` on deep JSON) ends the run that should have named it.
The reader-level ``conform`` target of ``tools/fuzz.py`` stops at ``read_output``; this one drives the
whole path after the decoder's process exits, as ``mpeg4fa conform`` does: exit status + stderr (bounded)
+ ``OUT.json`` / ``OUT.csv`` -> :meth:`CommandDecoder._result` -> :func:`compare` with the vector's rules
-> the suite's JSON, table and findings by rule, and every ``--report-every``-th case ``write_report``
(report.md, report.html, plots). Target ``suite`` mutates a suite's ``manifest.json`` and expected files
(a slice of the committed suite) and loads them as the runner does: only a located ``ConformanceError``
may come out.

    .venv/bin/python tools/fuzz_conform.py --cases 10000 --seed 0 [--target answer,suite] [--json out/e/fuzz.json]
    .venv/bin/python tools/fuzz_conform.py --case answer:1234 --seed 0        # one case again

Mutations are ``tools/fuzz_inputs.py``'s (JSON damage with nesting up to 100,000 levels, valid JSON with
wrong content, byte and line damage, number tokens, splices); the guards (per-case time limit, address
space cap) are ``tools/fuzz.py``'s. Each case is *ok* (a result, or for ``suite`` a ConformanceError),
*crash* (any other exception: input saved as ``OUT/crashes/TARGET-INDEX.bin`` with the traceback beside
it), *hang* (past ``--case-seconds``) or *memory* (a MemoryError under the cap). Exit status 1 when
anything but ok was seen.
"""
from __future__ import annotations

import argparse
import json
import random
import shutil
import sys
import tempfile
import time
import traceback
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import importlib.util  # noqa: E402


def _load_guards():
    """tools/fuzz.py (the guards) by path, as ``fuzz_tool``: the name ``fuzz`` belongs to the tests' package
    of that name, and the two must not replace each other whichever is imported first."""
    if "fuzz_tool" in sys.modules:
        return sys.modules["fuzz_tool"]
    spec = importlib.util.spec_from_file_location("fuzz_tool", Path(__file__).resolve().parent / "fuzz.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules["fuzz_tool"] = module
    spec.loader.exec_module(module)
    return module


fuzz = _load_guards()
import fuzz_inputs as fi  # noqa: E402  (the mutators)
import fuzz_seeds  # noqa: E402  (a decoder's answer and its expected file)

TARGETS = ("answer", "suite")
MUTATORS = {
    "answer": (fi.m_json,) * 4 + (fi.m_json_tree,) * 6 + (fi.m_bitflip, fi.m_insert, fi.m_delete, fi.m_truncate,
                                                        fi.m_duplicate, fi.m_splice, fi.m_number, fi.m_lines),
    "suite": (fi.m_json,) * 3 + (fi.m_json_tree,) * 8 + (fi.m_truncate, fi.m_number, fi.m_insert, fi.m_splice),
}
STDERRS = (b"", b"bad stream at bit 1234\n", b"refused (bit 99999999999999999999)\n", b"\xff\xfe bit 12 \x00\n",
           b"error at bit 1236 in frame 3\n" + b"x" * 200_000 + b"\nlast\n")
RETURN_CODES = (0, 0, 0, 0, 0, 1, 1, 1, 2, -11)


def answer_seeds() -> tuple[list[tuple[str, bytes]], dict]:
    """Answers a decoder may write (JSON with sent and feature points, shown only, a declared resolution, CSV)
    and the expected file they are judged by (all 68 columns, with a time-coded frame and feature points)."""
    doc, expected = fuzz_seeds.decoder_answer()
    seeds = list(fuzz_seeds.conform_seeds())
    seeds.append(("own/answer-ms.json", json.dumps({**{k: doc[k] for k in ("timestamps", "shown")},
                                                     "timestamp_resolution": 0.001}).encode()))
    expected = {**expected, "time_coded": [0, 3]}
    return [s for s in seeds if not s[0].endswith(".txt")], expected


def suite_slice(tmp: Path, count: int = 6) -> Path:
    """The first ``count`` vectors of the committed suite (manifest and expected files) in ``tmp/suite``."""
    from mpeg4fa.conformance.manifest import default_root

    src, root = default_root(), tmp / "suite"
    doc = json.loads((src / "manifest.json").read_text(encoding="utf-8"))
    picks = [v for v in doc["vectors"] if v["id"] in ("syntax/intra-only", "syntax/time-codes", "reject/truncated",
                                                     "semantics/fap-19", "informative/visemes")][:count]
    doc["vectors"] = picks
    for v in picks:
        for key in ("expected", "stream"):
            (root / v[key]).parent.mkdir(parents=True, exist_ok=True)
            shutil.copyfile(src / v[key], root / v[key])
    root.mkdir(exist_ok=True)
    (root / "manifest.json").write_text(json.dumps(doc, indent=1), encoding="utf-8")
    return root


class Campaign:
    def __init__(self, args: argparse.Namespace, tmp: Path) -> None:
        from mpeg4fa.conformance.manifest import full_width

        self.args, self.tmp = args, tmp
        self.guard = fuzz.Guard(args.case_seconds)
        self.answers, expected = answer_seeds()
        self.expected = full_width(expected)
        self.reject_expected = {"reject": True, "bit_offset": 1234, "frames_before": 2}
        self.suite = suite_slice(tmp)
        self.suite_seeds = [("manifest.json", (self.suite / "manifest.json").read_bytes())] + [
            (str(p.relative_to(self.suite)), p.read_bytes()) for p in sorted(self.suite.rglob("*.expected.json"))]
        self.tally: dict[str, Counter] = {t: Counter() for t in TARGETS}
        self.seen: dict[str, str] = {}
        self.crashes = Path(args.out) / "crashes"

    def mutate(self, target: str, rng: random.Random, seeds: list[tuple[str, bytes]]) -> tuple[str, bytes]:
        name, data = rng.choice(seeds)
        pool = [s[1] for s in seeds]
        for _ in range(rng.randint(1, 4)):
            try:
                data = rng.choice(MUTATORS[target])(rng, data, pool)[:fi.MAX_INPUT]
            except MemoryError:
                pass
        return name, data

    # ---- the targets ----------------------------------------------------------------------------------
    def run_answer(self, rng: random.Random, index: int) -> tuple[str, bytes]:
        from mpeg4fa.conformance.compare import compare
        from mpeg4fa.conformance.protocol import CommandDecoder, read_bounded
        from mpeg4fa.conformance.report import write_report
        from mpeg4fa.conformance.rules import check_rules
        from mpeg4fa.conformance.runner import SuiteResult, VectorResult, summary_table
        from mpeg4fa.conformance.manifest import Vector

        name, data = self.mutate("answer", rng, self.answers)
        case = self.tmp / "answer"
        shutil.rmtree(case, ignore_errors=True)
        case.mkdir()
        out = case / "out.json"
        as_csv = name.endswith(".csv") != (rng.random() < 0.1)
        (case / "out.csv" if as_csv else out).write_bytes(data)
        err = case / "stderr"
        err.write_bytes(rng.choice(STDERRS) if rng.random() < 0.8 else data[:300_000])
        with open(err, "rb") as fh:
            stderr = read_bounded(fh)
        expect = "reject" if rng.random() < 0.15 else "decode"
        vid = rng.choice(("syntax/time-codes", "semantics/fap-19", "informative/visemes", "syntax/quant-05"))
        vector = Vector(vid, vid.split("/")[0], "S", "fuzz", "x.fba", "", expect, "x.expected.json", "",
                        checks=tuple(sorted(check_rules(vid).items())))
        expected = self.reject_expected if expect == "reject" else self.expected
        result = CommandDecoder._result(rng.choice(RETURN_CODES), out, stderr, 0.01)
        checks = compare(expected, expect, result, vector.check_rules)
        suite = SuiteResult("fuzz", "fuzz", [VectorResult(vector, checks, 0.01, result, expected)], 0.01)
        json.dumps(suite.to_json())
        summary_table(suite)
        if self.args.report_every and index % self.args.report_every == 0:
            write_report(suite, case / "report")
        return name, data

    def run_suite(self, rng: random.Random, index: int) -> tuple[str, bytes]:
        from mpeg4fa.conformance.errors import ConformanceError
        from mpeg4fa.conformance.manifest import load_manifest

        name, data = self.mutate("suite", rng, self.suite_seeds)
        root = self.suite  # one file changed for the case, put back after it
        (root / name).write_bytes(data)
        try:
            try:
                manifest = load_manifest(root)
            except ConformanceError as exc:
                _located(exc)
                return name, data
            for vector in manifest.vectors:
                try:
                    manifest.expected(vector)
                except ConformanceError as exc:
                    _located(exc)
        finally:
            (root / name).write_bytes(dict(self.suite_seeds)[name])
        return name, data

    # ---- the loop -------------------------------------------------------------------------------------
    def one(self, target: str, index: int) -> str:
        rng = random.Random(f"{self.args.seed}:{target}:{index}")
        run = self.run_answer if target == "answer" else self.run_suite
        data = b""
        started = time.monotonic()
        try:
            self.guard.run(target, self.args.case_seconds, lambda: run(rng, index))
            return "ok"
        except fuzz._Hang:
            outcome = "hang"
        except MemoryError:
            outcome = "memory"
        except Exception as exc:  # noqa: BLE001 - what the fuzz exists to find
            outcome = "crash"
            key = f"{target}:{type(exc).__name__}:{fuzz._last_frame(exc)}"
            if key not in self.seen:
                self.seen[key] = f"{target}:{index}"
                self.crashes.mkdir(parents=True, exist_ok=True)
                (self.crashes / f"{target}-{index}.txt").write_text(
                    f"{key}\n{time.monotonic() - started:.2f} s\nreplay: {sys.executable} tools/fuzz_conform.py "
                    f"--case {target}:{index} --seed {self.args.seed}\n\n" + traceback.format_exc(), encoding="utf-8")
                print(f"CRASH {target}:{index} {key}", file=sys.stderr)
        del data
        return outcome


def _located(exc) -> None:
    """A ConformanceError must say where (a file, an entry): an unlocated one is a finding."""
    if not getattr(exc, "where", None):
        raise AssertionError(f"unlocated ConformanceError: {exc}")


def parse_args(argv: list[str] | None) -> argparse.Namespace:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--cases", type=int, default=10_000, help="cases in all, shared by the targets (default 10,000)")
    p.add_argument("--seconds", type=float, default=3600.0, help="stop after this long (default 1 h)")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--target", default=",".join(TARGETS), help="answer, suite or both (default)")
    p.add_argument("--case", help="TARGET:INDEX: run one case again")
    p.add_argument("--case-seconds", type=float, default=10.0, help="time limit of a case (default 10 s)")
    p.add_argument("--memory-gib", type=float, default=4.0, help="address space allowed above the start (GiB)")
    p.add_argument("--report-every", type=int, default=50, help="write the report with plots every N-th answer case")
    p.add_argument("--out", default="out/fuzz-conform", help="folder for crashes (default out/fuzz-conform)")
    p.add_argument("--json", help="write the summary here")
    return p.parse_args(argv)


def main(argv: list[str] | None = None) -> int:
    args = parse_args(argv)
    targets = [t.strip() for t in args.target.split(",") if t.strip()]
    if not targets or set(targets) - set(TARGETS):
        print(f"targets: {', '.join(TARGETS)}", file=sys.stderr)
        return 2
    import warnings
    warnings.simplefilter("ignore")
    fuzz.limit_memory(args.memory_gib)
    with tempfile.TemporaryDirectory(prefix="fuzz-conform-") as tmp:
        campaign = Campaign(args, Path(tmp))
        try:
            if args.case:
                target, index = args.case.split(":")
                outcome = campaign.one(target, int(index))
                print(f"{args.case}: {outcome}")
                return 0 if outcome == "ok" else 1
            started = time.monotonic()
            per = {t: args.cases // len(targets) + (i < args.cases % len(targets)) for i, t in enumerate(targets)}
            seconds: dict[str, float] = {}
            for target in targets:
                t0 = time.monotonic()
                for index in range(per[target]):
                    if time.monotonic() - started > args.seconds:
                        break
                    campaign.tally[target][campaign.one(target, index)] += 1
                seconds[target] = time.monotonic() - t0
        finally:
            campaign.guard.close()
    rows = [("target", "cases", "ok", "crash", "hang", "memory", "cases/s")]
    summary = {}
    for target in targets:
        t = campaign.tally[target]
        n = sum(t.values())
        rate = n / seconds[target] if seconds.get(target) else 0.0
        summary[target] = {"cases": n, **{k: t.get(k, 0) for k in ("ok", "crash", "hang", "memory")},
                           "cases_per_second": round(rate, 1)}
        rows.append((target, n, t.get("ok", 0), t.get("crash", 0), t.get("hang", 0), t.get("memory", 0), f"{rate:.1f}"))
    widths = [max(len(str(r[i])) for r in rows) for i in range(len(rows[0]))]
    for r in rows:
        print("  ".join(str(c).rjust(w) for c, w in zip(r, widths)))
    doc = {"seed": args.seed, "targets": summary, "crashes": campaign.seen}
    if args.json:
        Path(args.json).parent.mkdir(parents=True, exist_ok=True)
        Path(args.json).write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    bad = sum(summary[t][k] for t in summary for k in ("crash", "hang", "memory"))
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
