"""The tracker's parts on data they make themselves: One Euro filter, rigid head pose, FAP rules, neutral choice."""
from __future__ import annotations

import numpy as np
import pytest

from mpeg4fa.face.motion import head_rotation
from mpeg4fa.spec import ANGLE_UNIT
from mpeg4fa.tracking import faps as rules
from mpeg4fa.tracking.filters import OneEuroFilter, filter_all, step_delay
from mpeg4fa.tracking.neutral import calmest_neutral
from mpeg4fa.tracking.pose import fit_similarity, rotation_angles
from mpeg4fa.tracking.tracker import BETA, MIN_CUTOFF, fap_stream, filter_scale


def test_one_euro_smooths_still_noise_and_follows_a_step_within_two_frames():
    rng = np.random.default_rng(0)
    filt = OneEuroFilter(25, MIN_CUTOFF, BETA, scale=64.0)
    still = filter_all(rng.normal(0, 8, (200, 1)), filt)
    assert still[50:].std() < 0.5 * 8  # jitter of a still face more than halved
    delay = step_delay(OneEuroFilter(25, MIN_CUTOFF, BETA, scale=64.0), size=300.0)
    assert delay["frames_50"] <= 1 and delay["frames_90"] <= 3, delay
    held = OneEuroFilter(25)
    held(np.array([1.0, 2.0]))
    assert np.allclose(held(np.array([np.nan, 2.0])), [1.0, 2.0])  # a lost value holds



@pytest.mark.parametrize("peak", [500.0, 1000.0])  # a blink as tracked (the lids read at 0.5-0.8 of it) and as sent
def test_a_blink_passes_the_lid_filter_within_a_frame_and_nearly_whole(peak):
    """Issue 27: blinks found within a frame; the lids' smoothing must not delay or flatten a 5-frame blink."""
    shape = np.array([0.35, 0.85, 1.0, 0.7, 0.3])  # tools/track_loop.py's blink at 25 fps
    rng = np.random.default_rng(1)
    signal = np.zeros((60, 68))
    signal[30:35, 18] = peak * shape
    signal[:, 18] += rng.normal(0, 15, 60)  # the landmark model's jitter on a lid, FAPU
    raw = signal[:, 18]
    out = filter_all(signal, OneEuroFilter(25, MIN_CUTOFF, BETA, scale=filter_scale()))[:, 18]
    assert abs(int(np.argmax(out)) - int(np.argmax(raw))) <= 1
    assert out.max() >= 0.9 * raw.max(), (out.max(), raw.max())

def test_rigid_fit_recovers_scale_rotation_and_the_angles_the_head_uses():
    rng = np.random.default_rng(1)
    neutral = rng.normal(size=(30, 3))
    rotation = head_rotation(0.2, -0.45, 0.1)
    moved = 1.3 * neutral @ rotation.T + [4.0, -2.0, 1.0]
    pose = fit_similarity(neutral, moved)
    assert pose.scale == pytest.approx(1.3)
    assert np.allclose(pose.angles(), (0.2, -0.45, 0.1))
    assert np.allclose(pose.to_neutral(moved), neutral)
    assert np.allclose(rotation_angles(np.eye(3)), 0)


def _face(jaw: float = 0.0, corner_up: float = 0.0, brow: float = 0.0) -> np.ndarray:
    """A made-up neutral face (MPEG-4 axes, pixels) with FAPU that measure, moved by a few FAPs' worth."""
    p = np.zeros((len(rules.LABELS), 3))
    rng = np.random.default_rng(2)
    p[:, :2] = rng.uniform(-40, 40, (len(p), 2))
    put = {"3.5": (30, 40), "3.6": (-30, 40), "3.1": (30, 45), "3.3": (30, 36), "3.2": (-30, 45), "3.4": (-30, 36),
           "9.15": (0, 0), "2.2": (0, -15), "2.3": (0, -16), "8.3": (25, -18), "8.4": (-25, -18), "2.1": (0, -60),
           "2.4": (23, -17), "2.5": (-23, -17), "4.3": (32, 55)}
    for label, xy in put.items():
        p[rules.INDEX[label], :2] = xy
    p[rules.INDEX["2.1"], 1] -= jaw
    p[rules.INDEX["2.4"], 1] += corner_up
    p[rules.INDEX["4.3"], 1] += brow
    return p


