"""The frame-rate rule has one home (FrameRate.from_fps, widths from spec/frame_rate.csv) and refuses
absurd finite rates with an FbaError, not an OverflowError (issue 26: a header rate of 1e308)."""
from __future__ import annotations

import pytest

from mpeg4fa.fba import FbaError
from mpeg4fa.fba.stream import FrameRate
from mpeg4fa.formats import FormatError, read_bap, read_fap
from mpeg4fa.spec.frame_rate import FPS_MAX, FPS_MIN


@pytest.mark.parametrize("fps", [1e308, -1e308, 1e20, 256.0, 1e-300, 0.01, float("inf"), float("nan"), 0])
def test_unsendable_rates_are_one_fbaerror(fps):
    with pytest.raises(FbaError, match="frame rate"):
        FrameRate.from_fps(fps)


@pytest.mark.parametrize("fps", [FPS_MIN, FPS_MAX, 25, 29.97, 255.7])
def test_edge_rates_are_carried(fps):
    assert abs(FrameRate.from_fps(fps).fps - fps) < 1 / 16


def test_limits_come_from_the_table():
    assert (FPS_MIN, FPS_MAX) == (1 / 16, 255 + 15 / 16)


@pytest.mark.parametrize("version, reader", [("2.1", read_fap), ("3.1", read_bap)])
def test_text_reader_refuses_a_header_rate_of_1e308(tmp_path, version, reader):
    path = tmp_path / "big.txt"
    path.write_text(f"{version} big 1e308 1\n")
    with pytest.raises(FormatError) as info:
        reader(path)
    assert info.value.line == 1 and "frame rate" in str(info.value)
