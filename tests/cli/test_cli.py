"""The mpeg4fa command, run in-process on files the tests make themselves."""
from __future__ import annotations

import json

import pytest

from mpeg4fa.cli import main
from mpeg4fa.fba import decode, demo_stream


@pytest.fixture()
def demo(tmp_path):
    path = tmp_path / "demo.fba"
    assert main(["demo", "-o", str(path)]) == 0
    return path


def test_demo_writes_a_stream_that_decodes(demo):
    stream = decode(demo)
    assert len(stream) == len(demo_stream())
    assert stream.fps == 25.0


def test_demo_says_what_it_wrote_without_reading_it_back(capsys):
    """Fuzz of 2026-12-07: ``demo -o /dev/null`` wrote the stream, read its output back, found nothing there and
    failed with "/dev/null:1: the file has no header"."""
    assert main(["demo", "-o", "/dev/null"]) == 0
    out = capsys.readouterr().out
    assert "file: /dev/null" in out and "frames: 100" in out


def test_info_json(demo, capsys):
    capsys.readouterr()
    assert main(["info", str(demo), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["format"] == "fba"
    assert info["frames"] == 100
    assert info["duration_s"] == pytest.approx(4.0)
    assert info["bytes"] == demo.stat().st_size
    assert info["kbit_per_s"] == pytest.approx(demo.stat().st_size * 8 / 4.0 / 1000, rel=1e-3)
    assert 1 in info["faps_sent"] and 3 in info["faps_sent"]


def test_decode_then_encode_round_trip(demo, tmp_path):
    fap = tmp_path / "demo.fap"
    again = tmp_path / "again.fba"
    assert main(["decode", str(demo), "-o", str(fap)]) == 0
    assert fap.read_text().startswith("2.1 ")
    assert main(["encode", str(fap), "-o", str(again), "--quant", "1"]) == 0
    a, b = decode(demo), decode(again)
    assert (a.fap_values == b.fap_values).all() and (a.viseme == b.viseme).all()


def test_reencode_fba_is_byte_identical(demo, tmp_path):
    out = tmp_path / "same.fba"
    assert main(["encode", str(demo), "-o", str(out)]) == 0
    assert out.read_bytes() == demo.read_bytes()


def test_encode_options_change_the_stream(demo, tmp_path):
    out = tmp_path / "coarse.fba"
    assert main(["encode", str(demo), "-o", str(out), "--quant", "8", "--intra-period", "25"]) == 0
    stream = decode(out)
    assert sorted(stream.intra) == [0, 25, 50, 75]
    assert stream.intra[0].face.quant == 8
    assert out.stat().st_size < demo.stat().st_size


def test_validate_exit_status(demo, tmp_path, capsys):
    assert main(["validate", str(demo)]) == 0
    broken = tmp_path / "broken.fba"
    broken.write_bytes(demo.read_bytes()[:60])
    capsys.readouterr()
    assert main(["validate", str(broken)]) == 1
    line = capsys.readouterr().out.strip()
    assert "invalid" in line and "bit " in line and "\n" not in line
    assert main(["validate", str(broken), "--json"]) == 1
    result = json.loads(capsys.readouterr().out)
    assert result["valid"] is False and isinstance(result["bit_offset"], int)


def test_errors_are_one_line_and_status_1(tmp_path, capsys):
    assert main(["info", str(tmp_path / "missing.fba")]) == 1
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "error" in err
    bad = tmp_path / "bad.fap"
    bad.write_text("2.1 x 25 1\n1 0 1\n")
    assert main(["encode", str(bad), "-o", str(tmp_path / "x.fba")]) == 1
    assert "bad.fap:2" in capsys.readouterr().err


def test_help_of_every_command(capsys):
    for command in ("info", "decode", "encode", "validate", "demo"):
        with pytest.raises(SystemExit) as exc:
            main([command, "--help"])
        assert exc.value.code == 0
        assert "usage: mpeg4fa " + command in capsys.readouterr().out