def test_fap_values_are_displacements_along_the_direction_over_the_fapu():
    neutral = rules.Neutral.from_points(_face())
    geometry = rules.Receiver(jaw_carry=np.zeros(len(rules.LABELS)), eye_radius=0.2)
    moved = _face(jaw=3.0, corner_up=1.5, brow=2.0)
    values = rules.fap_values(moved[None], neutral, np.array([[0.1, -0.2, 0.05]]), geometry)[0]
    mns, ens = neutral.fapu.unit("MNS"), neutral.fapu.unit("ENS")
    assert values[2] == pytest.approx(3.0 / mns)      # FAP 3 open_jaw: 2.1 down
    assert values[11] == pytest.approx(1.5 / mns)     # FAP 12 raise_l_cornerlip: 2.4 up
    assert values[32] == pytest.approx(2.0 / ens)     # FAP 33 raise_l_m_eyebrow: 4.3 up
    assert np.allclose(values[47:50], np.array([0.1, -0.2, 0.05]) / ANGLE_UNIT)
    carried = rules.Receiver(jaw_carry=np.where(np.array(rules.LABELS) == "2.4", 0.5, 0.0), eye_radius=0.2)
    values = rules.fap_values(_face(jaw=3.0)[None], neutral, np.zeros((1, 3)), carried)[0]
    assert values[2] == pytest.approx(3.0 / mns)
    assert values[11] == pytest.approx(1.5 / mns)     # the corner stayed while the jaw would carry it 1.5 down


@pytest.mark.parametrize("sent", [{19: 1000, 20: 1000}, {21: 260, 22: 260}, {19: 500, 20: 500, 33: 200, 34: 200}])
def test_lids_read_back_as_sent_though_the_eye_corners_give(generic_face, sent):
    """The generic head's eye corners give a little as its lids close (mpeg4fa.face.lids.lid_corners). Read against
    those corners without the receiver's corner carry, a blink at 1000 read 848 and put 152 on the lower lids, 23 on
    the brows and a gaze of -9677 AU; with it, what was sent (1002, -2, 0, 145 AU)."""
    face = generic_face
    labels = list(face.mesh.fp_labels)
    index = [labels.index(label) for label in rules.LABELS]
    values = np.zeros(68)
    for fap, value in sent.items():
        values[fap - 1] = value
    points = face.pose_values(values).feature_points[index][None]
    neutral = rules.Neutral.from_points(face.neutral().feature_points[index])
    geometry = rules.receiver(face)
    assert np.all(geometry.corner_carry > 0.05)
    read = rules.fap_values(points, neutral, np.zeros((1, 3)), geometry)[0]
    for fap in (19, 20, 21, 22, 31, 32, 33, 34, 35, 36):
        assert read[fap - 1] == pytest.approx(values[fap - 1], abs=0.01 * 1000), fap
    assert np.abs(read[24:26]).max() < 300  # AU: 0.17 degrees of gaze (the carry is measured at 512, linear)
    plain = rules.Receiver(geometry.jaw_carry, geometry.eye_radius)
    still = rules.fap_values(points, neutral, np.zeros((1, 3)), plain)[0]
    assert np.abs(still[18:22] - values[18:22]).max() > 30  # the carry is what reads them right


def test_stream_sends_a_fixed_set_of_faps_in_every_frame():
    values = np.zeros((5, 68))
    values[:, 2] = [0, 10.4, 20.6, 30, 40]
    stream = fap_stream(values, 30.0)
    assert stream.fap_mask.sum(axis=1).tolist() == [len(rules.SENT)] * 5
    assert stream.fap_values[:, 2].tolist() == [0, 10, 21, 30, 40]
    assert stream.fps == 30.0 and filter_scale().shape == (68,)


def test_the_calmest_stretch_is_where_the_face_holds_still_with_the_mouth_shut():
    fps = 25
    rng = np.random.default_rng(3)
    base = _face()
    frames = np.repeat(base[None], 75, axis=0) + rng.normal(0, 0.8, (75, len(base), 3))
    frames[40:55] = base + rng.normal(0, 0.05, (15, len(base), 3))  # still from 1.6 s
    frames[60:70, rules.INDEX["2.3"], 1] -= 6                        # still but open-mouthed: not neutral
    frames[60:70] = frames[60] + rng.normal(0, 0.01, (10, len(base), 3))
    choice = calmest_neutral(frames, fps)
    assert 40 <= choice.first and choice.last < 55, (choice.first, choice.last)
    assert "calmest" in choice.describe(fps)


@pytest.mark.parametrize("fap_quant", [1, 3, 31])
def test_outliers_are_held_to_what_a_face_shows_and_a_stream_carries(fap_quant):
    from mpeg4fa.fba import EncodeOptions, decode, encode

    values = np.zeros((20, 68))
    values[:, 2] = np.linspace(-9000, 9000, 20)     # jaw: never negative, and within a range code
    values[:, 48] = np.linspace(-4e5, 4e5, 20)     # yaw beyond a half turn
    values[3, 18] = np.nan                          # a lost value
    decoded = decode(encode(fap_stream(values, 25.0), EncodeOptions(fap_quant=fap_quant)))
    assert decoded.fap_values[:, 2].min() == 0 and decoded.fap_values[:, 2].max() > 7000
    assert np.abs(decoded.fap_values[:, 48]).max() <= np.pi / ANGLE_UNIT + 2000
