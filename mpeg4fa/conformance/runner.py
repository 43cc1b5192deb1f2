"""Run every vector of a manifest through a decoder and collect pass / fail / not supported / crash / timeout.

Like Fluster's runner in shape: the suite is data (:mod:`.manifest`), the decoder is anything the
protocol can call (:mod:`.protocol`), and each vector gives one result per check (:mod:`.compare`).
The suite passes when no check of a *required* rule (V or S, ``spec/conformance_rules.csv``) fails, crashes
or times out; optional checks may be "not supported".
"""
from __future__ import annotations

import time
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Callable, Iterable

from mpeg4fa.conformance.compare import CRASH, DIFFERS, FAIL, NOT_SUPPORTED, PASS, STATUSES, TIMEOUT, Check, compare
from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.manifest import GROUPS, Manifest, Vector, sha256
from mpeg4fa.conformance.protocol import DEFAULT_TIMEOUT, Decoder, DecoderResult
from mpeg4fa.conformance.rules import rule_of

Progress = Callable[[int, int], None]
_WORST = (CRASH, TIMEOUT, FAIL, DIFFERS, NOT_SUPPORTED, PASS)


@dataclass
class VectorResult:
    """One vector's checks; ``expected`` and ``result`` stay for the report's plots."""

    vector: Vector
    checks: list[Check]
    seconds: float
    result: DecoderResult | None = field(default=None, repr=False)
    expected: dict[str, Any] | None = field(default=None, repr=False)

    @property
    def status(self) -> str:
        """The worst status of its checks (crash > timeout > fail > differs > not supported > pass)."""
        present = {c.status for c in self.checks}
        return next((s for s in _WORST if s in present), PASS)

    @property
    def failed(self) -> bool:
        """Whether this vector fails the suite: a check of a required rule failed, crashed or timed out."""
        return any(_counts_against(c) for c in self.checks)

    def to_json(self) -> dict[str, Any]:
        v = self.vector
        return {"id": v.id, "group": v.group, "confidence": v.confidence, "required": v.required,
                "status": self.status, "seconds": round(self.seconds, 4),
                "checks": [c.to_json() for c in self.checks]}


def _counts_against(check: Check) -> bool:
    """A check of a required rule (V or S) that failed, crashed, timed out, or is unsupported though not optional."""
    if not check.required:
        return False
    return check.status in (FAIL, CRASH, TIMEOUT) or (check.status == NOT_SUPPORTED and not check.optional)


@dataclass
class SuiteResult:
    decoder: str
    suite: str
    vectors: list[VectorResult]
    seconds: float

    @property
    def passed(self) -> bool:
        return not any(v.failed for v in self.vectors)

    def groups(self) -> list[str]:
        present = list(dict.fromkeys(v.vector.group for v in self.vectors))
        return sorted(present, key=lambda g: (GROUPS + (g,)).index(g))

    def summary(self) -> dict[str, dict[str, Any]]:
        """Per group: vectors, checks per status, and the vectors that fail the suite."""
        out: dict[str, dict[str, Any]] = {}
        for group in self.groups():
            members = [v for v in self.vectors if v.vector.group == group]
            counts = Counter(c.status for v in members for c in v.checks)
            out[group] = {"vectors": len(members), "checks": sum(counts.values()),
                          **{s: counts.get(s, 0) for s in STATUSES},
                          "vectors_failed": sum(v.failed for v in members),
                          "required": any(v.vector.required for v in members)}
        return out

    def by_rule(self) -> list[dict[str, Any]]:
        """Checks that did not pass, grouped by rule (required first, most first): one finding per rule, with
        its source, confidence, the vectors and the first of their messages."""
        groups: dict[str, dict[str, Any]] = {}
        for v in self.vectors:
            for c in v.checks:
                if c.status in (PASS, NOT_SUPPORTED):
                    continue
                rule = rule_of(c.name, {c.name: c.rule} if c.rule else None)
                g = groups.setdefault(rule.id, {"rule": rule.id, "statement": rule.statement, "source": rule.source,
                                                "confidence": rule.confidence, "required": rule.required,
                                                "checks": 0, "vectors": [], "statuses": Counter(), "example": "",
                                                "decoder_did": Counter()})
                g["checks"] += 1
                g["statuses"][c.status] += 1
                if v.vector.id not in g["vectors"]:
                    g["vectors"].append(v.vector.id)
                if not g["example"]:
                    g["example"] = f"{v.vector.id}: {c.name}: {c.message}"
                if c.worst.get("decoder_did"):
                    g["decoder_did"][c.worst["decoder_did"]] += 1
        out = sorted(groups.values(), key=lambda g: (not g["required"], -len(g["vectors"]), g["rule"]))
        for g in out:
            g["statuses"] = dict(g["statuses"])
            g["decoder_did"] = dict(g["decoder_did"])
        return out

    def failing(self) -> list[str]:
        """Ids of the vectors that fail the suite (required and not passed)."""
        return [v.vector.id for v in self.vectors if v.failed]

    def to_json(self) -> dict[str, Any]:
        return {"decoder": self.decoder, "suite": self.suite, "passed": self.passed,
                "seconds": round(self.seconds, 3), "summary": self.summary(), "failing": self.failing(),
                "by_rule": self.by_rule(), "vectors": [v.to_json() for v in self.vectors]}


