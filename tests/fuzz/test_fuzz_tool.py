"""tools/fuzz.py itself: a short campaign on its own seeds finds nothing, and each outcome is told apart."""
from __future__ import annotations

import importlib.util
import json
import mmap
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mpeg4fa.fba import FbaError
from mpeg4fa.speech.errors import MarkupError

TOOLS = Path(__file__).resolve().parents[2] / "tools"


def _load(name: str, file: str):
    """A tool script as a module (by path: this test package is itself named ``fuzz``)."""
    spec = importlib.util.spec_from_file_location(name, TOOLS / file)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


fuzz = _load("fuzz_tool", "fuzz.py")
fuzz_inputs = sys.modules["fuzz_inputs"]


@pytest.fixture(scope="module")
def seeds():
    """The seeds the tool makes itself (no ../shared/vectors: the same cases on every machine)."""
    return fuzz_inputs.collect_seeds(None)


@pytest.fixture
def campaign(tmp_path):
    guard = fuzz.Guard(0.5)
    yield fuzz.Campaign(0, tmp_path / "out", guard, 1 << 30, tmp_path)
    guard.close()


def test_own_seeds_for_every_target(seeds):
    assert all(seeds[target] for target in fuzz_inputs.TARGETS)


def test_short_campaign_finds_nothing(tmp_path, seeds):
    """The codec and FDP targets (the readers of issue 26 have their own test, ``test_fuzz_readers.py``)."""
    guard = fuzz.Guard(10.0)  # the limit per case, as the tool has by default
    campaign = fuzz.Campaign(0, tmp_path / "out", guard, 1 << 30, tmp_path)
    try:
        for target in fuzz_inputs.ORIGINAL_TARGETS:
            for index in range(25):
                campaign.run_case(target, index, seeds[target])
    finally:
        guard.close()
    for target, tally in campaign.tallies.items():
        assert tally.cases == 25
        assert tally.ok + tally.rejected == 25, (target, [vars(f) for f in campaign.findings.values()])
        assert tally.unlocated == 0, campaign.unlocated
    assert not campaign.findings


def test_a_case_is_the_same_every_time(campaign, seeds):
    for target in fuzz_inputs.TARGETS:
        first = fuzz_inputs.draw(campaign.case_rng(target, 7), target, seeds[target])
        assert fuzz_inputs.draw(campaign.case_rng(target, 7), target, seeds[target]) == first


def _runner(monkeypatch, target, body):
    monkeypatch.setitem(fuzz.RUNNERS, target, body)


def test_a_crash_is_saved_once_and_counted(campaign, monkeypatch):
    def crash(case):
        case.stage("parse", lambda: {}["missing"])
    _runner(monkeypatch, "markup", crash)
    assert campaign.run_input("markup", 3, b"(joy, 1, 1) hi", None, "test") == "crash"
    assert campaign.run_input("markup", 4, b"other", None, "test") == "crash"
    (finding,) = campaign.findings.values()
    assert (finding.type, finding.stage, finding.count, finding.first_case) == ("KeyError", "parse", 2, 3)
    saved = campaign.out / "crashes" / "markup-3.bin"
    assert saved.read_bytes() == b"(joy, 1, 1) hi"
    assert "KeyError" in saved.with_suffix(".txt").read_text(encoding="utf-8")
    assert campaign.tallies["markup"].crashes == 2


def test_the_layer_error_is_a_rejection(campaign, monkeypatch):
    def reject(case):
        case.stage("parse", lambda: (_ for _ in ()).throw(MarkupError("bad tag", 1, 2)))
    _runner(monkeypatch, "markup", reject)
    assert campaign.run_input("markup", 0, b"x", None, "test") == "rejected"
    assert campaign.tallies["markup"].unlocated == 0 and not campaign.findings


def test_a_slow_stage_is_a_hang(campaign, monkeypatch):
    _runner(monkeypatch, "markup", lambda case: case.stage("parse", lambda: time.sleep(5)))
    start = time.monotonic()
    assert campaign.run_input("markup", 0, b"x", None, "test") == "hang"
    assert time.monotonic() - start < 3
    assert campaign.tallies["markup"].hangs == 1


