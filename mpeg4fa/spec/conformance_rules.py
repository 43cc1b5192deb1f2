"""The rules the conformance suite's checks test, with their source and confidence (``spec/conformance_rules.csv``).

Why data: a verdict on someone else's decoder is only as good as the rule behind it, so every check
names a rule, and a rule's confidence (V verified, S stated in a source, M unverified) decides
whether failing it fails the suite. A rule is *required* only when its row says so and its
confidence is V or S; M rules and the rules the standard leaves to the decoder are *informative*:
reported with what the decoder did, never a fail. The table is checked at import.
"""
from __future__ import annotations

from dataclasses import dataclass

from mpeg4fa.spec._load import check, read_table

CONFIDENCES = ("V", "S", "M")
KINDS = ("required", "informative")


@dataclass(frozen=True)
class ConformanceRule:
    id: str
    statement: str
    source: str
    confidence: str
    kind: str

    @property
    def required(self) -> bool:
        """Whether failing a check of this rule fails the suite (V or S, and not left to the decoder)."""
        return self.kind == "required" and self.confidence in ("V", "S")


def _rules() -> dict[str, ConformanceRule]:
    rows = read_table("conformance_rules.csv", "id,statement,source,confidence,kind")
    rules = {r["id"]: ConformanceRule(r["id"], r["statement"], r["source"], r["confidence"], r["kind"]) for r in rows}
    check(len(rules) == len(rows), "conformance_rules.csv: rule ids must be unique")
    check(all(r.confidence in CONFIDENCES and r.kind in KINDS for r in rules.values()),
          "conformance_rules.csv: confidence must be V, S or M and kind required or informative")
    check(not any(r.kind == "required" and r.confidence == "M" for r in rules.values()),
          "conformance_rules.csv: a required rule must be V or S (an M rule is informative)")
    return rules


CONFORMANCE_RULES: dict[str, ConformanceRule] = _rules()
"""Every rule a conformance check may name, by id, in the file's order."""