def select(manifest: Manifest, only: Iterable[str] | None = None) -> list[Vector]:
    """The manifest's vectors in the named groups (all for None); ConformanceError for an unknown group."""
    if not only:
        return list(manifest.vectors)
    wanted = list(dict.fromkeys(only))
    unknown = [g for g in wanted if g not in manifest.groups()]
    if unknown:
        raise ConformanceError(f"no group {', '.join(unknown)} in the suite",
                               hint=f"groups: {', '.join(manifest.groups())}")
    return [v for v in manifest.vectors if v.group in wanted]


def _verified(manifest: Manifest, relative: str, digest: str, what: str) -> Any:
    path = manifest.path(relative)
    if not path.is_file():
        raise ConformanceError(f"{what} is missing", where=str(path))
    if digest and sha256(path) != digest:
        raise ConformanceError(f"{what} does not match its SHA-256 in the manifest", where=str(path),
                               hint="regenerate the suite or restore the file")
    return path


def run_vector(manifest: Manifest, vector: Vector, decoder: Decoder, timeout: float = DEFAULT_TIMEOUT) -> VectorResult:
    """One vector through ``decoder``, checked against its expected file."""
    stream = _verified(manifest, vector.stream, vector.sha256, f"stream of {vector.id}")
    _verified(manifest, vector.expected, vector.expected_sha256, f"expected file of {vector.id}")
    fdp = None
    if vector.face is not None:
        face = manifest.faces.get(vector.face)
        if face is None:
            raise ConformanceError(f"{vector.id} names face {vector.face!r}, which the manifest does not list")
        fdp = _verified(manifest, face.fdp, face.sha256, f"FDP of face {face.name}")
    expected = manifest.expected(vector)
    started = time.perf_counter()
    result = decoder(stream, fdp, timeout)
    checks = compare(expected, vector.expect, result, vector.check_rules)
    return VectorResult(vector, checks, time.perf_counter() - started, result, expected)


def run_suite(manifest: Manifest, decoder: Decoder, *, name: str = "", only: Iterable[str] | None = None,
              timeout: float = DEFAULT_TIMEOUT, progress: Progress | None = None, jobs: int = 1) -> SuiteResult:
    """Every selected vector through ``decoder``; ``progress(done, total)`` after each. ``jobs`` > 1 runs that
    many vectors at once in threads (for an external decoder: each is its own process); results keep the
    manifest's order."""
    vectors = select(manifest, only)
    started = time.perf_counter()
    if jobs <= 1 or len(vectors) <= 1:
        results = []
        for i, vector in enumerate(vectors):
            results.append(run_vector(manifest, vector, decoder, timeout))
            if progress is not None:
                progress(i + 1, len(vectors))
    else:
        from concurrent.futures import ThreadPoolExecutor, as_completed

        with ThreadPoolExecutor(max_workers=jobs) as pool:
            futures = {pool.submit(run_vector, manifest, vector, decoder, timeout): i for i, vector in enumerate(vectors)}
            done: dict[int, VectorResult] = {}
            try:
                for future in as_completed(futures):
                    done[futures[future]] = future.result()
                    if progress is not None:
                        progress(len(done), len(vectors))
            except BaseException:
                for future in futures:
                    future.cancel()
                raise
        results = [done[i] for i in range(len(vectors))]
    return SuiteResult(name or getattr(decoder, "name", "decoder"), str(manifest.root), results,
                       time.perf_counter() - started)


def summary_table(suite: SuiteResult) -> str:
    """The per-group summary as a fixed-width text table (the CLI's output)."""
    head = ("group", "vectors", "checks", *STATUSES, "failed")
    rows = [head]
    total = Counter()
    for group, s in suite.summary().items():
        label = group if s["required"] or group == "informative" else f"{group} (informative)"
        row = (label, s["vectors"], s["checks"], *(s[k] for k in STATUSES), s["vectors_failed"])
        rows.append(row)
        total.update({k: s[k] for k in ("vectors", "checks", *STATUSES, "vectors_failed")})
    rows.append(("all", total["vectors"], total["checks"], *(total[k] for k in STATUSES), total["vectors_failed"]))
    widths = [max(len(str(r[i])) for r in rows) for i in range(len(head))]
    lines = ["  ".join(str(c).ljust(w) if i == 0 else str(c).rjust(w) for i, (c, w) in enumerate(zip(r, widths)))
             for r in rows]
    lines.insert(1, "-" * len(lines[0]))
    lines.insert(len(lines) - 1, "-" * len(lines[0]))
    return "\n".join(lines)
