"""The semantic checker on hand-made streams: each rule fires at the right frame and FAP; clean streams give none."""
from __future__ import annotations

import json

import numpy as np
import pytest

from mpeg4fa.conformance.semantic import LONG_GAP_S, RULES, SEVERITIES, Finding, semantic_findings, summary
from mpeg4fa.decoded.limits import TRANSLATION_LIMIT
from mpeg4fa.fba import EncodeOptions, decode, encode
from mpeg4fa.fba.stream import FapStream, FrameRate
from mpeg4fa.spec import FAP_BY_NAME, FAPS, FULL_INTENSITY

FPS = 25.0
OPEN_JAW = FAP_BY_NAME["open_jaw"].number                 # unidirectional, MNS
RAISE_B_MIDLIP = FAP_BY_NAME["raise_b_midlip"].number     # bidirectional
HEAD_PITCH = FAP_BY_NAME["head_pitch"].number             # an angle (AU)


def made(n: int = 6) -> FapStream:
    """A clean face stream made in memory: open_jaw and raise_b_midlip, a viseme, at 25 fps."""
    stream = FapStream.empty(n)
    stream.source_fps = FPS
    stream.timestamps[:] = np.arange(n) / FPS
    for fap, value in ((OPEN_JAW, 100), (RAISE_B_MIDLIP, -50)):
        stream.fap_mask[:, fap - 1] = True
        stream.fap_values[:, fap - 1] = value
    stream.fap_mask[:, 0] = True
    stream.viseme[:] = (3, 5, 40, 0)
    return stream


def decoded(stream: FapStream, **options) -> FapStream:
    return decode(encode(stream, EncodeOptions(**options)))


def only(findings: list[Finding], rule: str) -> Finding:
    hits = [f for f in findings if f.rule == rule]
    assert len(hits) == 1, findings
    return hits[0]


def rules(findings: list[Finding]) -> set[str]:
    return {f.rule for f in findings}


# ---- clean streams ---------------------------------------------------------------------------------

def test_a_clean_stream_gives_no_finding():
    assert semantic_findings(made()) == []


@pytest.mark.parametrize("quant", [0, 1, 2, 7])
def test_a_clean_encoded_stream_gives_no_finding(quant):
    stream = made(30)
    stream.viseme[:, 2] = FULL_INTENSITY     # comes back as 64 at q = 2: legal
    stream.expression[:] = (1, FULL_INTENSITY, 6, 20, 0, 0)
    stream.fap_mask[:, 1] = True
    assert semantic_findings(decoded(stream, fap_quant=quant, intra_period=10)) == []


def test_an_empty_stream_gives_no_finding():
    assert semantic_findings(FapStream.empty(0)) == []


# ---- values ----------------------------------------------------------------------------------------

def test_negative_value_on_a_unidirectional_fap_is_an_error_at_its_frame_and_fap():
    stream = made()
    stream.fap_values[2, OPEN_JAW - 1] = -64
    finding = only(semantic_findings(stream), "unidirectional-negative")
    assert (finding.frame, finding.fap, finding.severity, finding.count, finding.worst) == (2, OPEN_JAW, "error", 1, -64)
    assert finding.line("s.fba") == ("s.fba: frame 2: FAP 3 (open_jaw): negative value -64 on a unidirectional FAP "
                                     "[error: unidirectional-negative]")


def test_a_repeated_finding_is_one_finding_with_count_and_worst():
    stream = made(1000)
    stream.fap_values[10:900, OPEN_JAW - 1] = -5
    stream.fap_values[500, OPEN_JAW - 1] = -328
    finding = only(semantic_findings(stream), "unidirectional-negative")
    assert (finding.frame, finding.count, finding.worst) == (10, 890, -328)
    assert "890 frames" in finding.message and "-328" in finding.message


