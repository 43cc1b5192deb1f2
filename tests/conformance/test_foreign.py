"""The suite on decoders it was not written with (issue 30): the shipped example adapters (this
project's decoder as an external command, the C template) and the visage|SDK decoder, whose verdict
(which vectors fail, by rule) is pinned so that a change to the suite that flips a verdict on a
foreign decoder is seen."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.conformance.adapter import decode_for_suite
from mpeg4fa.conformance.manifest import Manifest, default_root, load_manifest
from mpeg4fa.conformance.protocol import CommandDecoder, Rejected
from mpeg4fa.conformance.report import write_report
from mpeg4fa.conformance.rules import rule_of
from mpeg4fa.conformance.runner import run_suite

sys.path.insert(0, str(Path(__file__).parent))
from small_suite import build_small_suite  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
ADAPTERS = ROOT / "conformance" / "adapters"
VISAGE = ROOT.parent / "shared" / "tools" / "visage-fbadec"


@pytest.fixture(scope="module")
def suite(tmp_path_factory):
    return build_small_suite(tmp_path_factory.mktemp("foreign"))


def test_the_python_adapter_passes_through_conform(suite):
    decoder = CommandDecoder(f"{sys.executable} {ADAPTERS / 'mpeg4fa_decoder.py'}")
    result = run_suite(suite, decoder, only=["syntax", "reject"], jobs=2)
    assert result.passed, result.failing()
    statuses = {(c.name, c.status) for v in result.vectors for c in v.checks}
    assert ("sent", "pass") in statuses and ("reject_offset", "pass") in statuses  # it reports both


@pytest.fixture(scope="module")
def c_adapter(tmp_path_factory):
    cc = shutil.which("cc") or shutil.which("gcc")
    if cc is None:
        pytest.skip("no C compiler (cc, gcc) to build the C template")
    folder = tmp_path_factory.mktemp("c-template")
    built = {}
    for name, flags in (("plain", []), ("ms", ["-DTIMESTAMP_RESOLUTION=0.001"])):
        exe = folder / f"conform-{name}"
        subprocess.run([cc, "-O1", "-Wall", "-Wextra", "-Werror", *flags, "-o", str(exe),
                        str(ADAPTERS / "c_decoder_template.c"), str(Path(__file__).parent / "c_hooks_dump.c")],
                       check=True, capture_output=True)
        built[name] = exe
    return built


def _dumps(manifest: Manifest, groups: tuple[str, ...]) -> None:
    """Beside each stream, what this project's decoder makes of it, for the C hooks to replay."""
    for v in manifest.vectors:
        if v.group not in groups:
            continue
        stream = manifest.path(v.stream)
        try:
            out, head = decode_for_suite(stream), "ok"
        except Rejected as exc:
            out, head = exc.partial, f"refuse {exc.bit_offset}"
        rows = [] if out is None else [" ".join(repr(float(x)) for x in (t, *row)) for t, row in zip(out.timestamps, out.shown)]
        Path(f"{stream}.dump").write_text("\n".join([head, *rows]) + "\n", encoding="utf-8")


def test_the_c_template_speaks_the_protocol(suite, c_adapter, tmp_path):
    _dumps(suite, ("syntax", "reject"))
    result = run_suite(suite, CommandDecoder(str(c_adapter["plain"])), only=["syntax", "reject"])
    assert result.passed, result.failing()
    assert {c.status for v in result.vectors for c in v.checks if c.name == "reject_offset"} == {"pass"}
    stream = suite.path(suite.vectors[0].stream)
    out = tmp_path / "out.json"
    subprocess.run([str(c_adapter["ms"]), str(stream), str(out)], check=True)
    doc = json.loads(out.read_text())
    assert doc["timestamp_resolution"] == 0.001 and len(doc["shown"][0]) == 68
    bad = subprocess.run([str(c_adapter["ms"]), str(stream)], capture_output=True, text=True)
    assert bad.returncode == 3 and "usage" in bad.stderr


# ---- visage|SDK (an oracle outside the project, used only when it is there) ---------------------------

