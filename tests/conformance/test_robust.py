"""The runner never crashes on a decoder's answer or a suite's files (issue 30, item 2): every malformed
answer is a located "fail" or "crash" result (in the table and in the report, plots included), a decoder
that never exits is ended with its whole process group, megabytes of stderr cost a bounded read, and a
malformed manifest or expected file is one located error."""
from __future__ import annotations

import json
import os
import resource
import shutil
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.conformance.compare import CRASH, FAIL, TIMEOUT, compare
from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.manifest import load_manifest
from mpeg4fa.conformance.protocol import (DECODED, REJECTED, STDERR_KEEP, CommandDecoder, DecoderOutput,
                                          DecoderResult, output_from_json)
from mpeg4fa.conformance.report import write_report
from mpeg4fa.conformance.runner import run_suite

sys.path.insert(0, str(Path(__file__).parent))
from small_suite import build_small_suite  # noqa: E402


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    return build_small_suite(tmp_path_factory.mktemp("robust"))


def _script(tmp_path: Path, body: str, name: str = "decoder.py") -> str:
    path = tmp_path / name
    path.write_text("import json, os, subprocess, sys, time\nstream, out = sys.argv[1], sys.argv[2]\n" + body,
                    encoding="utf-8")
    return f"{sys.executable} {path}"


ROW = "[0.0] * 68"
ANSWERS = {
    "wrong frame count": ("json.dump({'timestamps': [0.0, 0.04], 'shown': [" + ROW + "] * 2}, open(out, 'w'))", FAIL,
                          "frames decoded, expected"),
    "NaN": ("open(out, 'w').write('{\"timestamps\": [NaN], \"shown\": [[0]*68]}'.replace('[0]*68', ','.join(['0']*68)))",
            CRASH, "unreadable output"),
    "empty file": ("open(out, 'w').close()", CRASH, "unreadable output"),
    "extra columns": ("json.dump({'timestamps': [0.0], 'shown': [[0.0] * 70]}, open(out, 'w'))", CRASH, "shape"),
    "CSV wrong header": ("open(out[:-5] + '.csv', 'w').write('time,a,b\\n0,0,0\\n')", CRASH, "header"),
    "JSON missing keys": ("json.dump({'shown': [" + ROW + "]}, open(out, 'w'))", CRASH, "timestamps"),
    "deep nesting": ("open(out, 'w').write('[' * 200000 + ']' * 200000)", CRASH, "unreadable output"),
    "not an object": ("json.dump([1, 2, 3], open(out, 'w'))", CRASH, "expected an object"),
    "bad resolution": ("json.dump({'timestamps': [0.0], 'shown': [" + ROW + "], 'timestamp_resolution': 5}, open(out, 'w'))",
                       CRASH, "timestamp_resolution"),
}


@pytest.mark.parametrize("case", sorted(ANSWERS))
def test_a_malformed_answer_is_a_located_result(suite, tmp_path, case):
    body, status, words = ANSWERS[case]
    decoder = CommandDecoder(_script(tmp_path, body + "\n"))
    result = run_suite(suite, decoder, only=["syntax"])
    basic = result.vectors[0]
    assert {c.status for c in basic.checks} == {status}, basic.checks
    assert all(words in c.message for c in basic.checks), basic.checks[0].message
    written = write_report(result, tmp_path / "report")  # plots included: never a traceback
    assert "**FAILED**" in written["markdown"].read_text(encoding="utf-8")


def test_a_wrong_frame_count_is_plotted_frame_by_frame(suite, tmp_path):
    body = "json.dump({'timestamps': [k / 25 for k in range(3)], 'shown': [[0.0, 0.0] + [5.0] * 66] * 3}, open(out, 'w'))\n"
    result = run_suite(suite, CommandDecoder(_script(tmp_path, body)), only=["syntax"])
    written = write_report(result, tmp_path / "report")
    plots = [p for k, p in written.items() if k.startswith("plot:")]
    assert plots and all(p.stat().st_size > 1000 for p in plots)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    try:  # a zombie waiting for its parent counts as ended
        return Path(f"/proc/{pid}/stat").read_text().split(")")[-1].split()[0] != "Z"
    except OSError:
        return False


def test_a_timeout_ends_the_decoders_whole_process_group(tmp_path):
    pidfile = tmp_path / "child.pid"
    body = (f"child = subprocess.Popen(['sleep', '60'])\nopen({str(pidfile)!r}, 'w').write(str(child.pid))\n"
            "time.sleep(60)\n")
    started = time.monotonic()
    result = CommandDecoder(_script(tmp_path, body))(tmp_path / "x.fba", None, timeout=1.5)
    assert result.status == TIMEOUT and "process group" in result.message
    assert time.monotonic() - started < 10
    child = int(pidfile.read_text())
    deadline = time.monotonic() + 5
    while _alive(child) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(child), "the wrapper's child outlived the run"


def test_megabytes_on_stderr_are_read_bounded(tmp_path):
    body = ("sys.stderr.write('fault at bit 4321\\n'); sys.stderr.write(('x' * 1023 + '\\n') * 20000)\n"
            "sys.stderr.write('last line\\n'); sys.exit(1)\n")
    result = CommandDecoder(_script(tmp_path, body))(tmp_path / "x.fba", None, timeout=20)
    assert result.status == REJECTED and result.bit_offset == 4321
    assert result.message == "last line"
    assert STDERR_KEEP <= 1 << 20


