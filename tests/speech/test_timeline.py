"""Checks of the FAP timeline: Hermite curves, viseme and expression tracks, merging, idle, frames."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mpeg4fa.spec import N_FAPS
from mpeg4fa.spec.profiles import EXPRESSION_PROFILES, VISEME_PROFILES, expression_blend
from mpeg4fa.speech.timeline import (
    CLOSURE_HOLD, CLOSURES, LAG, LAG_SHARE, LEAD, LEAD_SHARE, MIN_MOVE, ExpressionCue, VisemeSpan,
    expression_fields, expression_intensities, expression_track, frame_times, hermite, hermite_slope,
    idle_track, merge_tracks, viseme_fields, viseme_track,
)

PROPERTY = settings(max_examples=80, deadline=None, derandomize=True)
MPEG4 = [name for name in VISEME_PROFILES["mpeg4"] if name != "none"]


def profile(name: str, set_name: str = "mpeg4") -> np.ndarray:
    return VISEME_PROFILES[set_name][name].astype(np.float64)


def intensity_of(cues, times, name: str) -> np.ndarray:
    names, levels = expression_intensities(cues, np.atleast_1d(np.asarray(times, dtype=np.float64)))
    return levels[:, names.index(name)]


def slopes_around(f, at: float, h: float = 1e-5) -> tuple[np.ndarray, np.ndarray]:
    """Slopes (per second) just before and just after ``at``, from one side each.

    One-sided differences at two step sizes, extrapolated to ``at`` (Richardson),
    so the curvature near a join does not read as a kink.
    """
    def one_side(sign: float, step: float) -> np.ndarray:
        near, far = f(np.array([at + sign * step]))[0], f(np.array([at + sign * 2 * step]))[0]
        return (far - near) / (sign * step)

    return (2 * one_side(-1.0, h) - one_side(-1.0, 2 * h),
            2 * one_side(1.0, h) - one_side(1.0, 2 * h))


# ---- Hermite ---------------------------------------------------------------------------------------

def test_hermite_hand_values():
    assert hermite(0.0, 10.0, 20.0, 8.0) == pytest.approx(10.0)
    assert hermite(1.0, 10.0, 20.0, 8.0) == pytest.approx(20.0)
    # t = 1/2: h00 = h01 = 1/2, h10 = 1/8.
    assert hermite(0.5, 10.0, 20.0, 8.0) == pytest.approx(15.0 + 1.0)
    # t = 1/4: h00 = 0.84375, h01 = 0.15625, h10 = 0.140625.
    assert hermite(0.25, 10.0, 20.0, 8.0) == pytest.approx(8.4375 + 3.125 + 1.125)


def test_hermite_slope_ends():
    for g in (-30.0, 0.0, 12.5):
        assert hermite_slope(0.0, 10.0, 20.0, g) == pytest.approx(g)
        # No end-tangent term in the curve: every transition arrives at rest.
        assert hermite_slope(1.0, 10.0, 20.0, g) == pytest.approx(0.0)
    assert hermite_slope(0.5, 10.0, 20.0, 0.0) == pytest.approx(15.0)  # 1.5 * (a_e - a_s)


def test_hermite_slope_is_the_derivative():
    t = np.linspace(0.01, 0.99, 50)
    h = 1e-6
    a_s, a_e, g = profile("AA"), profile("ou"), np.linspace(-100, 100, N_FAPS)
    numeric = (hermite(t + h, a_s, a_e, g) - hermite(t - h, a_s, a_e, g)) / (2 * h)
    np.testing.assert_allclose(hermite_slope(t, a_s, a_e, g), numeric, atol=1e-4)


def test_hermite_shapes():
    t = np.linspace(0, 1, 7)
    assert hermite(t, 0.0, 1.0).shape == (7,)
    out = hermite(t, profile("PP"), profile("AA"), 0.0)
    assert out.shape == (7, N_FAPS)
    np.testing.assert_allclose(out[0], profile("PP"))
    np.testing.assert_allclose(out[-1], profile("AA"))
    assert hermite_slope(t, profile("PP"), 0.0, 0.0).shape == (7, N_FAPS)


# ---- visemes ---------------------------------------------------------------------------------------

SPEECH = [VisemeSpan("PP", 0.10, 0.18), VisemeSpan("AA", 0.18, 0.35), VisemeSpan("ih", 0.35, 0.41),
          VisemeSpan("ou", 0.41, 0.60), VisemeSpan("FF", 0.90, 1.00), VisemeSpan("E", 1.00, 1.30)]
# The moves of SPEECH by the rule (LEAD 0.1, LAG 0.03, shares 0.7 / 0.2, closure hold 0.04), worked by hand:
# (start, end, from, to). PP is a closure: shut at its onset 0.10 and held to 0.14, which delays the move
# into AA (nominally 0.18 - 0.7 * 0.08 = 0.124) to 0.14; AA is reached at 0.18 + min(0.03, 0.2 * 0.17).
MOVES = [(0.00, 0.10, "none", "PP"), (0.14, 0.21, "PP", "AA"), (0.25, 0.362, "AA", "ih"),
         (0.368, 0.44, "ih", "ou"), (0.50, 0.63, "ou", "none"), (0.80, 0.92, "none", "FF"),
         (0.93, 1.03, "FF", "E"), (1.20, 1.33, "E", "none")]


def test_viseme_rest_before_and_after():
    out = viseme_track(SPEECH, np.array([-1.0, 0.0, 0.05, 0.63, 0.75, 0.80, 1.33, 5.0]))
    assert out.shape == (8, N_FAPS)
    assert not out[:2].any()  # at rest until the move into the first span starts, LEAD before it
    assert out[2].any()  # on the way to PP before PP's onset: anticipation
    assert not out[3:6].any()  # closed by 0.63, at rest until the move into FF starts
    assert not out[6:].any()


def test_viseme_moves_cross_the_onsets():
    """Each move starts before its span's onset and ends at most LAG after it (closures at it), then holds."""
    for start, end, source, target in MOVES:
        out = viseme_track(SPEECH, np.array([start, end, end + 0.005]))
        np.testing.assert_allclose(out[0], profile(source), atol=1e-6, err_msg=f"{source}->{target}")
        np.testing.assert_allclose(out[1], profile(target), atol=1e-6, err_msg=f"{source}->{target}")
        np.testing.assert_allclose(out[2], profile(target), atol=1e-6, err_msg=f"{source}->{target} holds")
    for span in SPEECH:
        reach = span.start if span.viseme == "PP" else span.start + min(LAG, LAG_SHARE * (span.end - span.start))
        assert reach <= (span.start + span.end) / 2  # every shape is reached in the first half of its span
    assert not out[:, :2].any()  # FAP 1 and 2 are never set by low-level tracks