def test_a_bidirectional_fap_may_be_negative_but_not_beyond_what_a_face_shows():
    stream = made()
    stream.fap_values[:, RAISE_B_MIDLIP - 1] = -TRANSLATION_LIMIT
    assert rules(semantic_findings(stream)) == {"beyond-default-i-range"}    # informative only
    stream.fap_values[4, RAISE_B_MIDLIP - 1] = -TRANSLATION_LIMIT - 1
    finding = only(semantic_findings(stream), "beyond-face")
    assert (finding.frame, finding.fap, finding.severity, finding.worst) == (4, RAISE_B_MIDLIP, "warning",
                                                                             -TRANSLATION_LIMIT - 1)


def test_an_angle_beyond_a_half_turn():
    stream = made()
    stream.fap_mask[:, HEAD_PITCH - 1] = True
    stream.fap_values[:, HEAD_PITCH - 1] = 314159      # pi in AU, rounded down
    assert semantic_findings(stream) == []
    stream.fap_values[3, HEAD_PITCH - 1] = 314160
    finding = only(semantic_findings(stream), "beyond-face")
    assert (finding.frame, finding.fap) == (3, HEAD_PITCH)


def test_default_ranges_are_informative():
    record = FAPS[RAISE_B_MIDLIP - 1]
    i_range = record.i_max * record.quant_step            # faps.csv: 1860 x 2, already a multiple of 60
    stream = made()
    stream.fap_values[:, RAISE_B_MIDLIP - 1] = i_range
    assert semantic_findings(stream) == []
    stream.fap_values[:, RAISE_B_MIDLIP - 1] = 0
    stream.fap_values[3:, RAISE_B_MIDLIP - 1] = i_range + 1
    found = semantic_findings(stream)
    assert {(f.rule, f.frame, f.fap, f.severity) for f in found} == {
        ("beyond-default-i-range", 3, RAISE_B_MIDLIP, "info"), ("beyond-default-p-range", 3, RAISE_B_MIDLIP, "info")}
    assert only(found, "beyond-default-i-range").count == 3
    assert only(found, "beyond-default-p-range").count == 1   # one jump, then no change


def test_unsent_faps_are_not_value_checked():
    stream = made()
    stream.fap_mask[:, OPEN_JAW - 1] = False
    stream.fap_values[:, OPEN_JAW - 1] = 0
    assert semantic_findings(stream) == []


# ---- FAP 1 and FAP 2 -------------------------------------------------------------------------------

@pytest.mark.parametrize("column, value, rule", [
    (0, 15, "viseme-select"), (1, -1, "viseme-select"), (2, 64, "blend-range"), (2, -1, "blend-range"),
    (3, 2, "flag-range"),
])
def test_viseme_fields_out_of_range(column, value, rule):
    stream = made()
    stream.viseme[4, column] = value
    finding = only(semantic_findings(stream), rule)
    assert (finding.frame, finding.fap, finding.severity, finding.worst) == (4, 1, "error", value)


@pytest.mark.parametrize("column, value, rule", [
    (0, 7, "expression-select"), (2, 9, "expression-select"), (1, 70, "blend-range"), (3, -3, "blend-range"),
    (4, 5, "flag-range"), (5, -1, "flag-range"),
])
def test_expression_fields_out_of_range(column, value, rule):
    stream = made()
    stream.fap_mask[:, 1] = True
    stream.expression[1, column] = value
    finding = only(semantic_findings(stream), rule)
    assert (finding.frame, finding.fap, finding.worst) == (1, 2, value)


def test_quantised_blend_may_come_back_above_63_but_no_further_than_the_quantiser_codes():
    source = made(10)
    source.viseme[:, 2] = FULL_INTENSITY
    stream = decoded(source, fap_quant=2)
    assert stream.viseme[0, 2] > FULL_INTENSITY          # 64 at q = 2
    assert semantic_findings(stream) == []
    stream.viseme[6, 2] = stream.viseme[0, 2] + 2
    finding = only(semantic_findings(stream), "blend-range")
    assert (finding.frame, finding.fap) == (6, 1)


