"""The JSON manifest's job lines are found in the text the parser read (fuzz manifest:1343@2: a second
byte-order mark, dropped by the parser but not by the walk, ended in an IndexError)."""
from __future__ import annotations

import pytest

from mpeg4fa.batch import BatchError, load_manifest

JOBS = '[{"stream": "a.fba"},\n {"stream": "b.fba"},\n\n {"stream": "c.fba"}]'


@pytest.mark.parametrize("head", [b"", b"\xef\xbb\xbf", b"\xef\xbb\xbf\xef\xbb\xbf"], ids=["plain", "BOM", "two BOMs"])
@pytest.mark.parametrize("wrapped", [False, True], ids=["list", "object"])
def test_job_lines_after_a_byte_order_mark(tmp_path, head, wrapped):
    text = f'{{"jobs":\n {JOBS}}}' if wrapped else JOBS
    path = tmp_path / "jobs.json"
    path.write_bytes(head + text.encode())
    with pytest.raises(BatchError) as caught:
        load_manifest(path)
    first = 2 if wrapped else 1
    assert [p.split(":")[0] for p in caught.value.problems] == [
        f"job 0 at line {first}", f"job 1 at line {first + 1}", f"job 2 at line {first + 3}"], caught.value.problems


def test_an_unclosed_quote_in_a_csv_manifest_is_located(tmp_path):
    """Fuzz of 2026-12-07: ``"yes_0.fba,x.mp4`` was read as one stream name, so the error blamed a missing file."""
    path = tmp_path / "m.csv"
    path.write_text('stream,output\n"yes_0.fba,x.mp4\n', encoding="utf-8")
    with pytest.raises(BatchError, match="not valid CSV") as caught:
        load_manifest(path)
    assert caught.value.where == f"{path}:2" and "quote" in caught.value.hint


def test_ten_thousand_faults_make_a_line_of_twenty_and_keep_them_all(tmp_path):
    """Fuzz of 2026-12-07: 10,000 jobs of a missing file made one error line of 538 KB."""
    from mpeg4fa.batch.manifest import SHOWN_PROBLEMS

    path = tmp_path / "m.csv"
    path.write_text("stream\n" + "".join(f"missing{i}.fba\n" for i in range(10000)), encoding="utf-8")
    with pytest.raises(BatchError) as caught:
        load_manifest(path)
    assert len(caught.value.problems) == 10000 and str(caught.value).count("missing") == SHOWN_PROBLEMS
    assert "and 9,980 more" in str(caught.value) and len(str(caught.value)) < 5000
