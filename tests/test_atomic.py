"""Outputs appear whole or not at all: the temporary beside the target, renamed on success, removed on failure."""
from __future__ import annotations

import os

import pytest

from mpeg4fa.atomic import PARTIAL_MARK, atomic_output, atomic_outputs
from mpeg4fa.errors import MpegFaError


def leftovers(folder):
    return sorted(p.name for p in folder.iterdir() if PARTIAL_MARK in p.name)


def test_success_renames_and_keeps_the_suffix(tmp_path):
    target = tmp_path / "talk.fba"
    with atomic_output(target) as partial:
        assert partial.parent == tmp_path and partial.name.startswith(".talk.partial-")
        assert partial.suffix == ".fba" and not target.exists()
        partial.write_bytes(b"stream")
    assert target.read_bytes() == b"stream" and leftovers(tmp_path) == []


@pytest.mark.parametrize("error", [RuntimeError("boom"), KeyboardInterrupt()])
def test_failure_removes_the_temporary_and_keeps_the_old_file(tmp_path, error):
    target = tmp_path / "talk.fba"
    target.write_bytes(b"old")
    with pytest.raises(type(error)):
        with atomic_output(target) as partial:
            partial.write_bytes(b"half")
            raise error
    assert target.read_bytes() == b"old" and leftovers(tmp_path) == []


def test_errors_name_the_target_not_the_temporary(tmp_path):
    target = tmp_path / "out.json"
    with pytest.raises(MpegFaError) as info:
        with atomic_output(target) as partial:
            raise MpegFaError(f"cannot write {partial}", where=str(partial))
    assert info.value.where == str(target) and str(target) in info.value.message
    with pytest.raises(FileNotFoundError) as missing:
        with atomic_output(tmp_path / "no" / "such" / "x.wav") as partial:
            open(partial, "wb")
    assert missing.value.filename == str(tmp_path / "no" / "such" / "x.wav")


def test_a_folder_is_made_under_a_temporary_name(tmp_path):
    target = tmp_path / "frames"
    with pytest.raises(ValueError):
        with atomic_output(target, directory=True) as partial:
            partial.mkdir()
            (partial / "frame_000000.png").write_bytes(b"png")
            raise ValueError("render failed")
    assert not target.exists() and leftovers(tmp_path) == []
    with atomic_output(target, directory=True) as partial:
        partial.mkdir()
        (partial / "frame_000000.png").write_bytes(b"png")
    assert sorted(os.listdir(target)) == ["frame_000000.png"] and leftovers(tmp_path) == []


def test_into_an_existing_folder_files_are_moved_and_others_kept(tmp_path):
    target = tmp_path / "frames"
    target.mkdir()
    (target / "notes.txt").write_text("mine")
    (target / "frame_000000.png").write_bytes(b"old")
    with atomic_output(target, directory=True) as partial:
        partial.mkdir()
        (partial / "frame_000000.png").write_bytes(b"new")
    assert (target / "notes.txt").read_text() == "mine" and (target / "frame_000000.png").read_bytes() == b"new"


def test_kind_clashes_are_refused_before_any_work(tmp_path):
    (tmp_path / "file").write_text("x")
    with pytest.raises(NotADirectoryError):
        with atomic_output(tmp_path / "file", directory=True):
            pytest.fail("the block must not run")
    with pytest.raises(IsADirectoryError):
        with atomic_output(tmp_path):
            pytest.fail("the block must not run")


def test_a_link_keeps_pointing_at_its_file(tmp_path):
    real = tmp_path / "real.fap"
    real.write_text("old")
    link = tmp_path / "link.fap"
    link.symlink_to(real)
    with atomic_output(link) as partial:
        partial.write_text("new")
    assert link.is_symlink() and real.read_text() == "new"


def test_a_device_is_written_directly():
    with atomic_output("/dev/null") as partial:
        assert str(partial) == "/dev/null"
        partial.write_bytes(b"discarded")


def test_several_outputs_are_all_written_or_none(tmp_path):
    a, b = tmp_path / "a.fba", tmp_path / "b.wav"
    with pytest.raises(OSError):
        with atomic_outputs(a, None, b) as (pa, none, pb):
            assert none is None
            pa.write_bytes(b"stream")
            raise OSError("disk full")
    assert not a.exists() and not b.exists() and leftovers(tmp_path) == []
    with atomic_outputs(a, b) as (pa, pb):
        pa.write_bytes(b"stream")
        pb.write_bytes(b"wav")
    assert a.read_bytes() == b"stream" and b.read_bytes() == b"wav"


# -- signals: SIGTERM/SIGHUP unwind like Ctrl-C; C callbacks hold them ----------------------------------

import signal  # noqa: E402

from mpeg4fa.atomic import Terminated, clean_up_on_signals, failed_output, signals_deferred  # noqa: E402


def test_sigterm_raises_terminated_and_removes_the_temporary(tmp_path):
    target = tmp_path / "talk.fba"
    target.write_bytes(b"old")
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Terminated) as info:
        with clean_up_on_signals(), atomic_output(target) as partial:
            partial.write_bytes(b"half")
            signal.raise_signal(signal.SIGTERM)
    assert isinstance(info.value, KeyboardInterrupt)
    assert info.value.signum == signal.SIGTERM and info.value.signal_name == "SIGTERM"
    assert target.read_bytes() == b"old" and leftovers(tmp_path) == []
    assert signal.getsignal(signal.SIGTERM) is before  # put back after the block


def test_an_ignored_signal_is_left_ignored():
    before = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with clean_up_on_signals():
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
            signal.raise_signal(signal.SIGHUP)  # ignored: nothing raised
    finally:
        signal.signal(signal.SIGHUP, before)


def test_signals_in_c_callbacks_are_delivered_after_the_call():
    with clean_up_on_signals():
        with pytest.raises(Terminated):
            with signals_deferred() as stopped:
                assert not stopped()
                signal.raise_signal(signal.SIGHUP)  # as if it came while C code ran a callback
                assert stopped()  # the callback tells the C code to stop; nothing raised yet


def test_a_write_error_names_the_output(tmp_path):
    """write() on a full disk raises OSError without a file name: atomic_output gives it the target's."""
    target = tmp_path / "out.fba"
    with pytest.raises(OSError) as info:
        with atomic_output(target):
            raise OSError(28, "No space left on device")
    assert info.value.filename == str(target) and failed_output(info.value) == str(target)
    assert str(target) in str(info.value)


def test_a_reader_error_on_the_temporary_and_a_full_device_name_the_output(tmp_path):
    """Fuzz of 2026-12-07: ``fdp -o unwritable/f.json`` said ``.f.partial-288e53de.json: permission denied`` (a
    FormatError keeps its file in ``path``), and ``encode -o /dev/full`` said only ``No space left on device``."""
    from mpeg4fa.formats import FormatError

    target = tmp_path / "f.json"
    with pytest.raises(FormatError) as info:
        with atomic_output(target) as partial:
            raise FormatError.no_place(str(partial), "permission denied")
    assert info.value.path == str(target) and str(info.value).startswith(f"{target}: ")
    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full here")
    with pytest.raises(OSError) as full:
        with atomic_output("/dev/full") as out, open(out, "wb", buffering=0) as f:
            f.write(b"x")
    assert failed_output(full.value) == "/dev/full" and full.value.filename == "/dev/full"