def test_viseme_closure_is_shut_from_its_onset_for_the_hold():
    spans = [VisemeSpan("AA", 0.0, 0.2), VisemeSpan("PP", 0.2, 0.22), VisemeSpan("AA", 0.22, 0.4)]
    t = np.array([0.19, 0.2, 0.239, 0.25])
    out = viseme_track(spans, t)
    assert not np.allclose(out[0], profile("PP"))  # still closing before the onset
    np.testing.assert_allclose(out[1:3], np.stack([profile("PP")] * 2), atol=1e-6)  # shut 0.20-0.24
    np.testing.assert_allclose(out[3], profile("AA"), atol=1e-6)  # opened fast: 0.24-0.25 (MIN_MOVE)
    longer = viseme_track(spans, t, closure_hold=0.06)
    np.testing.assert_allclose(longer[3], profile("PP"), atol=1e-6)
    none = viseme_track(spans, t, closure_hold=0.0)  # the move to AA starts at 0.22 - 0.7 * 0.02
    assert not np.allclose(none[2], profile("PP"))
    with pytest.raises(ValueError, match="closure_hold"):
        viseme_track(spans, t, closure_hold=-0.01)


def test_viseme_interpolates_by_hermite():
    start, end = MOVES[2][:2]
    t = np.linspace(start, end, 9, endpoint=False)
    u = (t - start) / (end - start)
    np.testing.assert_allclose(viseme_track(SPEECH, t), hermite(u, profile("AA"), profile("ih")), atol=1e-9)


