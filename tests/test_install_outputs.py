"""What the commands say, in words a newcomer reads right (issue 32 item 5): info's intra frames counted,
say's and encode's different --level defaults explained, times said as 'took X s for Y s', model pose's
table headed."""
from __future__ import annotations

import pytest

from mpeg4fa.fba import EncodeOptions, demo_stream, encode


def test_info_counts_intra_frames_and_names_their_mean(tmp_path, cli):
    path = tmp_path / "demo.fba"
    path.write_bytes(encode(demo_stream(), EncodeOptions(fap_quant=1, intra_period=25)))
    code, out, _ = cli("info", str(path))
    assert code == 0
    lines = {line.split(":")[0].strip(): line.split(":", 1)[1].strip() for line in out.splitlines()}
    assert lines["intra frames"] == "4 (frames 0 25 50 75)"
    assert "intra mean" in lines["bits per frame"] and "intra_mean" not in out


def test_info_of_one_intra_frame_is_not_a_bare_zero(tmp_path, cli):
    path = tmp_path / "demo.fba"
    path.write_bytes(encode(demo_stream(), EncodeOptions(fap_quant=1)))
    _, out, _ = cli("info", str(path))
    assert "intra frames: 1 (frame 0)" in out


@pytest.mark.parametrize("command, default, why", [
    ("say", "low", "say renders the stream itself"),
    ("encode", "high", "say's default, as it renders them itself"),
])
def test_level_defaults_say_why_they_differ(command, default, why):
    from mpeg4fa.cli import build_parser

    parser = build_parser(("codec", "speech"))
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction").choices[command]
    level = next(a for a in sub.complete()._actions if "--level" in a.option_strings)
    assert level.default == default
    assert why in " ".join(sub.format_help().split())


@pytest.mark.usefixtures("generic_head_installed")
def test_model_pose_heads_its_table(cli):
    code, out, _ = cli("model", "pose", "--viseme", "AA", "--fap", "19=300")
    assert code == 0
    lines = out.splitlines()
    assert lines[0] == "pose: viseme AA, FAP 19=300"
    heading = next(i for i, line in enumerate(lines) if line.startswith("feature points that moved:"))
    assert "in mm" in lines[heading] and lines[heading + 1].split()[:2] == ["point", "neutral"]
    assert lines[-1].startswith("most moved: ")