def test_the_cpu_clock_counts_work_not_waiting(tmp_path, monkeypatch):
    """``--clock cpu``: a case that waits (the machine busy elsewhere) is not a hang; one that works past its
    limit is, and the table keeps the wall clock's slowest beside the CPU clock's."""
    guard = fuzz.Guard(0.3, "cpu")
    run = fuzz.Campaign(0, tmp_path / "out", guard, 1 << 30, tmp_path)

    def spin():
        end = time.process_time() + 5
        while time.process_time() < end:
            pass
    try:
        _runner(monkeypatch, "markup", lambda case: case.stage("parse", lambda: time.sleep(0.6)))
        assert run.run_input("markup", 0, b"x", None, "test") == "ok"
        _runner(monkeypatch, "markup", lambda case: case.stage("parse", spin))
        start = time.process_time()
        assert run.run_input("markup", 1, b"y", None, "test") == "hang"
        assert time.process_time() - start < 2
    finally:
        guard.close()
    tally = run.tallies["markup"]
    assert tally.hangs == 1 and tally.slowest < 1.5 and tally.slowest_wall >= 0.6
    (finding,) = run.findings.values()
    assert "of CPU" in finding.message and finding.first_case == 1
    with pytest.raises(ValueError):
        fuzz.Guard(1.0, "sundial")


def test_memory_errors_are_blow_ups_even_when_wrapped(campaign, monkeypatch):
    def wrapped(case):
        try:
            raise MemoryError()
        except MemoryError as exc:  # what fba's guard does with a stray MemoryError
            raise FbaError("malformed stream (MemoryError)", 8) from exc
    _runner(monkeypatch, "fba", wrapped)
    assert campaign.run_input("fba", 0, b"x", None, "test") == "memory"
    _runner(monkeypatch, "markup", lambda case: (_ for _ in ()).throw(MemoryError()))
    assert campaign.run_input("markup", 0, b"x", None, "test") == "memory"


def test_command_line(tmp_path):
    """The tool as run on demand (a subprocess: it caps its own address space)."""
    out = tmp_path / "summary.json"
    done = subprocess.run([sys.executable, str(TOOLS / "fuzz.py"), "--cases", "30", "--seconds", "60",
                           "--target", ",".join(fuzz_inputs.ORIGINAL_TARGETS),
                           "--no-vectors", "--json", str(out), "--out", str(tmp_path)],
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stdout + done.stderr
    assert "cases/s" in done.stdout
    summary = json.loads(out.read_text(encoding="utf-8"))
    assert sum(t["cases"] for t in summary["targets"].values()) == 30
    assert summary["memory_cap_bytes"] and not summary["findings"]


def _touch_fresh_pages(size: int = 96 << 20) -> None:
    """Grow RSS by ``size`` for certain: an anonymous map is never memory the allocator kept from an earlier
    test (a bytearray may reuse freed heap that is already resident, and then the peak does not move)."""
    block = mmap.mmap(-1, size)
    try:
        block[::mmap.PAGESIZE] = b"\x01" * (size // mmap.PAGESIZE)
    finally:
        block.close()


def test_a_case_that_grows_memory_is_reported(tmp_path, monkeypatch):
    guard = fuzz.Guard(5.0)
    if not guard.peak_ok:
        guard.close()
        pytest.skip("no /proc/self/clear_refs: peak memory per case is not measured here")
    small = fuzz.Campaign(0, tmp_path / "out", guard, 32 << 20, tmp_path)
    try:
        _runner(monkeypatch, "markup", lambda case: case.stage("parse", _touch_fresh_pages))
        assert small.run_input("markup", 0, b"x", None, "test") == "ok"
        _runner(monkeypatch, "markup", lambda case: None)
        assert small.run_input("markup", 1, b"y", None, "test") == "ok"  # the next case starts afresh
    finally:
        guard.close()
    assert small.tallies["markup"].peak == 1
    (finding,) = small.findings.values()
    assert finding.kind == "peak" and finding.first_case == 0