def test_viseme_joins_are_continuous_in_value_and_slope():
    track = lambda t: viseme_track(SPEECH, t)  # noqa: E731
    joins = sorted({x for move in MOVES for x in move[:2]})
    for step in (1e-3, 1e-4):
        for join in joins:
            around = track(np.array([join - step, join + step]))
            # the fastest move (~1.5 * 850 / 0.07 per second) bounds the jump over 2 steps
            assert np.abs(around[1] - around[0]).max() < 3e4 * step, join
    for join in joins:
        before, after = slopes_around(track, join)
        np.testing.assert_allclose(before, after, atol=0.5, err_msg=str(join))


def test_viseme_dense_sampling_has_no_jumps():
    t = np.arange(0.0, 1.5, 1e-4)
    out = viseme_track(SPEECH, t)
    assert np.abs(np.diff(out, axis=0)).max() < 3.0  # per 0.1 ms, against profiles of ~800


def test_viseme_gap_shorter_than_rest_time():
    """AA, a 50 ms pause, PP: the mouth closes to rest across AA's end and closes the lips into PP
    from rest (the pause shared 0.2 / 0.7 between the two moves)."""
    spans = [VisemeSpan("AA", 0.0, 0.2), VisemeSpan("PP", 0.25, 0.4)]
    out = viseme_track(spans, np.array([0.1, 0.155, 0.21, 0.215, 0.25, 0.29]), rest_time=0.15)
    np.testing.assert_allclose(out[0], profile("AA"))  # the closing move starts LEAD before the end
    np.testing.assert_allclose(out[1], profile("AA") / 2)  # halfway through it (0.10-0.21)
    assert not out[2].any() and not out[3].any()  # at rest, 0.21-0.215
    np.testing.assert_allclose(out[4:], np.stack([profile("PP")] * 2), atol=1e-6)  # shut at the onset


def test_viseme_rest_time_bounds_the_closing_move():
    spans = [VisemeSpan("AA", 0.0, 0.2)]
    out = viseme_track(spans, np.array([0.2 - 1e-12, 0.2]), rest_time=0.0)  # a step at the end
    np.testing.assert_allclose(out[0], profile("AA"), atol=1e-6)
    assert not out[1].any()
    # rest_time 0.065: the move (nominally 0.10 before and 0.03 after the end) is halved, 0.15-0.215
    out = viseme_track(spans, np.array([0.15, 0.215]), rest_time=0.065)
    np.testing.assert_allclose(out[0], profile("AA"), atol=1e-6)
    assert np.abs(out[1]).max() < 1e-6


def test_viseme_tangent_parameter():
    spans = [VisemeSpan("AA", 0.0, 0.2), VisemeSpan("ou", 0.2, 0.5)]  # the move to ou: 0.10-0.23
    track = lambda t: viseme_track(spans, t, tangent=1.5)  # noqa: E731
    _, after = slopes_around(track, 0.1)
    expected = 1.5 * (profile("ou") - profile("AA")) / 0.13
    np.testing.assert_allclose(after, expected, rtol=1e-3, atol=1e-2)
    before, _ = slopes_around(track, 0.23)
    np.testing.assert_allclose(before, 0.0, atol=1e-2)  # arrives at rest whatever the tangent
    with pytest.raises(ValueError, match="tangent"):
        viseme_track(spans, [0.1], tangent=3.5)


def test_viseme_order_and_sets():
    t = frame_times(1.4, 100.0)
    np.testing.assert_array_equal(viseme_track(SPEECH[::-1], t), viseme_track(SPEECH, t))
    zh = [VisemeSpan("bpm", 0.0, 0.1, "zh"), VisemeSpan("a", 0.1, 0.3, "zh")]
    out = viseme_track(zh, [0.0, 0.13, 0.2])
    np.testing.assert_allclose(out[0], profile("bpm", "zh"), atol=1e-6)  # a Chinese closure too: shut at onset
    np.testing.assert_allclose(out[1:], np.stack([profile("a", "zh")] * 2), atol=1e-6)  # reached at 0.1 + 0.03
    assert not viseme_track([], t).any()


