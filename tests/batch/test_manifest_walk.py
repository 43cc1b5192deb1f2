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