VISAGE_FAILS = {
    "reject-malformed": {"reject/object-mask-0-p", "reject/frame-rate-0", "reject/marker-group-mask",
                         "reject/marker-new-minmax", "reject/marker-time-code", "reject/p-plane-first",
                         "reject/bad-stuffing", "reject/viseme-select-20"},
    "frame-rate-1001": {"syntax/fps-29.970", "syntax/fps-23.976"},
    "frame-times": {"syntax/fps-30", "syntax/body-only", "syntax/body-quant-03"},
    "frame-rate-default": {"syntax/fps-absent"},
    "ranges": {"syntax/ranges-carry"},
    "start-codes": {"syntax/aligned-end-code"},
}
"""visage's legitimate deviations, by rule: it decodes 8 malformed streams (marker bits, stuffing, selects and
masks unchecked), computes 1000/1001 as 0, truncates time stamps to whole milliseconds (fps-30: 1.899 for
1.9; unless it declares the resolution), refuses two valid streams (ranges kept by a later intra, an end
code with no stuffing byte). ``reject-position`` fails on the same 8 streams (it reports no fault)."""
MS_TRUNCATED = {"syntax/fps-30", "syntax/body-only", "syntax/body-quant-03", "syntax/fps-absent"}


def _visage(extra: str = "") -> CommandDecoder:
    if not (VISAGE / "fbadec").is_file():
        pytest.skip(f"the visage oracle is not here ({VISAGE / 'fbadec'}): it lives outside the project")
    return CommandDecoder(f"{sys.executable} {VISAGE / 'visage_adapter.py'}{extra}")


@pytest.fixture(scope="module")
def visage_run():
    decoder = _visage()
    committed = default_root() / "manifest.json"
    if not committed.is_file():
        pytest.skip("conformance/manifest.json is not generated yet")
    return run_suite(load_manifest(committed), decoder, jobs=2)


def test_visage_fails_only_its_legitimate_deviations(visage_run):
    by_rule = {g["rule"]: g for g in visage_run.by_rule()}
    required = {rule: set(g["vectors"]) for rule, g in by_rule.items() if g["required"]}
    assert required == {**VISAGE_FAILS, "reject-position": VISAGE_FAILS["reject-malformed"]}
    assert set(visage_run.failing()) == set().union(*VISAGE_FAILS.values())
    for v in visage_run.vectors:  # no required failure from an M rule, every failure names its rule
        for c in v.checks:
            rule = rule_of(c.name, {c.name: c.rule})
            if c.status == "fail":
                assert rule.required and rule.confidence in ("V", "S"), (v.vector.id, c.name, rule.id)
    partner = by_rule["partner-copy"]
    assert not partner["required"] and len(partner["vectors"]) >= 70  # FAPs::interpolateLR: one finding
    assert "copies the sent counterpart" in next(iter(partner["decoder_did"]))


def test_visage_report_names_every_rule_with_plots(visage_run, tmp_path):
    written = write_report(visage_run, tmp_path)
    md = written["markdown"].read_text(encoding="utf-8")
    for rule in VISAGE_FAILS:
        assert f"| {rule} |" in md
    assert "partner-copy" in md and "**FAILED**" in md
    plots = [p for k, p in written.items() if k.startswith("plot:")]
    assert len(plots) >= 10 and all(p.read_bytes()[:4] == b"\x89PNG" for p in plots)


def test_visage_declaring_milliseconds_passes_the_truncated_vectors(tmp_path):
    """Item 4: the same answers with ``timestamp_resolution: 0.001`` are judged within 1 ms."""
    wrapper = tmp_path / "ms.py"
    wrapper.write_text(
        "import json, subprocess, sys\n"
        f"r = subprocess.run([sys.executable, {str(VISAGE / 'visage_adapter.py')!r}, *sys.argv[1:]])\n"
        "out = sys.argv[2]\n"
        "try:\n    doc = json.load(open(out))\nexcept OSError:\n    sys.exit(r.returncode)\n"
        "doc['timestamp_resolution'] = 0.001\njson.dump(doc, open(out, 'w'))\nsys.exit(r.returncode)\n")
    _visage()
    manifest = load_manifest(default_root())
    manifest.vectors = [v for v in manifest.vectors if v.id in MS_TRUNCATED]
    plain = run_suite(manifest, _visage())
    declared = run_suite(manifest, CommandDecoder(f"{sys.executable} {wrapper}"))
    assert set(plain.failing()) == MS_TRUNCATED and declared.passed, declared.failing()