def test_viseme_fields_follow_the_same_moves():
    """FAP 1 (select1 x blend/63 + select2 x (1 - blend/63)) is the low-level track up to blend rounding."""
    t = frame_times(1.4, 100.0)
    fields = viseme_fields(SPEECH, t)
    w = fields.blend[:, None] / 63.0
    first = np.stack([VISEME_PROFILES[s][v] for s, v in fields.select1]).astype(np.float64)
    second = np.stack([VISEME_PROFILES[s][v] for s, v in fields.select2]).astype(np.float64)
    track = viseme_track(SPEECH, t)
    step = np.abs(first - second).max(axis=1) / 63.0 / 2 + 1e-9  # half a blend step
    assert (np.abs(first * w + second * (1 - w) - track).max(axis=1) <= step).all()
    assert fields.select1[int(0.3 * 100)] == ("mpeg4", "ih") and fields.select2[int(0.3 * 100)] == ("mpeg4", "AA")
    hold = viseme_fields(SPEECH, [0.12], closure_hold=0.0)  # no hold: PP -> AA starts at 0.124
    assert viseme_fields(SPEECH, [0.139]).select1 == [("mpeg4", "PP")] and hold.select1 == [("mpeg4", "PP")]
    assert viseme_fields(SPEECH, [0.13], closure_hold=0.0).select1 == [("mpeg4", "AA")]


@pytest.mark.parametrize("spans, match", [
    ([VisemeSpan("AA", 0.2, 0.2)], "before end"),
    ([VisemeSpan("AA", 0.3, 0.2)], "before end"),
    ([VisemeSpan("AA", 0.0, 0.3), VisemeSpan("PP", 0.2, 0.4)], "overlap"),
    ([VisemeSpan("XX", 0.0, 0.3)], "not a viseme"),
    ([VisemeSpan("AA", 0.0, 0.3, "klingon")], "unknown viseme set"),
    ([VisemeSpan("AA", 0.0, float("nan"))], "not finite"),
])
def test_viseme_bad_spans(spans, match):
    with pytest.raises(ValueError, match=match):
        viseme_track(spans, [0.0])


def test_viseme_bad_times():
    with pytest.raises(ValueError, match="one-dimensional"):
        viseme_track(SPEECH, np.zeros((2, 2)))


@st.composite
def span_sequences(draw):
    set_name = draw(st.sampled_from(["mpeg4", "zh"]))
    names = [name for name in VISEME_PROFILES[set_name]]
    n = draw(st.integers(1, 8))
    spans, start = [], draw(st.floats(0.0, 0.5))
    for _ in range(n):
        length = draw(st.floats(0.01, 0.4))
        spans.append(VisemeSpan(draw(st.sampled_from(names)), start, start + length, set_name))
        start += length + draw(st.sampled_from([0.0, 0.0, 0.05, 0.3]))
    return spans


@PROPERTY
@given(span_sequences(), st.floats(0.0, 3.0), st.floats(0.0, 0.3))
def test_viseme_values_stay_between_the_profiles(spans, tangent, rest_time):
    t = np.linspace(-0.2, spans[-1].end + 0.5, 600)
    involved = np.stack([profile(s.viseme, s.set) for s in spans] + [np.zeros(N_FAPS)])
    out = viseme_track(spans, t, tangent=tangent, rest_time=rest_time)
    assert (out >= involved.min(axis=0) - 1e-9).all()
    assert (out <= involved.max(axis=0) + 1e-9).all()


@PROPERTY
@given(span_sequences())
def test_viseme_tracks_are_continuous(spans):
    t = np.linspace(-0.2, spans[-1].end + 0.4, 4000)
    step = t[1] - t[0]
    out = viseme_track(spans, t)
    gaps = [b.start - a.end for a, b in zip(spans, spans[1:]) if b.start > a.end]
    shortest = min([s.end - s.start for s in spans] + gaps)
    # every move lasts at least min(MIN_MOVE, LEAD_SHARE * shortest phase); Hermite with g = 0
    # moves at most 1.5 * (a_e - a_s) per move length
    move = min(MIN_MOVE, LEAD_SHARE * shortest)
    bound = 1.5 * 2 * np.abs(np.stack([profile(s.viseme, s.set) for s in spans])).max() / move
    assert np.abs(np.diff(out, axis=0)).max() <= bound * step + 1e-9


