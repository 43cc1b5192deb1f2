"""Rules per check (issue 30, item 1): the table in spec/, how the runner splits a vector's values by the rule
each depends on, and that informative rules never fail the suite."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.conformance.compare import DIFFERS, FAIL, PASS, check_names, compare, shown_cells
from mpeg4fa.conformance.manifest import default_root, load_manifest
from mpeg4fa.conformance.protocol import DECODED, DecoderOutput, DecoderResult
from mpeg4fa.conformance.rules import BASE_RULES, SUB_CHECK_RULES, check_rules, rule_of
from mpeg4fa.spec import conformance_rules
from mpeg4fa.spec.conformance_rules import CONFORMANCE_RULES


def test_the_table_required_rules_are_v_or_s_and_the_open_ones_informative():
    for rule in CONFORMANCE_RULES.values():
        assert rule.statement and rule.source
        assert not rule.required or rule.confidence in ("V", "S")
    for rule_id in ("unsent-hold", "partner-copy", "unsent-never", "high-level-profiles", "time-code-follow"):
        assert not CONFORMANCE_RULES[rule_id].required  # M, or left to the decoder by the standard
    assert set(BASE_RULES.values()) <= set(CONFORMANCE_RULES)


def test_the_table_refuses_a_required_m_rule(monkeypatch):
    rows = [{"id": "x", "statement": "s", "source": "facts", "confidence": "M", "kind": "required"}]
    monkeypatch.setattr(conformance_rules, "read_table", lambda name, columns: rows)
    with pytest.raises(ValueError, match="required rule must be V or S"):
        conformance_rules._rules()


def test_every_committed_vector_names_known_rules():
    manifest = load_manifest(default_root())
    for v in manifest.vectors:
        assert set(v.check_rules.values()) <= set(CONFORMANCE_RULES), v.id
        assert dict(v.checks) == check_rules(v.id, v.confidence), v.id  # the generator's table, as written
    quant = next(v for v in manifest.vectors if v.id == "syntax/quant-05")
    assert rule_of("shown", quant.check_rules).id == "quantisation"
    assert rule_of("shown_partner", quant.check_rules).id == "partner-copy"


def _expected(n: int = 3) -> dict:
    mask = np.zeros((n, 68), dtype=np.int64)
    mask[:, 30] = 1          # FAP 31 sent every frame (its partner FAP 32 never)
    mask[0, 2] = 1           # FAP 3 sent in frame 0 only
    shown = np.zeros((n, 68))
    shown[:, 30] = 40.0
    shown[:, 2] = 10.0       # held
    return {"frames": n, "timestamps": np.arange(n) / 25, "time_coded": [1], "shown": shown,
            "sent": {"mask": mask, "values": (shown * mask).astype(np.int64),
                     "viseme": np.zeros((n, 4), np.int64), "expression": np.zeros((n, 6), np.int64)},
            "tolerance": {"shown": 1e-3}}


def test_shown_values_split_by_what_they_depend_on():
    cells = shown_cells(_expected())
    assert cells["shown"][:, 30].all() and cells["shown"][0, 2]
    assert cells["shown_partner"][:, 31].all() and cells["shown_partner"].sum() == 3
    assert cells["shown_held"][1:, 2].all() and cells["shown_held"].sum() == 2
    assert cells["shown_never_sent"][:, 50].all()
    assert "shown_high_level" not in cells
    names = check_names(_expected(), "decode")
    assert names == ["timestamps", "timestamps_after_time_code", "sent", "shown", "shown_partner", "shown_held",
                     "shown_never_sent"]
    assert set(SUB_CHECK_RULES) >= set(names) - {"timestamps", "sent", "shown"}


def test_a_partner_copy_and_no_hold_differ_without_failing():
    expected = _expected()
    got = expected["shown"].copy()
    got[:, 31] = 40.0        # visage's interpolateLR: FAP 32 takes FAP 31's value
    got[1:, 2] = 0.0         # does not hold FAP 3
    times = expected["timestamps"].copy()
    times[2] += 0.5          # a plane after a time code placed otherwise (no source settles it)
    checks = {c.name: c for c in compare(expected, "decode", DecoderResult(DECODED, DecoderOutput(times, got)),
                                         {"shown": "quantisation"})}
    assert checks["shown"].status == PASS and checks["shown"].rule == "quantisation"
    assert checks["shown_partner"].status == DIFFERS and "copies the sent counterpart" in checks["shown_partner"].message
    assert checks["shown_held"].status == DIFFERS and checks["shown_held"].rule == "unsent-hold"
    assert checks["timestamps"].status == PASS and checks["timestamps_after_time_code"].status == DIFFERS
    assert not any(c.required and c.status != PASS for c in checks.values() if c.name != "sent")


def test_a_wrong_sent_value_fails_its_own_rule():
    expected = _expected()
    got = expected["shown"].copy()
    got[:, 30] = -40.0
    checks = {c.name: c for c in compare(expected, "decode", DecoderResult(DECODED, DecoderOutput(expected["timestamps"], got)),
                                         {"shown": "quantisation"})}
    assert checks["shown"].status == FAIL and checks["shown"].required
    assert checks["shown"].worst["fap"] == 31 and checks["shown"].to_json()["confidence"] == "V"