def test_table_redefinition_is_informative():
    stream = made()
    stream.viseme[2:, 3] = 1
    finding = only(semantic_findings(stream), "table-redefinition")
    assert (finding.frame, finding.fap, finding.severity, finding.count) == (2, 1, "info", 4)


def test_high_level_fields_while_unsent():
    stream = made()
    stream.fap_mask[:, 1] = False
    stream.expression[3] = (2, 30, 0, 0, 0, 0)
    finding = only(semantic_findings(stream), "unsent-value")
    assert (finding.frame, finding.fap, finding.severity) == (3, 2, "warning")


def test_low_level_value_while_unsent():
    stream = made()
    stream.fap_mask[5, OPEN_JAW - 1] = False
    finding = only(semantic_findings(stream), "unsent-value")
    assert (finding.frame, finding.fap) == (5, OPEN_JAW)


# ---- masks -----------------------------------------------------------------------------------------

def test_mask_type_0_group_that_sends():
    stream = decoded(made(8))
    group = FAP_BY_NAME["head_pitch"].group
    assert stream.intra[0].face.mask_types[group - 1] == 0
    stream.fap_mask[5, HEAD_PITCH - 1] = True
    found = semantic_findings(stream)
    finding = only(found, "mask-type-0-sent")
    assert (finding.frame, finding.fap, finding.severity) == (5, HEAD_PITCH, "error")
    assert only(found, "mask-not-intra").frame == 5


def test_mask_type_3_group_that_leaves_a_fap_out():
    source = made(8)
    group = FAP_BY_NAME["head_pitch"].group
    members = [f.number for f in FAPS if f.group == group]
    source.fap_mask[:, [m - 1 for m in members]] = True
    stream = decoded(source)
    assert stream.intra[0].face.mask_types[group - 1] == 3
    assert semantic_findings(stream) == []
    stream.fap_mask[6, members[1] - 1] = False
    finding = only(semantic_findings(stream), "mask-type-3-unsent")
    assert (finding.frame, finding.fap) == (6, members[1])


def test_interpolation_with_no_counterpart_is_informative():
    left, right = FAP_BY_NAME["raise_l_cornerlip"].number, FAP_BY_NAME["raise_r_cornerlip"].number
    group = FAPS[left - 1].group
    members = [f.number for f in FAPS if f.group == group]
    types = [1] * 10
    types[group - 1] = 2
    source = made(5)
    source.fap_mask[:, [m - 1 for m in members]] = True
    source.fap_mask[:, right - 1] = False              # left to interpolation: copies the left corner
    stream = decoded(source, mask_types=types)
    assert stream.intra[0].face.mask_types[group - 1] == 2
    assert semantic_findings(stream) == []
    source.fap_mask[:, left - 1] = False               # now neither corner, nor the outer-lip ones, is sent
    found = semantic_findings(decoded(source, mask_types=types))
    assert {f.fap for f in found} == {left, right}
    assert all(f.rule == "interpolation-never" and f.severity == "info" and (f.frame, f.count) == (0, 5)
               for f in found)


def test_interpolation_is_not_asked_of_a_hold_group():
    assert semantic_findings(decoded(made(5), mask_types=[1] * 10)) == []


# ---- time ------------------------------------------------------------------------------------------

def test_time_going_backwards_and_repeated():
    stream = made(8)
    stream.timestamps[:] = np.array([0, 1, 2, 3, 2, 2, 3, 4]) / FPS
    found = semantic_findings(stream)
    back = only(found, "time-backwards")
    assert (back.frame, back.fap, back.severity) == (4, None, "error")
    assert back.worst == pytest.approx(-1 / FPS)
    repeated = only(found, "time-repeated")
    assert (repeated.frame, repeated.severity) == (5, "warning")


