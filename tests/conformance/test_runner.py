"""The runner, the decoder protocol (in-process and as a command), the comparison, the report and the CLI."""
from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.conformance.adapter import decode_for_suite, in_process
from mpeg4fa.conformance.compare import DIFFERS, FAIL, NOT_SUPPORTED, PASS, compare_rejected
from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.faults import faulty_decoder
from mpeg4fa.conformance.manifest import load_manifest
from mpeg4fa.conformance.protocol import (CRASH, DECODED, REJECTED, TIMEOUT, CommandDecoder, DecoderResult,
                                          InProcessDecoder, bit_from_text, output_from_csv, output_from_json,
                                          read_output, write_output)
from mpeg4fa.conformance.report import write_report
from mpeg4fa.conformance.runner import run_suite, summary_table

sys.path.insert(0, str(Path(__file__).parent))
from small_suite import build_small_suite  # noqa: E402


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    return build_small_suite(tmp_path_factory.mktemp("suite"))


@pytest.fixture(scope="module")
def passed(suite):
    return run_suite(suite, in_process())


def test_this_decoder_passes_the_small_suite(passed):
    assert passed.passed, passed.failing()
    statuses = {c.status for v in passed.vectors for c in v.checks}
    assert statuses <= {PASS, NOT_SUPPORTED}
    summary = passed.summary()
    assert list(summary) == ["syntax", "semantics", "reject", "informative"]
    assert summary["reject"]["pass"] == 2 and summary["semantics"]["vectors"] == 7
    assert "all" in summary_table(passed)


def test_without_feature_points_the_checks_are_not_supported_and_the_suite_passes(suite):
    decoder = InProcessDecoder(lambda s, f: decode_for_suite(s, f, feature_points=False))
    result = run_suite(suite, decoder, only=["semantics"])
    fp = [c for v in result.vectors for c in v.checks if c.name == "feature_points"]
    assert len(fp) == 6 and {c.status for c in fp} == {NOT_SUPPORTED}
    assert result.passed


def test_an_informative_failure_does_not_fail_the_suite(suite):
    result = run_suite(suite, faulty_decoder("sign-flipped"), only=["informative"])
    assert result.vectors[0].status == DIFFERS and not result.vectors[0].failed
    assert result.passed


def test_unknown_group_and_changed_files_are_errors(suite, tmp_path):
    with pytest.raises(ConformanceError, match="no group"):
        run_suite(suite, in_process(), only=["nope"])
    copy = build_small_suite(tmp_path)
    (copy.root / copy.vectors[0].stream).write_bytes(b"\x00")
    with pytest.raises(ConformanceError, match="SHA-256"):
        run_suite(load_manifest(copy.root), in_process())


# ---- the protocol -------------------------------------------------------------------------

def test_output_round_trips_through_json_and_csv(suite, tmp_path):
    out = decode_for_suite(suite.path(suite.vectors[0].stream))
    for name in ("o.json", "o.csv"):
        write_output(out, tmp_path / name)
    back = read_output(tmp_path / "o.json")
    assert np.array_equal(back.shown, out.shown) and np.array_equal(back.sent["values"], out.sent["values"])
    (tmp_path / "o.json").unlink()
    from_csv = read_output(tmp_path / "o.json")  # the runner looks for the .csv beside the .json
    assert from_csv.sent is None and np.allclose(from_csv.shown, out.shown) and len(from_csv) == len(out)


@pytest.mark.parametrize("doc, message", [
    ([], "timestamps"), ({"timestamps": [0], "shown": [[0] * 67]}, "shape"),
    ({"timestamps": [0, 1], "shown": [[0] * 68]}, "2 timestamps"),
    ({"timestamps": [0], "shown": [[0] * 68], "sent": {"mask": []}}, "sent"),
    ({"timestamps": [0], "shown": [[0] * 68], "feature_points": {"labels": ["2.1"], "positions": [[[0, 0]]]}},
     "feature_points"),
])
def test_bad_outputs_say_what_is_wrong(doc, message):
    with pytest.raises(ConformanceError, match=message):
        output_from_json(doc)


def test_csv_needs_its_header():
    with pytest.raises(ConformanceError, match="header"):
        output_from_csv("t,FAP1\n0,0\n")


def test_bit_offset_from_a_message():
    assert bit_from_text("error: bad code at bit 1234 (byte 154), frame 3") == 1234
    assert bit_from_text("no place") is None


def _script(tmp_path: Path, body: str) -> str:
    path = tmp_path / "decoder.py"
    path.write_text("import json, os, sys, time\nstream, out = sys.argv[1], sys.argv[2]\n" + body, encoding="utf-8")
    return f"{sys.executable} {path}"


