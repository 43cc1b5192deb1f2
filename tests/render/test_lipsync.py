"""Lip sync measure (mpeg4fa.render.lipsync): energy, correlation and lag on synthetic data with known
answers, then the 16 real speech streams of ../shared/vectors/fba/en against their .wav files.

Run with ``pytest -s`` to see the per-stream figures.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.fba.stream import FapStream
from mpeg4fa.formats.sniff import read_stream
from mpeg4fa.render.audio import Audio, read_audio
from mpeg4fa.render.lipsync import (LipSyncReport, best_lag, lagged_correlations, lipsync_report,
                                    mouth_opening, pearson, speech_energy)

RATE = 16000
FPS = 25.0
VECTORS = Path(__file__).resolve().parents[2].parent / "shared" / "vectors"
EN = VECTORS / "fba" / "en"


def tone(seconds: float, amplitude: float, freq: float = 500.0) -> np.ndarray:
    t = np.arange(int(round(seconds * RATE))) / RATE
    return (amplitude * np.sin(2 * np.pi * freq * t)).astype(np.float32)


def audio_of(x: np.ndarray) -> Audio:
    return Audio(np.asarray(x, dtype=np.float32)[:, None], RATE)


# ---- speech_energy -----------------------------------------------------------------------------

def test_tone_burst_in_silence():
    """0.5 s of a 500 Hz tone between 1 s silences: its dB RMS inside, the floor outside, half power on the edge."""
    amp = 0.5
    x = np.concatenate([np.zeros(RATE), tone(0.5, amp), np.zeros(RATE)])
    audio = audio_of(x)
    expected = 20 * math.log10(amp / math.sqrt(2))  # -9.03 dBFS
    times = np.array([0.2, 0.9, 1.1, 1.25, 1.45, 1.6, 2.3])
    e = speech_energy(audio, times, 0.04)
    assert e[0] == e[1] == e[5] == e[6] == -60.0
    np.testing.assert_allclose(e[2:5], expected, atol=0.05)
    # a window centred on the onset holds half tone, half silence: 3 dB down
    on, off = speech_energy(audio, np.array([1.0, 1.5]), 0.04)
    assert on == pytest.approx(expected - 10 * math.log10(2), abs=0.05)
    assert off == pytest.approx(expected - 10 * math.log10(2), abs=0.05)
    lin = speech_energy(audio, times, 0.04, db=False)
    assert lin[0] == 0.0 and lin[3] == pytest.approx(amp / math.sqrt(2), rel=1e-3)


def test_windows_past_the_ends_use_the_part_inside():
    """A tone from the first to the last sample: windows cut by either end still read its full level;
    a window wholly outside reads the floor (dB) or 0 (linear)."""
    audio = audio_of(tone(1.0, 0.5))
    expected = 20 * math.log10(0.5 / math.sqrt(2))
    e = speech_energy(audio, np.array([0.0, 0.01, 0.99, 1.0]), 0.04)
    np.testing.assert_allclose(e, expected, atol=0.1)
    outside = np.array([-0.5, 1.2])
    assert list(speech_energy(audio, outside, 0.04)) == [-60.0, -60.0]
    assert list(speech_energy(audio, outside, 0.04, floor_db=-80.0)) == [-80.0, -80.0]
    assert list(speech_energy(audio, outside, 0.04, db=False)) == [0.0, 0.0]


def test_energy_matches_a_direct_computation():
    rng = np.random.default_rng(1)
    x = rng.normal(0, 0.1, 8000).astype(np.float32)
    x[3000:4000] *= 5
    audio = audio_of(x)
    times = rng.uniform(-0.05, 0.55, 50)
    got = speech_energy(audio, times, 0.025, db=False)
    size = int(round(0.025 * RATE))
    for t, g in zip(times, got):
        lo = int(round(t * RATE)) - size // 2
        part = x[max(lo, 0):max(min(lo + size, len(x)), 0)].astype(np.float64)
        want = math.sqrt((part ** 2).mean()) if len(part) else 0.0
        assert g == pytest.approx(want, rel=1e-6, abs=1e-12)


def test_energy_rejects_a_bad_window():
    with pytest.raises(ValueError):
        speech_energy(audio_of(np.zeros(100)), np.zeros(1), 0.0)


# ---- correlation and lag -----------------------------------------------------------------------

def test_pearson_and_lag_convention():
    rng = np.random.default_rng(2)
    e = rng.normal(size=200)
    assert pearson(e, 3 * e + 1) == pytest.approx(1.0)
    assert pearson(e, -e) == pytest.approx(-1.0)
    assert math.isnan(pearson(np.ones(10), e[:10]))
    # the mouth at frame k shows what the audio does at frame k + 3: the mouth leads, lag +3
    mouth = np.concatenate([e[3:], rng.normal(size=3)])
    r = lagged_correlations(mouth, e, 5)
    assert best_lag(r) == 3 and r[3 + 5] == pytest.approx(1.0)
    assert best_lag(lagged_correlations(e, mouth, 5)) == -3
    assert best_lag(np.full(11, np.nan)) == 0


def syllables(n: int, seed: int = 3) -> np.ndarray:
    """A loud/quiet pattern per frame in runs of 2-6 frames, like syllables and pauses."""
    rng = np.random.default_rng(seed)
    out, loud = [], False
    while len(out) < n:
        out += [loud] * int(rng.integers(2, 7))
        loud = not loud
    return np.array(out[:n])


def speech_for(loud: np.ndarray, extra_s: float = 0.0) -> Audio:
    """A 200 Hz tone whose level is loud or faint around each frame time (frame k's sound centred on k/fps)."""
    n = len(loud)
    total = int(round((n / FPS + extra_s) * RATE))
    t = np.arange(total) / RATE
    frame = np.clip(np.round(t * FPS).astype(int), 0, n - 1)
    level = np.where(loud[frame], 0.4, 0.004)
    level[t >= n / FPS] = 0.0
    return audio_of(level * np.sin(2 * np.pi * 200.0 * t))


def jaw_stream(jaw_open: np.ndarray) -> FapStream:
    """Only FAP 3 (open_jaw) sent, at every frame, 25 fps."""
    n = len(jaw_open)
    s = FapStream.empty(n)
    s.fap_mask[:, 2] = True
    s.fap_values[:, 2] = jaw_open
    s.timestamps[:] = np.arange(n) / FPS
    s.source_fps = FPS
    return s


def test_synthetic_stream_in_sync(procedural_face):
    loud = syllables(120)
    stream = jaw_stream(np.where(loud, 400, 0))
    rep = lipsync_report(procedural_face, stream, speech_for(loud), name="synthetic")
    print(f"\nsynthetic in sync: r={rep.correlation:.3f} best lag {rep.best_lag_frames:+d}")
    assert rep.correlation > 0.9
    assert rep.best_lag_frames == 0 and rep.best_correlation == rep.correlation
    assert rep.n_frames == rep.n_compared == 120 and rep.fps == FPS
    assert rep.stream_duration == pytest.approx(120 / FPS)


def test_synthetic_stream_mouth_three_frames_early(procedural_face):
    """The jaw opens 3 frames before the sound: best lag +3 (mouth leads), lag 0 much worse."""
    loud = syllables(123)
    jaw = np.where(loud[3:], 400, 0)             # jaw[k] follows loud[k + 3]
    stream = jaw_stream(jaw)
    rep = lipsync_report(procedural_face, stream, speech_for(loud[:120]))
    print(f"\nsynthetic, mouth 3 frames early: r0={rep.correlation:.3f} "
          f"best lag {rep.best_lag_frames:+d} r={rep.best_correlation:.3f}")
    assert rep.best_lag_frames == 3
    assert rep.best_correlation > 0.9
    assert rep.correlation < rep.best_correlation - 0.3


def test_opening_matches_animate(procedural_face):
    """The de-duplicated posing gives what animate() gives frame by frame."""
    rng = np.random.default_rng(4)
    stream = jaw_stream(rng.choice([0, 150, 400], size=40))
    stream.fap_mask[::3, 4] = True               # FAP 5 raise_b_midlip, sent every third frame (held between)
    stream.fap_values[::3, 4] = rng.integers(-200, 200, size=len(stream.fap_values[::3]))
    labels = list(procedural_face.mesh.fp_labels)
    up, low = labels.index("2.2"), labels.index("2.3")
    want = [p.feature_points[up, 1] - p.feature_points[low, 1] for p in procedural_face.animate(stream)]
    np.testing.assert_allclose(mouth_opening(procedural_face, stream), want, atol=1e-9)
    assert mouth_opening(procedural_face, FapStream.empty(0)).shape == (0,)


def test_short_audio_compares_only_frames_inside(procedural_face):
    loud = syllables(100)
    audio = speech_for(loud)
    cut = Audio(audio.samples[: int(3.0 * RATE)], RATE)  # 3 s of a 4 s stream
    rep = lipsync_report(procedural_face, jaw_stream(np.where(loud, 400, 0)), cut)
    assert rep.n_compared == 75 and rep.n_frames == 100
    assert rep.duration_mismatch == pytest.approx(-1.0)
    assert rep.correlation > 0.9


def test_skipped_frames_are_put_back_on_the_grid(procedural_face):
    """A stream that skips repeats (as the encoder's optimize does) reads like the same stream sent in
    full: lags count frame periods, not decoded frames."""
    loud = syllables(120)
    full = jaw_stream(np.where(loud[3:], 400, 0))  # the mouth 3 frames early
    keep = np.r_[True, np.diff(full.fap_values[:, 2]) != 0]
    sparse = full.take(list(np.flatnonzero(keep)))
    sparse.skip[:] = np.diff(np.r_[np.flatnonzero(keep), len(full)]) - 1
    audio = speech_for(loud[:117])
    a, b = lipsync_report(procedural_face, full, audio), lipsync_report(procedural_face, sparse, audio)
    assert len(sparse) < len(full) / 2 and b.n_frames == len(full)
    assert b.best_lag_frames == a.best_lag_frames == 3
    np.testing.assert_allclose(b.lag_correlations, a.lag_correlations)


def test_report_to_json():
    rep = LipSyncReport("x", 3, 25.0, 0.12, 0.2, float("nan"), 0, float("nan"),
                        lag_correlations=[float("nan"), 0.5])
    doc = json.loads(json.dumps(rep.to_dict()))
    assert doc["correlation"] is None and doc["lag_correlations"] == [None, 0.5]
    assert doc["duration_mismatch"] == pytest.approx(0.08)


# ---- the real streams ----------------------------------------------------------------------------

def en_pairs() -> list[tuple[Path, Path]]:
    if not EN.is_dir():
        pytest.skip(f"../shared/vectors not present: the speech streams and .wav files are read from {EN}")
    pairs = [(p, p.with_suffix(".wav")) for p in sorted(EN.iterdir())
             if p.suffix.lower() == ".fba" and p.with_suffix(".wav").is_file()]
    if not pairs:
        pytest.skip(f"no .fba + .wav pairs in {EN}")
    return pairs


@pytest.fixture(scope="module")
def en_reports(generic_face) -> list[LipSyncReport]:
    reports = []
    for stream_path, wav_path in en_pairs():
        stream, _ = read_stream(stream_path)
        reports.append(lipsync_report(generic_face, stream, read_audio(wav_path), name=stream_path.stem))
    print(f"\n{'stream':<25} {'frames':>6} {'stream s':>8} {'audio s':>7} {'r0':>7} {'lag':>4} {'r best':>7}")
    for r in reports:
        print(f"{r.name:<25} {r.n_frames:>6} {r.stream_duration:>8.2f} {r.audio_duration:>7.2f} "
              f"{r.correlation:>+7.3f} {r.best_lag_frames:>+4d} {r.best_correlation:>+7.3f}")
    print(f"{'mean':<25} {'':>6} {'':>8} {'':>7} {np.mean([r.correlation for r in reports]):>+7.3f} "
          f"{'':>4} {np.mean([r.best_correlation for r in reports]):>+7.3f}")
    return reports


def test_en_streams_are_measured(en_reports):
    assert len(en_reports) == 16
    for r in en_reports:
        assert r.fps == 25.0 and r.n_frames > 30
        assert 0 < r.n_compared <= r.n_frames
        assert all(math.isfinite(c) for c in r.lag_correlations), r.name
        assert -5 <= r.best_lag_frames <= 5
        assert r.best_correlation >= r.correlation
        # the speech and the stream it was made for are within half a second of each other
        assert abs(r.duration_mismatch) < 0.5, r.name


def test_en_mouth_follows_speech_on_average(en_reports):
    """Across the 16 streams r is positive at lag 0 and peaks with the mouth a frame or two ahead (the lips
    open before the voice starts); every stream correlates positively at its best lag.

    A weak check, on purpose: every clip opens on ~3 silent frames with the mouth neutral, and that onset
    carries most of r. Each stream's mouth against another clip's audio scores about the same (mean
    +0.09 at lag 0), so these figures show the measure works, not that each stream is in sync."""
    r0 = np.array([r.correlation for r in en_reports])
    curve = np.mean([r.lag_correlations for r in en_reports], axis=0)
    assert r0.mean() > 0.0
    assert 0 <= int(np.argmax(curve)) - 5 <= 2
    assert all(r.best_correlation > 0 for r in en_reports)


@pytest.mark.xfail(strict=True, reason="measured: 6 of the 16 en streams correlate negatively at lag 0 "
                                       "(car-unlock -0.15, restaurants-unlock -0.14, ...): frame-level "
                                       "energy is a weak proxy for viseme openness on these clips")
def test_every_en_stream_positive_at_lag0(en_reports):
    assert all(r.correlation > 0 for r in en_reports)
