"""Which rule each check of a vector tests (ids of ``spec/conformance_rules.csv``).

Why per check and not per vector: a vector that tests quantisation also shows FAPs it never sends
and the partners of those it sends; how a decoder shows those is another rule (often one the
standard leaves open), and failing a decoder's quantisation over it would be a verdict on a guess.
So the runner splits a vector's checks by what each value depends on (:func:`mpeg4fa.conformance.compare.check_names`)
and each check names its rule; the manifest stores the vector's rules (``checks``), the generator
writes them from :func:`check_rules`.
"""
from __future__ import annotations

from fnmatch import fnmatchcase

from mpeg4fa.spec.conformance_rules import CONFORMANCE_RULES, ConformanceRule

SUB_CHECK_RULES = {
    "shown_high_level": "high-level-profiles",
    "shown_partner": "partner-copy",
    "shown_held": "unsent-hold",
    "shown_never_sent": "unsent-never",
    "timestamps_after_time_code": "time-code-follow",
}
"""Checks the runner splits off a vector's ``shown`` and ``timestamps`` by what the values depend on."""

BASE_RULES = {"timestamps": "frame-times", "sent": "decoded-values", "shown": "decoded-values",
              "feature_points": "fap-motion", "reject": "reject-malformed", "reject_offset": "reject-position",
              **SUB_CHECK_RULES}
"""The rule of each check unless a vector's pattern below says otherwise."""

_BY_VECTOR: tuple[tuple[str, dict[str, str]], ...] = (
    ("syntax/quant-*", {"value": "quantisation"}),
    ("syntax/mask-*", {"value": "mask-types"}),
    ("syntax/all-faps", {"value": "mask-types"}),
    ("syntax/ranges-*", {"value": "ranges"}),
    ("syntax/adaptation-halving", {"value": "arithmetic-coder"}),
    ("syntax/arith-stuffing", {"value": "arithmetic-coder"}),
    ("syntax/repair-lookahead", {"value": "arithmetic-coder"}),
    ("syntax/fps-29.970", {"value": "plane-header", "timestamps": "frame-rate-1001"}),
    ("syntax/fps-23.976", {"value": "plane-header", "timestamps": "frame-rate-1001"}),
    ("syntax/fps-absent", {"value": "plane-header", "timestamps": "frame-rate-default"}),
    ("syntax/fps-*", {"value": "plane-header"}),
    ("syntax/skip-*", {"value": "plane-header", "timestamps": "skip-frames"}),
    ("syntax/time-code*", {"value": "plane-header", "timestamps": "time-code"}),
    ("syntax/intra-p", {"value": "prediction"}),
    ("syntax/intra-period", {"value": "prediction"}),
    ("syntax/mask-change", {"value": "mask-types"}),
    ("syntax/face-body", {"value": "body-data"}),
    ("syntax/body-*", {"value": "body-data"}),
    ("syntax/p-fewer-parts", {"value": "plane-header"}),
    ("syntax/start-code-*", {"value": "start-codes"}),
    ("syntax/aligned-end-code", {"value": "start-codes"}),
    ("syntax/repair-hidden-frame", {"value": "start-codes"}),
    ("syntax/*", {"value": "plane-header"}),
    ("informative/mask-g01-*", {"value": "high-level-fields"}),
    ("informative/syntax-fap*", {"value": "high-level-fields"}),
    ("informative/viseme*", {"value": "high-level-fields"}),
    ("informative/expression*", {"value": "high-level-fields"}),
    ("informative/high-low-mix", {"value": "high-level-fields"}),
    ("informative/unsent-hold", {}),  # the sent values and times are required; the unsent ones the runner
    ("informative/interpolate-*", {}),  # splits off under their informative rules
    ("informative/hold-left-right", {}),
)


def check_rules(vector_id: str, confidence: str = "S") -> dict[str, str]:
    """Rule id per check name for a vector (only the checks whose rule differs from :data:`BASE_RULES`);
    ``value`` in the table above sets both ``sent`` and ``shown``."""
    for pattern, rules in _BY_VECTOR:
        if fnmatchcase(vector_id, pattern):
            out = {k: v for k, v in rules.items() if k != "value"}
            if "value" in rules:
                out.update(sent=rules["value"], shown=rules["value"])
            return out
    if confidence == "M":
        return {"sent": "unverified", "shown": "unverified", "timestamps": "unverified"}
    return {}


def rule_of(check: str, rules: dict[str, str] | None = None) -> ConformanceRule:
    """The rule a check tests: the vector's own (``rules``), else :data:`BASE_RULES`."""
    rule_id = (rules or {}).get(check) or BASE_RULES.get(check, "unverified")
    return CONFORMANCE_RULES[rule_id]
