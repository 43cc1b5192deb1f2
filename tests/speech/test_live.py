"""Live lip sync (mpeg4fa.speech.live): frames come out a fixed latency after the audio they describe, the
mouth moves while espeak-ng speaks and rests in the silences and in noise. Timing is counted in samples
and frames, never by the wall clock (tools/bench_live.py measures the real-time behaviour)."""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("pocketsphinx", reason="live lip sync needs pocketsphinx (the 'align' extra)")
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tools"))

import espeak_fresh  # noqa: E402

from mpeg4fa.spec import FAP_BY_NAME  # noqa: E402
from mpeg4fa.speech.align.recording import frame_levels, resample  # noqa: E402
from mpeg4fa.speech.live import LATENCY, LiveLipSync, Resampler, phone_parts  # noqa: E402

RATE = 16000
FPS = 25.0
LIPS = [FAP_BY_NAME[n].number - 1 for n in (
    "open_jaw", "lower_t_midlip", "raise_b_midlip", "stretch_l_cornerlip", "stretch_r_cornerlip",
    "lower_t_lip_lm", "lower_t_lip_rm", "raise_b_lip_lm", "raise_b_lip_rm", "push_b_lip", "push_t_lip")]
SENTENCES = ("Hello there, how are you?", "Maybe Bob will bring a map.")
PAUSE = 1.2


@pytest.fixture(scope="module")
def clip() -> tuple[np.ndarray, list[tuple[float, float]]]:
    """Two espeak-ng sentences with PAUSE s of silence before, between and after, at 16 kHz int16, and the
    spans (s) where the audio is louder than -45 dBFS (the speech, measured, not espeak-ng's events). Each
    sentence is spoken by a fresh process (tools/espeak_fresh.py): in this one espeak-ng's audio changes with what
    it spoke before, and in the whole suite's order one rendition (112527 samples) gave frames that differed
    between 20 ms and 4999-sample chunks, in two runs, where 76 renditions made here did not."""
    parts = [np.zeros(int(PAUSE * RATE))]
    for text in SENTENCES:
        speech = espeak_fresh.spoken(text, lang="en", rate=175).speech
        parts += [resample(speech.samples / 32768.0, speech.rate, RATE), np.zeros(int(PAUSE * RATE))]
    x = np.concatenate(parts)
    loud = frame_levels(x, RATE) > -45
    edges = np.flatnonzero(np.diff(np.r_[0, loud.astype(int), 0]))
    spans = [(a * 0.01, b * 0.01) for a, b in zip(edges[::2], edges[1::2])]
    merged = [list(spans[0])]
    for a, b in spans[1:]:  # gaps inside a sentence (stops) are speech
        if a - merged[-1][1] < 0.3:
            merged[-1][1] = b
        else:
            merged.append([a, b])
    return np.clip(np.rint(x * 32767), -32768, 32767).astype(np.int16), [tuple(s) for s in merged]


@pytest.fixture(scope="module")
def fed(clip):
    """The clip fed in 20 ms chunks."""
    return run(clip[0], 320)


def run(pcm: np.ndarray, chunk: int, rate: int = RATE, **kwargs) -> tuple[list[tuple[int, np.ndarray]], np.ndarray]:
    """Feed ``pcm`` ``chunk`` samples at a time: (samples fed, frames out) per feed, and flush()'s frames."""
    live = LiveLipSync(rate, FPS, **kwargs)
    out = []
    for i in range(0, len(pcm), chunk):
        part = pcm[i:i + chunk]
        out.append((min(i + chunk, len(pcm)), live.feed(part if i % 2 else part.astype("<i2").tobytes())))
    return out, live.flush()


def moving(frames: np.ndarray) -> np.ndarray:
    return np.abs(frames[:, LIPS]).max(axis=1) > 0


def test_every_frame_comes_out_exactly_latency_after_its_audio(clip, fed):
    pcm, _ = clip
    for chunk in (320, 137, 16000):  # 20 ms, an odd size, 1 s
        out, tail = fed if chunk == 320 else run(pcm, chunk)
        total = 0
        for fed, frames in out:
            total += len(frames)
            due = math.floor(round((fed / RATE - LATENCY) * FPS, 9)) + 1 if fed / RATE >= LATENCY else 0
            assert total == due, f"chunk {chunk}: after {fed} samples {total} frames, {due} due"
        assert total + len(tail) == math.ceil(len(pcm) / RATE * FPS)