@PROPERTY
@given(span_sequences())
def test_viseme_shapes_are_reached_early_in_their_spans(spans):
    """Each span's shape is on by its onset + min(LAG, LAG_SHARE x length) (closures: by the onset),
    unless a closure's hold delayed its move (each move after a hold can end at most MIN_MOVE later
    than the one before); and the first move starts LEAD before the first onset, not earlier."""
    closures = [(i, s.start) for i, s in enumerate(spans) if (s.set, s.viseme) in CLOSURES]
    for k, span in enumerate(spans):
        delayed = any(i < k and start + CLOSURE_HOLD + 2 * (k - i) * MIN_MOVE > span.start for i, start in closures)
        closure = (span.set, span.viseme) in CLOSURES
        reach = span.start + (0.0 if closure else min(LAG, LAG_SHARE * (span.end - span.start)))
        assert reach <= (span.start + span.end) / 2
        if not delayed:
            np.testing.assert_allclose(viseme_track(spans, [reach])[0], profile(span.viseme, span.set), atol=1e-6)
    first = spans[0]
    assert not viseme_track(spans, [first.start - LEAD - 1e-9]).any()
    if first.viseme != "none":
        assert viseme_track(spans, [first.start - LEAD + 1e-3]).any()


# ---- expressions -----------------------------------------------------------------------------------

def test_expression_case_1_first_cue_starts_from_rest():
    cues = [ExpressionCue("joy", 50, 0.4, 1.0)]
    t = np.linspace(0.0, 2.0, 41)
    u = np.clip((t - 1.0) / 0.4, 0.0, 1.0)
    np.testing.assert_allclose(intensity_of(cues, t, "joy"), np.where(t < 1.0, 0.0, hermite(u, 0.0, 50.0)))
    before, after = slopes_around(lambda x: intensity_of(cues, x, "joy"), 1.0)
    assert before == 0.0 and after == pytest.approx(0.0, abs=1e-3)


def test_expression_case_2_finished_transition_starts_at_rest():
    cues = [ExpressionCue("joy", 50, 0.4, 0.0), ExpressionCue("joy", 20, 0.5, 1.0)]
    t = np.linspace(1.0, 1.5, 11)
    np.testing.assert_allclose(intensity_of(cues, t, "joy"), hermite((t - 1.0) / 0.5, 50.0, 20.0))
    assert intensity_of(cues, [0.7], "joy")[0] == pytest.approx(50.0)


@pytest.mark.parametrize("first, second", [
    (ExpressionCue("joy", 60, 1.0, 0.0), ExpressionCue("joy", 10, 0.3, 0.45)),  # re-tagged, short
    (ExpressionCue("joy", 60, 0.4, 0.0), ExpressionCue("joy", 30, 2.0, 0.1)),  # re-tagged, long
    (ExpressionCue("anger", 63, 0.8, 0.0), ExpressionCue("fear", 40, 0.5, 0.5)),  # another expression
])
def test_expression_case_3_interrupted_transition_is_c1(first, second):
    cues = [first, second]
    at = second.start
    for name in {first.expression, second.expression}:
        f = lambda x, name=name: intensity_of(cues, x, name)  # noqa: E731
        before, after = slopes_around(f, at)
        assert after == pytest.approx(before, abs=0.05), name
        assert f([at + 1e-9])[0] == pytest.approx(f([at - 1e-9])[0], abs=1e-5)
    if first.expression == second.expression:
        assert before != pytest.approx(0.0, abs=1.0)  # it really was moving


def test_expression_case_3_tangent_is_rescaled_to_the_new_duration():
    cues = [ExpressionCue("joy", 60, 1.0, 0.0), ExpressionCue("joy", 10, 0.3, 0.45)]
    u_old = 0.45
    value = float(hermite(u_old, 0.0, 60.0))
    g_new = float(hermite_slope(u_old, 0.0, 60.0)) / 1.0 * 0.3  # per old time -> per second -> per new time
    t = np.linspace(0.45, 0.75, 7)
    expected = np.clip(hermite((t - 0.45) / 0.3, value, 10.0, g_new), 0, 63)
    np.testing.assert_allclose(intensity_of(cues, t, "joy"), expected, atol=1e-9)


