"""The suite's self-test (issue 13, item 5): planted faults fail the vectors they should and pass the rest,
and this project's decoder passes everything; on the small suite built here, and on the committed
suite (``conformance/manifest.json``) when it is there."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.conformance.adapter import in_process
from mpeg4fa.conformance.compare import CRASH, DIFFERS, FAIL, TIMEOUT
from mpeg4fa.conformance.faults import FAULTS, SIGN_FLIPPED_FAP, faulty_decoder
from mpeg4fa.conformance.manifest import default_root, load_manifest
from mpeg4fa.conformance.runner import SuiteResult, run_suite
from mpeg4fa.spec import FAP_PARTNERS

sys.path.insert(0, str(Path(__file__).parent))
from small_suite import build_small_suite  # noqa: E402

BAD = (FAIL, CRASH, TIMEOUT)
HEAD_ROTATIONS = (48, 49, 50)

FAILS = {
    "fapu-es-for-irisd": {"semantics/fap-19-adult", "semantics/fap-19-wide"},
    "left-right-swapped": {"syntax/basic", "syntax/interpolate", "semantics/fap-19-adult", "semantics/fap-19-wide",
                           "semantics/fap-31-wide"},
    "sign-flipped": {"syntax/basic", "semantics/fap-05-adult"},
    "quant-step": {"syntax/basic", "syntax/fps-ntsc", "syntax/interpolate", "semantics/fap-03-adult", "semantics/fap-48-adult",
                   "semantics/fap-05-adult", "semantics/fap-31-wide"},
    "au-10x": {"semantics/fap-48-adult"},
    "fap19-mns": {"semantics/fap-19-adult", "semantics/fap-19-wide"},
    "ntsc-zero": {"syntax/fps-ntsc"},
    "ntsc-ignored": {"syntax/fps-ntsc"},
    "hold-not-interpolate": set(),
}
"""Vectors of the small suite each fault must fail (every other one must pass). Why each: FAP 19 is
the only IRISD FAP with a face; every vector sending a sided FAP or interpolating one shows the
swap, FAP 3 (midline) and the viseme do not; FAP 5 is in basic, its own vector and viseme AA/PP;
FAPs 3, 4, 5 and the brows have quantiser steps above 1, FAP 19 has step 1 (FAP 48 has 170); only fps-ntsc has the
1000/1001 flag; only interpolate uses mask type 2; only fap-48 turns the head (about 7.1). The viseme and
informative/basic show a fault only through informative rules (FAP 1 profiles, an M vector): "differs"."""
GEOMETRY = ("fapu-es-for-irisd", "au-10x", "fap19-mns")
INFORMATIVE = {"hold-not-interpolate": {("syntax/interpolate", "shown_partner")}}
"""Faults that break only a rule the standard leaves to the decoder (interpolation under mask type 2): the
suite reports them ("differs", with the rule) and still passes."""


def _bad(result: SuiteResult) -> set[str]:
    return {v.vector.id for v in result.vectors if v.status in BAD}


def _bad_checks(result: SuiteResult) -> set[str]:
    return {c.name for v in result.vectors for c in v.checks if c.status in BAD}


@pytest.fixture(scope="module")
def small(tmp_path_factory):
    return build_small_suite(tmp_path_factory.mktemp("selftest"))


def test_the_fault_list_is_complete():
    assert set(FAILS) == set(FAULTS)


def test_this_decoder_passes_everything(small):
    result = run_suite(small, in_process())
    assert result.passed and not _bad(result)


@pytest.mark.parametrize("name", sorted(FAULTS))
def test_each_fault_fails_what_it_should_and_passes_the_rest(small, name):
    result = run_suite(small, faulty_decoder(name))
    assert _bad(result) == FAILS[name]
    assert result.passed == (name in INFORMATIVE)
    differs = {(v.vector.id, c.name) for v in result.vectors for c in v.checks if c.status == DIFFERS}
    assert differs == INFORMATIVE.get(name, set()) or name not in INFORMATIVE
    if name in GEOMETRY:
        assert _bad_checks(result) == {"feature_points"}  # values right, geometry wrong
    if name.startswith("ntsc-"):
        assert _bad_checks(result) == {"timestamps"}


# ---- on the committed suite ---------------------------------------------------------------

COMMITTED = default_root() / "manifest.json"


@pytest.fixture(scope="module")
def committed():
    if not COMMITTED.is_file():
        pytest.skip("conformance/manifest.json is not generated yet")
    return load_manifest(COMMITTED)


@pytest.fixture(scope="module")
def committed_pass(committed):
    return run_suite(committed, in_process())


def test_this_decoder_passes_the_committed_suite(committed_pass):
    assert committed_pass.passed, committed_pass.failing()[:20]


def _asymmetric(expected: dict) -> bool:
    perm = np.where(FAP_PARTNERS[:, 0] >= 0, FAP_PARTNERS[:, 0], np.arange(len(FAP_PARTNERS)))
    tol = float(expected.get("tolerance", {}).get("shown", 1e-3))
    shown = np.asarray(expected["shown"], dtype=np.float64).reshape(-1, len(perm))
    if np.abs(shown[:, perm] - shown).max(initial=0.0) > tol:
        return True
    mask = np.asarray(expected["sent"]["mask"], dtype=bool).reshape(-1, len(perm))
    return bool((mask[:, perm] != mask).any())


def _uses(expected: dict, column: int) -> bool:
    tol = float(expected.get("tolerance", {}).get("shown", 1e-3))
    return bool(np.abs(np.asarray(expected["shown"], dtype=np.float64)[:, column]).max(initial=0.0) > tol)


def _lone_head_turn(expected: dict) -> bool:
    tol = float(expected.get("tolerance", {}).get("shown", 1e-3))
    active = np.abs(np.asarray(expected["shown"], dtype=np.float64)) > tol
    alone = active.sum(axis=1) == 1
    return bool((alone & active[:, [n - 1 for n in HEAD_ROTATIONS]].any(axis=1)).any())


def _bad_pairs(result: SuiteResult) -> set[tuple[str, str]]:
    """Checks a fault shows in: failed (a required rule) or differs (an informative one)."""
    return {(v.vector.id, c.name) for v in result.vectors for c in v.checks if c.status in BAD + (DIFFERS,)}


@pytest.mark.parametrize("name", sorted(FAULTS))
def test_each_fault_is_caught_by_the_committed_suite(committed, committed_pass, name):
    """Judged on what the fault adds to this decoder's own result, so a disagreement between the decoder
    and the suite (reported by the test above) does not hide or fake a fault's effect."""
    result = run_suite(committed, faulty_decoder(name))
    base = _bad_pairs(committed_pass)
    new = _bad_pairs(result) - base
    vectors = {vid for vid, _ in new}
    assert vectors, f"fault {name} fails nothing this decoder passes"
    assert result.passed == (name in INFORMATIVE)
    decoded = {v.vector.id: v.expected for v in committed_pass.vectors if v.vector.expect == "decode"}
    already = {vid for vid, _ in base}
    if name in GEOMETRY:
        assert {check for _, check in new} == {"feature_points"}
    if name.startswith("ntsc-"):
        assert {check for _, check in new} == {"timestamps"}
    predicted = None
    if name == "left-right-swapped":  # exactly the vectors whose expected output is not symmetric
        predicted = {vid for vid, e in decoded.items() if _asymmetric(e)}
    if name == "sign-flipped":  # exactly the vectors that show FAP 5
        predicted = {vid for vid, e in decoded.items() if _uses(e, SIGN_FLIPPED_FAP - 1)}
    if name == "au-10x":  # exactly the vectors with a face where a head rotation acts alone in some frame
        predicted = {vid for vid, e in decoded.items() if "feature_points" in e and _lone_head_turn(e)}
    if predicted is not None:
        assert vectors <= predicted and predicted - already <= vectors