def test_the_frames_do_not_depend_on_how_the_audio_is_cut(clip, fed):
    pcm, _ = clip
    a = np.concatenate([f for _, f in fed[0]] + [fed[1]])
    b_out, b_tail = run(pcm, 4999)
    b = np.concatenate([f for _, f in b_out] + [b_tail])
    assert a.shape == b.shape and np.array_equal(a, b)


def test_the_mouth_moves_within_200_ms_of_the_speech_and_rests_in_its_silences(clip, fed):
    pcm, speech = clip
    out, tail = fed
    frames = np.concatenate([f for _, f in out] + [tail])
    move = moving(frames)
    t = np.arange(len(frames)) / FPS
    for start, end in speech:
        # the feed after which a frame showing the mouth moving for this sentence first came out
        emitted, first_fed = 0, None
        for fed, f in out:
            k = np.flatnonzero(moving(f) & (np.arange(emitted, emitted + len(f)) / FPS > start - 0.3))
            emitted += len(f)
            if len(k):
                first_fed = fed
                break
        assert first_fed is not None
        delay = first_fed / RATE - start
        print(f"speech at {start:.2f} s: the mouth moved {delay * 1000:.0f} ms later")
        assert delay <= 0.200, f"the mouth first moved {delay * 1000:.0f} ms after the speech at {start:.2f} s"
        inside = (t >= start + 0.1) & (t < end - 0.1)
        assert move[inside].mean() >= 0.6, f"the mouth moved in {move[inside].mean():.0%} of {start:.2f}-{end:.2f}"
    edges = [0.0] + [x for s in speech for x in s] + [len(pcm) / RATE]
    for a, b in zip(edges[::2], edges[1::2]):  # the silences, away from the speech's moves
        quiet = (t >= a + 0.25) & (t < b - 0.25)
        assert quiet.any() and not move[quiet].any(), f"the mouth moved in the silence {a:.2f}-{b:.2f} s"


def test_closures_shut_the_lips(fed):
    out, tail = fed
    frames = np.concatenate([f for _, f in out] + [tail])
    from mpeg4fa.spec import VISEME_PROFILES

    pp = VISEME_PROFILES["mpeg4"]["PP"]
    col = int(np.argmax(np.abs(pp)))
    assert (np.sign(frames[:, col]) == np.sign(pp[col])).any() and \
        (np.abs(frames[:, col]) >= 0.8 * abs(pp[col])).any(), "'Maybe Bob ... map' never shut the lips"


@pytest.mark.parametrize("kind", ["silence", "noise", "chord"])
def test_silence_noise_and_a_held_chord_keep_the_mouth_at_rest(kind):
    """A held chord (C major, its loudness swelling at 0.5 Hz) is voice to the detector: without the
    steady-pitch gate the mouth moved in 91 % of its frames (melodies: the next test)."""
    n = 5 * RATE
    x = np.zeros(n)
    if kind == "noise":  # white noise at -30 dBFS
        x = np.random.default_rng(3).standard_normal(n)
        x *= 10 ** (-30 / 20) / np.sqrt(np.mean(x ** 2))
    elif kind == "chord":
        t = np.arange(n) / RATE
        x = sum(0.15 * np.sin(2 * np.pi * f * t) for f in (261.6, 329.6, 392.0)) * (0.6 + 0.4 * np.sin(np.pi * t))
    pcm = np.clip(np.rint(x * 32767), -32768, 32767).astype(np.int16)
    out, tail = run(pcm, 320)
    frames = np.concatenate([f for _, f in out] + [tail])
    assert len(frames) == 5 * FPS
    assert (~moving(frames)).mean() >= 0.95 if kind != "silence" else not moving(frames).any()