def test_expression_cross_fade_between_expressions():
    cues = [ExpressionCue("joy", 63, 0.3, 0.0), ExpressionCue("sadness", 42, 0.5, 1.0)]
    names, levels = expression_intensities(cues, np.array([0.5, 1.25, 1.6]))
    joy, sad = names.index("joy"), names.index("sadness")
    assert levels[0, joy] == 63 and levels[0, sad] == 0
    assert 0 < levels[1, joy] < 63 and 0 < levels[1, sad] < 42  # both moving
    assert levels[1, joy] == pytest.approx(63 / 2) and levels[1, sad] == pytest.approx(21)
    assert levels[2, joy] == 0 and levels[2, sad] == 42
    mid = expression_track(cues, np.array([1.25]))[0]
    np.testing.assert_allclose(mid, EXPRESSION_PROFILES["joy"] * 0.5 + EXPRESSION_PROFILES["sadness"] / 3)


def test_expression_track_matches_expression_blend():
    cues = [ExpressionCue("anger", 63, 0.2, 0.0), ExpressionCue("surprise", 21, 1.0, 0.5)]
    names, levels = expression_intensities(cues, np.array([1.0]))  # anger fading, surprise rising
    a, s = levels[0, names.index("anger")], levels[0, names.index("surprise")]
    blend_at_ints = expression_blend("anger", 63, "surprise", 21)
    np.testing.assert_allclose(expression_track(cues, np.array([0.4]))[0], EXPRESSION_PROFILES["anger"])
    np.testing.assert_allclose(expression_track(cues, np.array([2.0]))[0], EXPRESSION_PROFILES["surprise"] / 3)
    np.testing.assert_allclose(expression_track(cues, np.array([1.0]))[0],
                               (EXPRESSION_PROFILES["anger"] * a + EXPRESSION_PROFILES["surprise"] * s) / 63)
    assert blend_at_ints.shape == (N_FAPS,)


@pytest.mark.parametrize("reset", [ExpressionCue("joy", 0, 0.3, 1.0), ExpressionCue("fear", 0, 0.3, 1.0),
                                   ExpressionCue("neutral", 63, 0.3, 1.0)])
def test_expression_intensity_zero_resets(reset):
    cues = [ExpressionCue("joy", 40, 0.2, 0.0), ExpressionCue("sadness", 30, 0.6, 0.7), reset]
    t = np.array([1.3, 1.31, 3.0])
    assert not expression_track(cues, t).any()
    assert expression_track(cues, np.array([1.1])).any()


def test_expression_step_with_zero_seconds():
    cues = [ExpressionCue("joy", 30, 0.0, 0.5), ExpressionCue("joy", 50, 0.0, 1.0)]
    values = intensity_of(cues, [0.5 - 1e-9, 0.5, 0.7, 1.0 - 1e-9, 1.0, 9.0], "joy")
    np.testing.assert_array_equal(values, [0, 30, 30, 30, 50, 50])
    # A transition after a step starts at rest from the stepped value.
    cues.append(ExpressionCue("joy", 10, 0.4, 2.0))
    before, after = slopes_around(lambda x: intensity_of(cues, x, "joy"), 2.0)
    assert before == 0.0 and after == pytest.approx(0.0, abs=1e-3)


def test_expression_step_interrupting_a_transition():
    cues = [ExpressionCue("joy", 60, 1.0, 0.0), ExpressionCue("disgust", 20, 0.0, 0.5)]
    names, levels = expression_intensities(cues, np.array([0.5, 0.6]))
    assert levels[0, names.index("joy")] == 0 and levels[0, names.index("disgust")] == 20
    assert levels[1, names.index("joy")] == 0


def test_expression_cues_at_one_instant_apply_in_order():
    cues = [ExpressionCue("joy", 60, 0.5, 1.0), ExpressionCue("anger", 30, 0.5, 1.0)]
    names, levels = expression_intensities(cues, np.array([1.0, 1.25, 2.0]))
    assert not levels[:, names.index("joy")].any()
    assert levels[2, names.index("anger")] == 30


