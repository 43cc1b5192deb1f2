"""fba.js through the conformance protocol: adapter.mjs under `mpeg4fa conform --decoder`."""
from __future__ import annotations

import json
import subprocess
import sys

from .conftest import ROOT, need_node

ADAPTER = ROOT / "mpeg4fa" / "serve" / "static" / "js" / "fba" / "adapter.mjs"


def test_adapter_passes_the_reject_group():
    """Every reject vector refused, at a bit within the suite's tolerance (the whole suite, 168 vectors, takes
    a minute: `mpeg4fa conform --decoder 'node mpeg4fa/serve/static/js/fba/adapter.mjs'`, in the report)."""
    node = need_node()
    run = subprocess.run([sys.executable, "-m", "mpeg4fa.cli", "conform", "--only", "reject", "--json",
                          "--decoder", f"{node} {ADAPTER}"], capture_output=True, text=True, cwd=ROOT, timeout=300)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-2000:]
    reject = json.loads(run.stdout)["summary"]["reject"]
    assert reject["vectors"] >= 10 and reject["pass"] == reject["checks"], reject  # reject and reject_offset


def test_adapter_output(tmp_path):
    """A decodable vector: timestamps, shown and sent rows, one per frame; a refused one exits 1 naming the bit."""
    node = need_node()
    good = sorted((ROOT / "conformance" / "vectors" / "syntax").glob("*.fba"))[0]
    out = tmp_path / "out.json"
    run = subprocess.run([node, str(ADAPTER), str(good), str(out)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    doc = json.loads(out.read_text())
    n = len(doc["timestamps"])
    assert n > 0 and len(doc["shown"]) == n and all(len(row) == 68 for row in doc["shown"])
    assert len(doc["sent"]["mask"]) == n
    bad = tmp_path / "bad.fba"
    bad.write_bytes(good.read_bytes()[:-9])
    run = subprocess.run([node, str(ADAPTER), str(bad), str(tmp_path / "bad.json")], capture_output=True, text=True)
    assert run.returncode == 1 and " at bit " in run.stderr, run.stderr