def test_an_output_with_a_declared_resolution_round_trips():
    out = output_from_json({"timestamps": [0.0], "shown": [[0.0] * 68], "timestamp_resolution": 0.001})
    assert out.timestamp_resolution == 0.001 and out.to_json()["timestamp_resolution"] == 0.001
    expected = {"frames": 1, "timestamps": np.array([0.0009]), "shown": np.zeros((1, 68)),
                "sent": {"mask": np.zeros((1, 68), int), "values": np.zeros((1, 68), int)}}
    late = DecoderOutput(np.array([0.0]), np.zeros((1, 68)))
    assert compare(expected, "decode", DecoderResult(DECODED, late))[0].status == FAIL  # 0.9 ms > 0.5 ms
    late.timestamp_resolution = 0.001
    assert compare(expected, "decode", DecoderResult(DECODED, late))[0].status == "pass"
    late.timestamp_resolution = 0.5  # coarser than 1 ms: still judged within 1 ms
    expected["timestamps"] = np.array([0.0015])
    assert compare(expected, "decode", DecoderResult(DECODED, late))[0].status == FAIL


# ---- the suite's own files --------------------------------------------------------------------------------

@pytest.fixture
def copy(suite, tmp_path):
    root = tmp_path / "suite"
    shutil.copytree(suite.root, root)
    return root


def _edit(root: Path, change) -> None:
    doc = json.loads((root / "manifest.json").read_text())
    change(doc)
    (root / "manifest.json").write_text(json.dumps(doc))


@pytest.mark.parametrize("change, words", [
    (lambda d: d["vectors"][0].pop("stream"), 'vectors[0] (syntax/basic): "stream" is missing'),
    (lambda d: d["faces"].update(adult=3), "faces.adult"),
    (lambda d: d.pop("vectors"), '"vectors" must be a list'),
    (lambda d: d.update(vectors={"a": 1}), '"vectors" must be a list'),
    (lambda d: d["vectors"].__setitem__(1, "x"), "vectors[1]: a vector entry must be an object"),
    (lambda d: d["vectors"][0].update(stream="../../etc/hostname"), "leaves the suite's folder"),
    (lambda d: d["vectors"][0].update(expected="/etc/hostname"), "leaves the suite's folder"),
    (lambda d: d["faces"]["adult"].update(fdp="../x.fdp"), "leaves the suite's folder"),
    (lambda d: d["vectors"][0].update(checks={"shown": "no-such-rule"}), "unknown rule no-such-rule"),
    (lambda d: d["vectors"][0].update(face="nobody"), "face 'nobody'"),
    (lambda d: d["vectors"][0].update(expect="maybe"), '"expect" must be'),
])
def test_a_malformed_manifest_is_one_located_error(copy, change, words):
    _edit(copy, change)
    with pytest.raises(ConformanceError) as err:
        load_manifest(copy)
    assert words in str(err.value) and "manifest.json" in str(err.value)


def test_broken_manifest_json_is_located(copy, cli):
    (copy / "manifest.json").write_text('{"suite": "mpeg4fa-fba-conformance",\n "version": 1, "vectors": [}')
    code, out, err = cli("conform", "--suite", str(copy))
    assert code == 1 and "manifest.json:2:" in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_a_symlink_out_of_the_suite_is_refused(copy):
    (copy / "vectors" / "escape.fba").symlink_to("/etc/hostname")
    _edit(copy, lambda d: d["vectors"][0].update(stream="vectors/escape.fba"))
    with pytest.raises(ConformanceError, match="leaves the suite"):
        load_manifest(copy)


def test_an_expected_file_claiming_700000_frames_costs_nothing(copy):
    manifest = load_manifest(copy)
    vector = manifest.vectors[0]
    path = manifest.path(vector.expected)
    doc = json.loads(path.read_text())
    doc["frames"] = 700_000
    path.write_text(json.dumps(doc))
    before = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    with pytest.raises(ConformanceError, match="700000 frames"):
        manifest.expected(vector)
    assert resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before < 50_000  # kB
    doc["frames"] = 3  # a count that does not match the rows
    path.write_text(json.dumps(doc))
    with pytest.raises(ConformanceError, match="shape"):
        manifest.expected(vector)


@pytest.mark.parametrize("doc, words", [
    ([], "JSON object"), ({"frames": 1}, "no 'shown'"),
    ({"frames": 1, "timestamps": [0], "shown": [[0] * 68], "sent": {"mask": [[0] * 68], "values": [[0] * 67]}},
     "shape"),
])
def test_a_malformed_expected_file_is_located(copy, doc, words):
    manifest = load_manifest(copy)
    vector = manifest.vectors[0]
    manifest.path(vector.expected).write_text(json.dumps(doc))
    with pytest.raises(ConformanceError) as err:
        manifest.expected(vector)
    assert words in str(err.value) and vector.expected in str(err.value)


@pytest.mark.parametrize("command, words", [
    ("'unclosed", "cannot be split into words: No closing quotation"),
    ("decoder \\", "cannot be split into words"),
    ("", "the decoder command is empty"),
    ("   ", "the decoder command is empty"),
])
def test_a_decoder_command_that_is_no_command_is_one_line(copy, cli, command, words):
    """Fuzz of 2026-12-07: an unclosed quote ended in shlex's ValueError traceback, and an empty command quietly
    ran this project's own decoder instead."""
    code, out, err = cli("conform", "--suite", str(copy), "--decoder", command)
    assert code == 1 and words in err and "--decoder" in err, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1 and "PASSED" not in out