@pytest.mark.parametrize("body, status, bit", [
    ("json.dump({'timestamps': [0.0], 'shown': [[0.0] * 68]}, open(out, 'w'))\n", DECODED, None),
    ("print('bad stream at bit 77', file=sys.stderr); sys.exit(1)\n", REJECTED, 77),
    ("sys.exit(3)\n", CRASH, None),
    ("os.kill(os.getpid(), 9)\n", CRASH, None),
    ("time.sleep(5)\n", TIMEOUT, None),
    ("pass\n", CRASH, None),  # exit 0 and no output
    ("open(out, 'w').write('{')\n", CRASH, None),
])
def test_command_decoder_statuses(tmp_path, body, status, bit):
    result = CommandDecoder(_script(tmp_path, body))(tmp_path / "x.fba", None, timeout=1.0)
    assert result.status == status, result.message
    assert result.bit_offset == bit


def test_command_decoder_gets_the_fdp(tmp_path):
    body = "assert sys.argv[3:] == ['--fdp', 'face.fdp']; sys.exit(1)\n"
    assert CommandDecoder(_script(tmp_path, body))(tmp_path / "x.fba", Path("face.fdp"), 5.0).status == REJECTED


def test_adapter_as_a_command_on_the_reject_vector(suite):
    result = run_suite(suite, CommandDecoder(f"{sys.executable} -m mpeg4fa.conformance.adapter"), only=["reject"])
    assert [c.status for c in result.vectors[0].checks] == [PASS, PASS]


def test_reject_offsets():
    want = {"reject": True, "bit_offset": 1000, "frames_before": 4}
    def checks(bit, partial=None):
        from mpeg4fa.conformance.protocol import DecoderOutput
        out = None if partial is None else DecoderOutput(np.zeros(partial), np.zeros((partial, 68)))
        return [c.status for c in compare_rejected(want, DecoderResult(REJECTED, out, bit))]
    assert checks(1000) == checks(1032) == checks(968) == [PASS, PASS]
    assert checks(1100) == [PASS, FAIL]
    assert checks(1100, partial=4) == [PASS, PASS]  # found in the same frame
    assert checks(None) == [PASS, NOT_SUPPORTED]
    assert [c.status for c in compare_rejected(want, DecoderResult(DECODED))] == [FAIL, FAIL]


# ---- report and CLI -----------------------------------------------------------------------

def test_report_shows_failures_with_plots(suite, tmp_path):
    result = run_suite(suite, faulty_decoder("left-right-swapped"))
    written = write_report(result, tmp_path / "report")
    md = written["markdown"].read_text(encoding="utf-8")
    assert "**FAILED**" in md and "syntax/interpolate: shown (fail, rule plane-header [V], required)" in md
    assert "expected" in md and "| plane-header | V | required |" in md
    png = tmp_path / "report" / "syntax_interpolate-shown.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "syntax_interpolate-shown.png" in written["html"].read_text(encoding="utf-8")


def test_an_informative_rule_differs_and_the_suite_passes(suite, tmp_path):
    result = run_suite(suite, faulty_decoder("hold-not-interpolate"))
    assert result.passed
    differs = [(v.vector.id, c) for v in result.vectors for c in v.checks if c.status == "differs"]
    assert [(vid, c.name, c.rule) for vid, c in differs] == [("syntax/interpolate", "shown_partner", "partner-copy")]
    md = write_report(result, tmp_path / "report")["markdown"].read_text(encoding="utf-8")
    assert "**PASSED**" in md and "partner-copy" in md and "informative" in md


def test_cli_passes_and_prints_json(cli, suite, passed, tmp_path):
    code, out, err = cli("conform", "--suite", suite.root, "--json", "--only", "syntax,reject",
                         "--report", tmp_path / "r")
    doc = json.loads(out)
    assert code == 0 and doc["passed"] and set(doc["summary"]) == {"syntax", "reject"}
    assert (tmp_path / "r" / "report.html").is_file()
    code, out, err = cli("conform", "--suite", suite.root, "--only", "reject")
    assert code == 0 and "PASSED" in out and "reject" in out


def test_cli_fails_on_a_failing_external_decoder(cli, suite, tmp_path):
    body = "json.dump({'timestamps': [0.0], 'shown': [[0.0] * 68]}, open(out, 'w'))\n"
    code, out, err = cli("conform", "--suite", suite.root, "--only", "syntax", "--decoder", _script(tmp_path, body))
    assert code == 1 and "FAILED" in out and "frames decoded, expected 10" in out


def test_cli_missing_suite_is_one_line(cli, tmp_path):
    code, out, err = cli("conform", "--suite", tmp_path / "none")
    assert code == 1 and err.count("\n") == 1 and "manifest.json" in err
    with pytest.raises(SystemExit) as exc:  # an argparse error: exit status 2 before any work
        cli("conform", "--suite", tmp_path, "--timeout", "0")
    assert exc.value.code == 2


def test_this_decoder_passes_the_committed_suite(cli):
    """`mpeg4fa conform` on the suite committed with the project: every required check passes."""
    from mpeg4fa.conformance.manifest import default_root

    code, out, err = cli("conform", "--json")
    doc = json.loads(out)
    assert code == 0 and doc["passed"], err
    assert set(doc["summary"]) >= {"syntax", "semantics", "reject"}
    assert (default_root() / "manifest.json").is_file()