def test_expression_fields():
    cues = [ExpressionCue("joy", 63, 0.3, 0.0), ExpressionCue("sadness", 42, 0.5, 1.0)]
    fields = expression_fields(cues, np.array([-1.0, 0.5, 1.25, 1.6]))
    assert list(fields.select1) == ["neutral", "joy", "joy", "sadness"]
    assert list(fields.intensity1) == [0, 63, 32, 42]
    assert list(fields.select2) == ["neutral", "neutral", "sadness", "neutral"]
    assert list(fields.intensity2) == [0, 0, 21, 0]
    assert fields.intensity1.dtype.kind == "i"


@pytest.mark.parametrize("cue, match", [
    (ExpressionCue("glee", 10, 0.1, 0.0), "unknown expression"),
    (ExpressionCue("joy", 64, 0.1, 0.0), "intensity"),
    (ExpressionCue("joy", -1, 0.1, 0.0), "intensity"),
    (ExpressionCue("joy", 1.5, 0.1, 0.0), "intensity"),  # type: ignore[arg-type]
    (ExpressionCue("joy", True, 0.1, 0.0), "intensity"),
    (ExpressionCue("joy", 10, -0.1, 0.0), "seconds"),
    (ExpressionCue("joy", 10, 0.1, float("inf")), "not finite"),
])
def test_expression_bad_cues(cue, match):
    with pytest.raises(ValueError, match=match):
        expression_track([cue], [0.0])


cue_lists = st.lists(st.builds(
    ExpressionCue, st.sampled_from(list(EXPRESSION_PROFILES)), st.integers(0, 63),
    st.sampled_from([0.0, 0.05, 0.3, 1.0, 3.0]), st.floats(0.0, 4.0)), max_size=8)


@PROPERTY
@given(cue_lists)
def test_expression_intensities_stay_in_range_and_settle(cues):
    t = np.linspace(-0.5, 9.0, 800)
    names, levels = expression_intensities(cues, t)
    assert levels.shape == (800, len(names)) and "neutral" not in names
    assert (levels >= 0).all() and (levels <= 63).all()
    if cues:
        last = sorted(cues, key=lambda c: c.start)[-1]
        final = dict(zip(names, levels[-1]))
        for name, value in final.items():
            want = last.intensity if name == last.expression else 0
            assert value == pytest.approx(want, abs=1e-9)
    fields = expression_fields(cues, t)
    assert (fields.intensity1 >= fields.intensity2).all()
    assert ((fields.select1 == "neutral") == (fields.intensity1 == 0)).all()


# ---- merging ---------------------------------------------------------------------------------------

def test_merge_by_maximum_per_direction():
    v = np.array([[100.0, -100.0, 30.0, -30.0, 0.0, 50.0, -80.0]])
    e = np.array([[40.0, -40.0, 90.0, -90.0, -70.0, -20.0, 30.0]])
    # same sign: larger magnitude with its sign; opposite signs: they cancel in part.
    np.testing.assert_allclose(merge_tracks(v, e), [[100, -100, 90, -90, -70, 30, -50]])
    np.testing.assert_allclose(merge_tracks(e, v), merge_tracks(v, e))


def test_merge_shapes_and_many_tracks():
    rng = np.random.default_rng(3)
    a, b, c = (rng.normal(0, 100, (5, N_FAPS)) for _ in range(3))
    out = merge_tracks(a, b, c)
    assert out.shape == (5, N_FAPS)
    np.testing.assert_allclose(out, merge_tracks(c, a, b))
    np.testing.assert_allclose(out, np.maximum(np.maximum(a, b), np.maximum(c, 0))
                               + np.minimum(np.minimum(a, b), np.minimum(c, 0)))
    np.testing.assert_allclose(merge_tracks(a, np.zeros_like(a)), a)


finite = st.floats(-1e4, 1e4)


