"""Every JSON reader of the package goes through mpeg4fa.jsonio (issue 26: 100,000 '[' ended in a
RecursionError in a batch manifest and in an external decoder's answer, which killed conform)."""
from __future__ import annotations

import sys
import textwrap

import pytest

from mpeg4fa.batch.errors import BatchError
from mpeg4fa.batch.manifest import load_manifest
from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.protocol import CRASH, CommandDecoder, read_output

DEEP = b"[" * 100_000


def test_a_deep_manifest_is_one_located_error(tmp_path):
    path = tmp_path / "jobs.json"
    path.write_bytes(DEEP)
    with pytest.raises(BatchError, match="nested more than 8 levels") as info:
        load_manifest(path)
    assert info.value.where == f"{path}:1:9"


def test_manifest_bytes_that_are_not_utf8_are_located(tmp_path):
    path = tmp_path / "jobs.json"
    path.write_bytes(b'[{"stream": "a.fba"},\n {"stream": "\xe9.fba"}]')
    with pytest.raises(BatchError, match="not UTF-8") as info:
        load_manifest(path)
    assert info.value.where == f"{path}:2:14"


def test_manifest_jobs_keep_their_lines(tmp_path):
    (tmp_path / "s.fba").write_bytes(b"")
    path = tmp_path / "jobs.json"
    path.write_text("[\n" + ",\n\n".join('{"stream": "s.fba", "output": "o%d.mp4"}' % k for k in range(300)) + "\n]")
    jobs = load_manifest(path).jobs
    assert [job.where for job in jobs][:2] == ["job 0 at line 2", "job 1 at line 4"]
    assert jobs[-1].where == f"job 299 at line {2 + 2 * 299}"


def test_a_deep_decoder_answer_is_an_error_not_a_crash_of_the_run(tmp_path):
    out = tmp_path / "out.json"
    out.write_bytes(DEEP)
    with pytest.raises(ConformanceError, match="nested more than 8 levels"):
        read_output(out)
    script = tmp_path / "decoder.py"
    script.write_text(textwrap.dedent("""
        import sys
        open(sys.argv[2], "w").write("[" * 100000)
    """))
    result = CommandDecoder(f"{sys.executable} {script}")(tmp_path / "any.fba", None, 30)
    assert result.status == CRASH and "nested more than 8 levels" in result.message


def test_decoder_answers_that_broke_the_protocol_reader(tmp_path):
    from mpeg4fa.conformance.protocol import bit_from_text

    assert bit_from_text("error at bit " + "9" * 5000) is None and bit_from_text("at bit 1234 (byte 154)") == 1234
    out = tmp_path / "out.json"
    row = "[" + ", ".join(["0"] * 68) + "]"
    big = "[" + ", ".join(["1" + "0" * 40] * 68) + "]"
    out.write_text('{"timestamps": [0], "shown": [' + row + '], "sent": {"mask": [' + row + '], "values": ['
                   + big + '], "viseme": [[0, 0, 0, 0]], "expression": [[0, 0, 0, 0, 0, 0]]}}')
    with pytest.raises(ConformanceError, match="not an array of numbers"):
        read_output(out)
    out.unlink()
    out.with_suffix(".csv").write_text("t," + "x" * 200_000 + "\n")
    with pytest.raises(ConformanceError, match="not valid CSV"):
        read_output(out)


def test_a_manifest_path_the_system_refuses_is_a_problem_not_a_crash(tmp_path):
    path = tmp_path / "jobs.json"
    path.write_text('[{"stream": "' + "x" * 5000 + '.fba"}]')
    with pytest.raises(BatchError, match="File name too long"):
        load_manifest(path)
