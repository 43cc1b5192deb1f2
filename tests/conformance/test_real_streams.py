"""Real-stream conformance (issue 13, item 7): other systems' streams in ../shared/vectors decode,
re-encode to the same bytes (``.fba``) or the same values (``.fap``), play, and get their semantic
findings listed, not failed: the findings are what we know about those encoders (run with ``-s``
to see them per stream)."""
from __future__ import annotations

import collections
import warnings
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.conformance.semantic import RULES, SEVERITIES, semantic_findings, summary
from mpeg4fa.decoded import resolve
from mpeg4fa.decoded.limits import LOWER, UPPER
from mpeg4fa.fba import decode, encode
from mpeg4fa.formats import read_fap, write_fap

VECTORS = Path(__file__).resolve().parents[2].parent / "shared" / "vectors"
ABSENT = f"../shared/vectors not present ({VECTORS}): real streams not checked"


def _streams() -> list:
    fba = sorted(p for p in (VECTORS / "fba").rglob("*") if p.is_file() and p.suffix.lower() == ".fba")
    fap = sorted(p for p in (VECTORS / "fap").rglob("*") if p.is_file() and p.suffix.lower() == ".fap")
    found = [pytest.param(p, id=str(p.relative_to(VECTORS))) for p in fba + fap]
    return found or [pytest.param(None, id="none", marks=pytest.mark.skip(reason=ABSENT))]


STREAMS = _streams()
needs_vectors = pytest.mark.skipif(not VECTORS.is_dir(), reason=ABSENT)
_FINDINGS: dict[str, collections.Counter] = {}


def _read(path: Path):
    return decode(path) if path.suffix.lower() == ".fba" else read_fap(path)


@pytest.mark.parametrize("path", STREAMS)
def test_real_stream_round_trips(path, tmp_path):
    stream = _read(path)
    assert len(stream) > 0
    if path.suffix.lower() == ".fba":
        assert encode(stream) == path.read_bytes()
        return
    copy = tmp_path / path.name
    write_fap(stream, copy)
    again = read_fap(copy)
    for name in ("fap_mask", "fap_values", "viseme", "expression", "skip", "timestamps"):
        assert np.array_equal(getattr(again, name), getattr(stream, name)), name
    assert again.fps == stream.fps


@pytest.mark.parametrize("path", STREAMS)
def test_real_stream_semantic_findings_are_listed(path):
    stream = _read(path)
    findings = semantic_findings(stream)
    for finding in findings:
        assert finding.rule in RULES and finding.severity == RULES[finding.rule].severity
        assert 0 <= finding.frame < len(stream) and 1 <= finding.count <= len(stream)
    counts = collections.Counter(f"{f.rule} ({f.severity})" for f in findings)
    _FINDINGS[str(path.relative_to(VECTORS))] = counts
    said = ", ".join(f"{n} {s}" for s, n in summary(findings).items())
    print(f"\n{path.relative_to(VECTORS)}: {len(stream)} frames, {said}")
    for finding in findings:
        print("  " + finding.line(path.name))
    # What the checker calls out of range on sent values, the player clamps: it plays within the bounds.
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        shown = resolve(stream)
    assert np.isfinite(shown).all()
    assert ((shown >= LOWER) & (shown <= UPPER)).all()
    flagged = {f.fap for f in findings if f.rule in ("unidirectional-negative", "beyond-face")}
    clamped = {int(s.split("FAP ")[1].split(" ")[0]) for s in map(str, (w.message for w in caught)) if "FAP " in s}
    assert flagged <= clamped


@needs_vectors
def test_zz_findings_per_rule_over_all_real_streams():
    """The per-rule totals over every real stream (the tests above fill them in; printed with -s)."""
    if not _FINDINGS:
        pytest.skip("the per-stream tests did not run in this session")
    total = collections.Counter()
    for counts in _FINDINGS.values():
        total.update(counts)
    print(f"\n{len(_FINDINGS)} real streams; findings per rule (severity), streams with it:")
    for rule, n in sorted(total.items()):
        print(f"  {rule}: {n} in {sum(rule in c for c in _FINDINGS.values())} streams")
    assert all(rule.split(" (")[1].rstrip(")") in SEVERITIES for rule in total)
