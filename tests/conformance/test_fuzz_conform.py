"""A short run of the runner fuzz (tools/fuzz_conform.py): mutated decoder answers and suite files give a
verdict or a located error, never a crash, a hang or a MemoryError."""
from __future__ import annotations

import json
import sys
from pathlib import Path

TOOLS = Path(__file__).resolve().parents[2] / "tools"
sys.path.insert(0, str(TOOLS))

import fuzz_conform  # noqa: E402


def test_two_hundred_mutated_answers_and_suites_do_not_crash_the_runner(tmp_path):
    out = tmp_path / "fuzz.json"
    code = fuzz_conform.main(["--cases", "200", "--seed", "7", "--report-every", "100", "--memory-gib", "0",
                              "--out", str(tmp_path), "--json", str(out)])
    doc = json.loads(out.read_text())
    assert code == 0, doc["crashes"]
    assert {t: doc["targets"][t]["cases"] for t in ("answer", "suite")} == {"answer": 100, "suite": 100}
    assert all(doc["targets"][t]["ok"] == 100 for t in ("answer", "suite"))


def test_a_deeply_nested_answer_is_a_crash_result_not_a_recursion_error(tmp_path):
    from mpeg4fa.conformance.protocol import CRASH, CommandDecoder

    (tmp_path / "out.json").write_text("[" * 100_000 + "]" * 100_000)
    result = CommandDecoder._result(0, tmp_path / "out.json", "", 0.0)
    assert result.status == CRASH and "nest" in result.message