@PROPERTY
@given(finite, finite, finite, finite)
def test_merge_is_continuous(a, b, da, db):
    # Lipschitz 1 in each track, so no jump where opposite values cross in size.
    m0 = merge_tracks(np.array([a]), np.array([b]))[0]
    m1 = merge_tracks(np.array([a + da * 1e-3]), np.array([b + db * 1e-3]))[0]
    assert abs(m1 - m0) <= (abs(da) + abs(db)) * 1e-3 + 1e-9
    assert min(a, b, 0) - 1e-9 <= m0 <= max(a, b, 0) + 1e-9


# ---- idle ------------------------------------------------------------------------------------------

BLINK, HEAD = [18, 19], [47, 48, 49]


def test_idle_is_deterministic_and_seeded():
    t = frame_times(30.0)
    first = idle_track(t, seed=7)
    np.testing.assert_array_equal(first, idle_track(t, seed=7))
    assert not np.array_equal(first, idle_track(t, seed=8))
    # Sampling does not change the motion: a subset of frames sees the same values.
    np.testing.assert_array_equal(idle_track(t[:100], seed=7), first[:100])
    others = np.delete(np.arange(N_FAPS), BLINK + HEAD)
    assert not first[:, others].any()


def test_idle_blinks():
    t = frame_times(60.0, 1000.0)
    lids = idle_track(t, seed=1, head=False)
    assert not lids[:, HEAD].any()
    np.testing.assert_array_equal(lids[:, 18], lids[:, 19])
    assert lids.min() >= 0 and lids.max() == pytest.approx(1024)
    shut = lids[:, 18] > 0
    starts = t[1:][shut[1:] & ~shut[:-1]]
    ends = t[1:][~shut[1:] & shut[:-1]]
    assert 60 / 6 - 1 <= len(starts) <= 60 / 2
    assert (np.diff(starts) >= 2.0 - 1e-9).all() and (np.diff(starts) <= 6.0 + 1e-9).all()
    np.testing.assert_allclose(ends - starts[: len(ends)], 0.15, atol=2e-3)
    # At 25 fps every blink shows at least one frame with the lid shut.
    frames = frame_times(60.0)
    lids25 = idle_track(frames, seed=1, head=False)[:, 18]
    for s in starts:
        inside = (frames >= s) & (frames < s + 0.15)
        assert lids25[inside].max() == pytest.approx(1024)


def test_idle_head_motion():
    t = frame_times(120.0)
    head = idle_track(t, seed=5, blinks=False)
    assert not head[:, BLINK].any()
    limits = np.radians([1.5, 2.5, 1.0]) * 1e5
    assert (np.abs(head[:, HEAD]) <= limits + 1e-6).all()
    assert (np.abs(head[:, HEAD]).max(axis=0) > 0.3 * limits).all()  # it does move
    assert not head[0].any()  # starts at the neutral pose
    # Smooth and slow: at most ~2*pi*0.3 Hz * amplitude per second.
    assert (np.abs(np.diff(head[:, HEAD], axis=0)).max(axis=0) <= 2 * np.pi * 0.3 * limits / 25 + 1e-6).all()
    np.testing.assert_array_equal(head[:, HEAD], idle_track(t, seed=5)[:, HEAD])


def test_idle_off_and_bad_arguments():
    t = frame_times(5.0)
    assert not idle_track(t, seed=0, blinks=False, head=False).any()
    with pytest.raises(ValueError, match="seed"):
        idle_track(t, seed=1.5)  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="blink_seconds"):
        idle_track(t, seed=0, blink_seconds=3.0)


# ---- frames ----------------------------------------------------------------------------------------

@pytest.mark.parametrize("duration, fps, n", [(1.0, 25.0, 25), (0.28, 25.0, 7), (0.281, 25.0, 8),
                                              (0.0, 25.0, 1), (2.0, 30.0, 60), (1.0, 29.97, 30)])
def test_frame_times(duration, fps, n):
    t = frame_times(duration, fps)
    assert len(t) == n
    np.testing.assert_array_equal(t, np.arange(n) / fps)
    assert len(t) / fps >= duration - 1e-9


@pytest.mark.parametrize("duration, fps", [(-1.0, 25.0), (1.0, 0.0), (float("nan"), 25.0)])
def test_frame_times_bad(duration, fps):
    with pytest.raises(ValueError):
        frame_times(duration, fps)