def test_time_that_disagrees_with_fps_and_skip():
    stream = made(6)
    stream.skip[2] = 3
    found = semantic_findings(stream)
    mismatch = only(found, "time-mismatch")
    assert (mismatch.frame, mismatch.count) == (3, 1)
    stream.timestamps[3:] += 3 / FPS
    assert semantic_findings(stream) == []


def test_skipped_frames_decode_clean():
    source = made(10)
    source.skip[4] = 20
    source.timestamps[5:] += 20 / FPS
    assert semantic_findings(decoded(source)) == []


def test_negative_and_long_skips():
    stream = made(4)
    stream.skip[1] = -1
    stream.skip[2] = int(LONG_GAP_S * FPS) + 1
    stream.timestamps[2] = stream.timestamps[1]           # what skip -1 asks for
    stream.timestamps[3] = stream.timestamps[2] + (stream.skip[2] + 1) / FPS
    found = semantic_findings(stream)
    assert (only(found, "skip-negative").frame, only(found, "skip-negative").severity) == (1, "error")
    long = only(found, "skip-long")
    assert (long.frame, long.severity) == (2, "warning")


def test_time_codes_may_fall_a_second_off_the_running_clock():
    stream = decoded(made(60), time_codes=True, intra_period=25)
    assert [k for k, p in stream.intra.items() if p.time_code is not None] == [0, 25, 50]
    assert semantic_findings(stream) == []
    stream.timestamps[25:] += 0.5                          # a time code counts whole seconds
    assert semantic_findings(stream) == []
    stream.timestamps[50:] += 1.5
    finding = only(semantic_findings(stream), "time-mismatch")
    assert finding.frame == 50 and finding.worst == pytest.approx(1.5)


# ---- frame rate ------------------------------------------------------------------------------------

def test_frame_rate_not_representable_in_a_header():
    stream = made()
    stream.source_fps = 23.9
    finding = only(semantic_findings(stream), "fps-not-representable")
    assert (finding.frame, finding.severity, finding.worst) == (0, "warning", 23.9)


def test_frame_rate_that_no_header_carries():
    stream = made()
    stream.source_fps = 300.0
    stream.timestamps[:] = np.arange(len(stream)) / 300.0
    assert only(semantic_findings(stream), "fps-invalid").severity == "error"


def test_1000_over_1001_and_unsent_rates_are_informative():
    stream = decoded(made(), fps=30000 / 1001)
    assert stream.intra[0].frame_rate.frequency_offset == 1
    assert rules(semantic_findings(stream)) == {"fps-1001"}
    stream.intra[0].frame_rate = None
    stream.timestamps[:] = np.arange(len(stream)) / 30.0
    assert rules(semantic_findings(stream)) == {"fps-unsent"}
    stream.intra[0].frame_rate = FrameRate(0)
    assert only(semantic_findings(stream), "fps-invalid").frame == 0


# ---- the rule table --------------------------------------------------------------------------------

def test_every_rule_is_documented_with_its_severity():
    import re

    import mpeg4fa.conformance.semantic as module

    bullets = [line for line in module.__doc__.splitlines() if line.startswith("* ``")]
    named = {name for line in bullets for name in re.findall(r"``([a-z0-9-]+)``", line.split("(")[0])}
    assert named == set(RULES)
    for name, rule in RULES.items():
        line = next(b for b in bullets if f"``{name}``" in b)
        assert f"({rule.severity})" in line, name


def test_findings_serialise_and_count():
    stream = made()
    stream.fap_values[1, OPEN_JAW - 1] = -1
    stream.viseme[2, 3] = 1
    found = semantic_findings(stream)
    assert summary(found) == {"error": 1, "warning": 0, "info": 1}
    record = json.loads(json.dumps([f.as_dict() for f in found]))
    assert record[0]["fap_name"] == "open_jaw" and record[0]["frame"] == 1


# ---- the command -----------------------------------------------------------------------------------