def melody(kind: str, seconds: float = 8.0, seed: int = 1, dbfs: float = -12.0) -> np.ndarray:
    """Notes of 0.3 s, 220-880 Hz (seeded, on the semitones), as pure tones, sawtooths (band-limited) or an
    organ's drawbars; RMS ``dbfs``."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(0.3 * RATE)) / RATE
    ramp = np.minimum(1, t / 0.01) * np.minimum(1, (0.3 - t) / 0.01)
    partials = {"sine": [(1, 1.0)], "sawtooth": [(k, 1 / k) for k in range(1, 40)],
                "organ": [(0.5, 0.6), (1, 1.0), (2, 0.7), (3, 0.4), (4, 0.3), (6, 0.2), (8, 0.15)]}[kind]
    notes = []
    for _ in range(int(seconds / 0.3)):
        f = 220 * 2 ** (rng.integers(0, 25) / 12)
        notes.append(ramp * sum(a * np.sin(2 * np.pi * f * m * t) for m, a in partials if f * m < RATE / 2))
    x = np.concatenate(notes)
    return x / np.sqrt(np.mean(x ** 2)) * 10 ** (dbfs / 20)


@pytest.mark.parametrize("kind", ["sine", "sawtooth", "organ", "music"])
def test_melodies_and_music_keep_the_mouth_at_rest(kind):
    """Measured 97.4 % at rest for each melody, 96.5 % for the music (the first 0.2 s move the mouth);
    before the pitch was taken on windows within the audio heard and at its period's shortest lag: 18 %, 19 %,
    65 % and 8 %."""
    from mpeg4fa.speech.listen.signals import music

    x = music(8.0, RATE) if kind == "music" else melody(kind)
    out, tail = run(np.clip(np.rint(x * 32767), -32768, 32767).astype(np.int16), 320)
    frames = np.concatenate([f for _, f in out] + [tail])
    rest = (~moving(frames)).mean()
    print(f"{kind}: at rest in {rest:.1%} of the frames")
    assert rest >= 0.95, f"{kind}: the mouth at rest in only {rest:.0%} of the frames"


@pytest.mark.parametrize("lang, text", [("es", "Mi madre compró pan y manzanas en el mercado."),
                                        ("de", "Meine Mutter backt heute Brot für die ganze Familie.")])
def test_speech_in_other_languages_moves_the_mouth(lang, text):
    """The music gate leaves speech alone: the mouth moves in (measured) 99-100 % of the 40 ms frames
    louder than -45 dBFS, as before it."""
    from mpeg4fa.speech.tts.espeak import EspeakEngine

    s = EspeakEngine().synthesize(text, voice=lang)
    x = np.r_[np.zeros(RATE // 2), resample(s.samples / 32768.0, s.rate, RATE), np.zeros(RATE // 2)]
    out, tail = run(np.clip(np.rint(x * 32767), -32768, 32767).astype(np.int16), 320)
    frames = np.concatenate([f for _, f in out] + [tail])
    loud = frame_levels(x, RATE) > -45
    spoken = np.array([loud[4 * k:4 * k + 4].any() for k in range(len(frames))])
    share = moving(frames)[spoken].mean()
    assert spoken.sum() >= 40 and share >= 0.9, f"{lang}: the mouth moved in {share:.0%} of the spoken frames"


def test_other_sample_rates_are_resampled_as_they_come(clip):
    pcm, speech = clip
    up = np.clip(np.rint(resample(pcm / 32768.0, RATE, 48000) * 32767), -32768, 32767).astype(np.int16)
    out, tail = run(up, 960, rate=48000)
    frames = np.concatenate([f for _, f in out] + [tail])
    assert len(frames) == math.ceil(len(up) / 48000 * FPS)
    t = np.arange(len(frames)) / FPS
    start, end = speech[0]
    assert moving(frames)[(t >= start + 0.1) & (t < end - 0.1)].mean() >= 0.6
    assert not moving(frames)[t < speech[0][0] - 0.25].any()
    # the resampler cut anywhere gives the same samples
    x = np.random.default_rng(0).integers(-2000, 2000, 4800).astype(np.int16)
    r1, r2 = Resampler(48000, RATE), Resampler(48000, RATE)
    whole = r1(x)
    parts = np.concatenate([r2(x[i:i + 333]) for i in range(0, len(x), 333)])
    assert len(whole) == 1600 and np.array_equal(whole, parts)


def test_every_phone_of_the_model_has_its_mouth_shapes():
    from mpeg4fa.spec import VISEME_PROFILES

    phones = {"AA", "AE", "AH", "AO", "AW", "AY", "B", "CH", "D", "DH", "EH", "ER", "EY", "F", "G", "HH", "IH",
              "IY", "JH", "K", "L", "M", "N", "NG", "OW", "OY", "P", "R", "S", "SH", "T", "TH", "UH", "UW", "V",
              "W", "Y", "Z", "ZH"}  # the en-us model's 39 phones
    for phone in phones:
        parts = phone_parts(phone)
        assert parts and all(v in VISEME_PROFILES["mpeg4"] for v, _, _ in parts), phone
        assert parts[0][1] == 0.0 and parts[-1][2] == 1.0 and all(a[2] == b[1] for a, b in zip(parts, parts[1:]))
    assert phone_parts("P") == phone_parts("B") == phone_parts("M") == (("PP", 0.0, 1.0),)
    assert [v for v, _, _ in phone_parts("AY")] == ["AA", "ih"]  # a diphthong in two shapes
    assert phone_parts("SIL") == phone_parts("+NSN+") == ()


@pytest.mark.parametrize("bad, why", [(b"\x00\x01\x02", "even number"), (np.zeros((2, 2), np.int16), "mono"),
                                      (np.array([np.nan]), "NaN"), (np.zeros(3, np.int32), "int16 or float")])
def test_bad_chunks_are_refused_saying_why(bad, why):
    live = LiveLipSync()
    with pytest.raises(ValueError, match=why):
        live.feed(bad)


def test_bad_settings_are_refused():
    with pytest.raises(ValueError, match="latency"):
        LiveLipSync(latency=0.05)
    with pytest.raises(ValueError, match="rate"):
        LiveLipSync(rate=100)


def test_the_kept_spans_lie_in_the_speech(clip):
    pcm, speech = clip
    live = LiveLipSync(keep_spans=True)
    for i in range(0, len(pcm), 320):
        live.feed(pcm[i:i + 320])
    live.flush()
    spans = live.timings
    assert len(spans) == live.spans > 0 and all(t.end > t.start for t in spans)
    for t in spans:
        assert any(a - 0.05 <= t.start and t.end <= b + 0.2 for a, b in speech), (t, speech)
    for a, b in speech:
        assert sum(min(t.end, b) - max(t.start, a) for t in spans if t.end > a and t.start < b) >= 0.5 * (b - a)
    with pytest.raises(ValueError, match="keep_spans"):
        LiveLipSync().timings


def test_a_skip_rests_the_mouth_over_it_and_listening_resumes_after(clip, fed):
    """A listener that fell behind skips audio (mpeg4fa.serve.microphone does, past a bound): the frames
    keep their count and times, the mouth rests over the skipped audio, and the speech after it moves the
    mouth as when it was all heard."""
    pcm, speech = clip
    (a0, a1), (b0, b1) = speech
    cut0, cut1 = int((a0 + 0.3) * RATE) // 320 * 320, int((a1 + 0.3) * RATE) // 320 * 320  # into the first sentence
    live = LiveLipSync(RATE, FPS)
    out, total = [], 0
    for i in range(0, len(pcm), 320):
        part = pcm[i:i + 320]
        frames = live.skip(part) if cut0 <= i < cut1 else live.feed(part)
        out.append(frames)
        total += len(frames)
        due = math.floor(round(((i + len(part)) / RATE - LATENCY) * FPS, 9)) + 1 if i + len(part) >= LATENCY * RATE else 0
        assert total == due, f"after {i + len(part)} samples {total} frames, {due} due"
    frames = np.concatenate(out + [live.flush()])
    assert len(frames) == math.ceil(len(pcm) / RATE * FPS) and live.skipped == cut1 - cut0
    t = np.arange(len(frames)) / FPS
    move = moving(frames)
    assert not move[(t >= cut0 / RATE + 0.25) & (t < cut1 / RATE)].any(), "the mouth moved over the skipped audio"
    assert move[(t >= a0) & (t < cut0 / RATE - 0.1)].mean() >= 0.6, "the speech before the skip was lost"
    # the second sentence, heard whole after the skip, as when nothing was skipped
    whole = np.concatenate([f for _, f in fed[0]] + [fed[1]])
    inside = (t >= b0 + 0.1) & (t < b1 - 0.1)
    assert move[inside].mean() >= 0.6
    agree = (frames[inside][:, LIPS] == whole[inside][:, LIPS]).all(axis=1).mean()
    print(f"the sentence after the skip: {agree:.0%} of its frames as when all was heard")
    # not all: the decoders' cepstral means (pocketsphinx's live CMN) carry the audio each heard before, and
    # after a skip that is other audio, so the phone loop decides otherwise where it is unsure (84 % here
    # alone, 68 % in the whole suite, whose espeak-ng speaks the clip a little differently after other text)
    assert agree >= 0.5


def test_a_skip_at_another_rate_keeps_the_clock(clip):
    """At 44.1 kHz in 128-sample blocks (an AudioWorklet's): a skipped second is 16000 of the model's samples
    (46.44 a block: rounded block by block, 1 % of the skipped time was lost), and the frames after it come on
    time."""
    pcm = resample(clip[0] / 32768.0, RATE, 44100)
    live = LiveLipSync(44100, FPS)
    n = 0
    for k, i in enumerate(range(0, len(pcm), 128)):
        part = pcm[i:i + 128]
        n += len(live.skip(part) if 345 <= k < 690 else live.feed(part))  # 345 blocks, 44160 samples
    assert live.skipped == round(44160 * RATE / 44100) == 16022
    assert n + len(live.flush()) == math.ceil(len(pcm) / 44100 * FPS)