def write(stream: FapStream, path, **options) -> str:
    path.write_bytes(encode(stream, EncodeOptions(**options)))
    return str(path)


def test_cli_semantic_clean_stream_exits_0_with_a_summary(cli, tmp_path):
    path = write(made(), tmp_path / "clean.fba")
    code, out, _ = cli("validate", "--semantic", path)
    assert code == 0
    assert out.splitlines() == [f"{path}: valid syntax, 6 frames at 25 fps; semantic: 0 errors, 0 warnings, 0 info"]


def test_cli_without_semantic_is_unchanged(cli, tmp_path):
    stream = made()
    stream.fap_values[:, OPEN_JAW - 1] = -64
    path = write(stream, tmp_path / "neg.fba")
    code, out, _ = cli("validate", path)
    assert (code, out) == (0, f"{path}: valid: 6 frames at 25 fps\n")


def test_cli_semantic_error_exits_1_and_groups_repeats(cli, tmp_path):
    stream = made(1000)
    stream.fap_values[12, OPEN_JAW - 1] = -64
    stream.fap_mask[:, HEAD_PITCH - 1] = True
    stream.fap_values[100:, HEAD_PITCH - 1] = 1850 * FAPS[HEAD_PITCH - 1].quant_step   # past a half turn, 900 frames
    path = write(stream, tmp_path / "bad.fba")
    code, out, _ = cli("validate", "--semantic", path)
    lines = out.splitlines()
    assert code == 1
    assert lines[0] == (f"{path}: frame 12: FAP 3 (open_jaw): negative value -64 on a unidirectional FAP "
                        "[error: unidirectional-negative]")
    beyond = [line for line in lines if "beyond-face" in line]
    assert len(beyond) == 1 and "frame 100: FAP 48 (head_pitch)" in beyond[0] and "900 frames" in beyond[0]
    informative = [line for line in lines if "[info:" in line]
    assert len(lines) == 3 + len(informative) <= 6
    assert lines[-1].endswith(f"semantic: 1 error, 1 warning, {len(informative)} info")


def test_cli_semantic_warnings_and_info_do_not_fail(cli, tmp_path):
    stream = made()
    stream.viseme[:, 3] = 1                                        # info: table-redefinition
    code, out, _ = cli("validate", "--semantic", write(stream, tmp_path / "def.fba"))
    assert code == 0 and "table-redefinition" in out


def test_cli_semantic_json(cli, tmp_path):
    stream = made()
    stream.fap_values[2, OPEN_JAW - 1] = -64
    code, out, _ = cli("validate", "--semantic", "--json", write(stream, tmp_path / "neg.fba"))
    result = json.loads(out)
    assert code == 1
    assert result["valid"] is True and result["format"] == "fba" and result["frames"] == 6
    assert result["semantic"] == {"error": 1, "warning": 0, "info": 0}
    [finding] = result["findings"]
    assert finding == {"frame": 2, "fap": 3, "fap_name": "open_jaw", "severity": "error",
                       "rule": "unidirectional-negative", "message": "negative value -64 on a unidirectional FAP",
                       "count": 1, "worst": -64.0}


def test_cli_semantic_reads_fap_files(cli, tmp_path):
    from mpeg4fa.formats import write_fap

    stream = made()
    stream.fap_values[4, OPEN_JAW - 1] = -3
    path = tmp_path / "neg.fap"
    write_fap(stream, path)
    code, out, _ = cli("validate", "--semantic", path)
    assert code == 1 and f"{path}: frame 4: FAP 3 (open_jaw)" in out


def test_cli_semantic_invalid_syntax_is_reported_as_before(cli, tmp_path):
    path = tmp_path / "cut.fba"
    path.write_bytes(encode(made(), EncodeOptions())[:12])
    code, out, _ = cli("validate", "--semantic", path)
    plain_code, plain_out, _ = cli("validate", path)
    assert code == plain_code == 1 and out == plain_out and "invalid" in out
