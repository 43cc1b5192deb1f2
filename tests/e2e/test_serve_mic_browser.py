"""The live page's microphone in a real browser: Chromium's fake microphone plays an espeak-ng WAV
(``--use-fake-device-for-media-stream --use-file-for-fake-audio-capture=FILE.wav``, looped), the page
captures it (getUserMedia, the AudioWorklet's 16 kHz), the server listens (mpeg4fa.speech.live) and sends
the face back as FBA, which the player decodes and poses. Checked on what the page itself shows: the jaw
and lip FAPs of the frames it plays (read back from ``window.player``) open while the file speaks and
rest in its silences, the drawn head's values open during the run, and a screenshot of the open mouth
(``test-artifacts/serve-mic/``). The player holds only the frames of the last 2 s shown and those to come
(a session has no end the page knows of): the test keeps those it lets go, and the most it held is checked
against that bound; the status line says how far behind the voice the face is."""
from __future__ import annotations

import re
import time
from pathlib import Path

import numpy as np
import pytest

from e2e.browser import ARGS, CHROMIUM, fresh_folder, require_browser

sync_api = require_browser()
pytest.importorskip("pocketsphinx", reason="the microphone's lip sync needs pocketsphinx (the 'align' extra)")

from mpeg4fa.serve.app import create_app  # noqa: E402
from mpeg4fa.spec import FAP_BY_NAME  # noqa: E402
from mpeg4fa.speech.align.recording import resample  # noqa: E402
from mpeg4fa.wav import write_pcm16  # noqa: E402
from serve.live_server import face_for_tests, running  # noqa: E402

ARTEFACTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "serve-mic"
TEXT = "Open wide and say ah. Maybe Bob will bring a map."
RATE = 48000
BEFORE, AFTER = 1.5, 2.5
LIPS = [FAP_BY_NAME[n].number - 1 for n in (
    "open_jaw", "lower_t_midlip", "raise_b_midlip", "stretch_l_cornerlip", "stretch_r_cornerlip",
    "lower_t_lip_lm", "lower_t_lip_rm", "raise_b_lip_lm", "raise_b_lip_rm", "push_b_lip", "push_t_lip")]
JAW = FAP_BY_NAME["open_jaw"].number - 1
KEEP, FPS = 2.0, 25
HELD_AT_MOST = int((KEEP + 1.0) * FPS)  # 2 s shown, and under 1 s to come (latency, margin, a late message)


@pytest.fixture(scope="module")
def wav(tmp_path_factory) -> tuple[Path, float]:
    """The file the fake microphone plays: silence, the sentences, silence (16-bit mono, 48 kHz)."""
    from mpeg4fa.speech.tts.espeak import EspeakEngine

    speech = EspeakEngine().synthesize(TEXT)
    x = np.concatenate([np.zeros(int(BEFORE * RATE)), resample(speech.samples / 32768.0, speech.rate, RATE),
                        np.zeros(int(AFTER * RATE))])
    path = tmp_path_factory.mktemp("mic") / "speech.wav"
    write_pcm16(path, np.clip(np.rint(x * 32767), -32768, 32767).astype(np.int16), RATE)
    return path, len(x) / RATE


def speech_spans(levels: list[float]) -> list[tuple[float, float]]:
    """Where the audio the page sent is speech: 20 ms chunks above -45 dBFS, gaps under 0.3 s joined."""
    loud = np.asarray(levels) > -45
    edges = np.flatnonzero(np.diff(np.r_[0, loud.astype(int), 0]))
    spans: list[list[float]] = []
    for a, b in zip(edges[::2] * 0.02, edges[1::2] * 0.02):
        if spans and a - spans[-1][1] < 0.3:
            spans[-1][1] = b
        else:
            spans.append([a, b])
    return [(a, b) for a, b in spans]


def test_the_mouth_follows_the_microphone(wav):
    path, loop = wav
    fresh_folder(ARTEFACTS)
    args = ARGS + ["--use-fake-device-for-media-stream", "--use-fake-ui-for-media-stream",
                   f"--use-file-for-fake-audio-capture={path}", "--autoplay-policy=no-user-gesture-required"]
    app = create_app(face_for_tests(), warm=True)  # as `serve` starts it
    with running(app) as base, sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=args)
        page = browser.new_page(viewport={"width": 900, "height": 700})
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.goto(base + "/")
        page.wait_for_function("window.player && window.player.ready && window.mic", timeout=60_000)
        page.click("#mic")
        page.wait_for_function("window.mic.on || window.mic.errors.length", timeout=30_000)
        assert page.evaluate("window.mic.errors") == []
        # the head as drawn: its jaw FAP sampled while about 1.6 loops of the file play
        shown, best, shots, open_shot = [], 0.0, 0, ARTEFACTS / "01-mouth-open.png"
        statuses: list[str] = []
        # the frames the player lets go, kept by the test as they go (page.evaluate between screenshots would
        # miss those a stalled page trims in a burst)
        page.evaluate(f"""() => {{
            const p = window.player, trim = p.trim, row = (f) => [f.t, ...{LIPS}.map((c) => f.values[c])];
            window.gone = [];
            window.rows = () => window.gone.concat(p.frames.map(row));
            p.trim = (seconds) => {{
                const before = p.frames.slice(), n = trim(seconds);
                for (let i = 0; i < n; i++) window.gone.push(row(before[i]));
                return n;
            }};
        }}""")

        deadline, polled = time.monotonic() + 60, 0.0
        while page.evaluate("window.mic.sent") < 1.6 * loop * 16000:
            assert time.monotonic() < deadline, "the page did not send the microphone's audio in time"
            jaw = page.evaluate(f"window.player.valuesNow[{JAW}]")
            shown.append(jaw)
            if jaw > max(best * 1.3, 150) and shots < 3:  # a screenshot stalls the page: a few only
                best, shots = jaw, shots + 1
                page.screenshot(path=str(open_shot))
            if time.monotonic() - polled > 0.25:
                statuses.append(page.evaluate("document.getElementById('status').textContent"))
                polled = time.monotonic()
            time.sleep(0.02)
        page.click("#mic")
        page.wait_for_function("window.mic.ended !== null", timeout=20_000)
        page.wait_for_timeout(500)
        page.screenshot(path=str(ARTEFACTS / "02-after.png"))
        mic = page.evaluate("({levels: window.mic.levels, offset: window.mic.offset, faces: window.mic.faces, "
                            "errors: window.mic.errors, ended: window.mic.ended, rate: window.mic.contextRate, "
                            "frames: window.mic.frames, mostHeld: window.mic.mostHeld, dropped: window.mic.dropped, "
                            "neverShown: window.mic.neverShown(), longestWait: window.mic.longestWait, skipped: window.mic.skipped, "
                            "skips: window.mic.skips})")
        frames = np.array(page.evaluate("window.rows()"), dtype=np.float64)
        player_errors = page.evaluate("window.player.errors")
        browser.close()
    assert not errors and not player_errors and not mic["errors"], (errors, player_errors, mic["errors"])
    assert mic["faces"] > 0 and mic["ended"]["frames"] >= mic["frames"] == len(frames) > 0
    assert np.all(np.diff(frames[:, 0]) > 0)  # in order, none twice
    print(f"\nframes held at most {mic['mostHeld']} of {mic['frames']} received ({mic['dropped']} dropped once shown)")
    assert mic["mostHeld"] <= HELD_AT_MOST < mic["frames"] / 2, (mic["mostHeld"], mic["frames"])
    behind = [int(m.group(1)) for text in statuses if (m := re.search(r"face (\d+) ms behind the voice", text))]
    assert behind, statuses[-3:]
    print(f"status: {statuses[len(statuses) // 2]!r}; behind the voice {min(behind)}-{max(behind)} ms")
    # how long ago the audio of the face on screen was sent, on the page's clock: the server's latency (180 ms)
    # and the page's margin at least; on this 2-core machine the server shares the cores with Chromium's
    # software rendering and its answers come 400-550 ms after the audio (2026-12-07). Before, the line said
    # how far the page's clock was behind the audio sent: 54 ms once in CI, where the fake microphone ran
    # slower than the clock, though no face can show before the server has heard its audio
    assert 100 <= np.median(behind) <= 1500, behind
    # frames past their time when they come are shown when they come: no "underruns" on this page; what it
    # says instead is what a viewer would see go wrong (frames never shown, the face waiting for a message)
    lines = [text for text in statuses if "behind the voice" in text]
    assert lines and not any("underrun" in text for text in lines), lines[-1]
    assert all(re.search(r"\d+ never shown, longest wait \d+ ms", text) for text in lines), lines[-1]
    print(f"never shown {mic['neverShown']} of {mic['frames']}, longest wait {mic['longestWait'] * 1000:.0f} ms")
    assert 0 <= mic["neverShown"] < mic["frames"]  # how many depends on how fast this machine draws the page
    t = frames[:, 0] - mic["offset"]  # the session time of the audio each frame shows
    moving = np.abs(frames[:, 1:]).max(axis=1) > 0
    spans = speech_spans(mic["levels"])
    sent = len(mic["levels"]) * 0.02
    print(f"\njaw in the frames: max {frames[:, 1].max():.0f}, p90 {np.percentile(frames[:, 1], 90):.0f}; "
          f"context {mic['rate']} Hz, {sent:.1f} s sent, {len(frames)} frames, speech at "
          + ", ".join(f"{a:.2f}-{b:.2f}" for a, b in spans) + f"; jaw shown up to {max(shown):.0f}")
    assert len(spans) >= 1
    # a server that fell behind (a busy machine) skipped audio to catch up, the mouth at rest over it: speech
    # from where it began skipping to half a second after it resumed is not its to show (serve/microphone.py)
    skips = [(a, np.inf if b is None else b + 0.5) for a, b in mic["skips"]]
    print(f"the server skipped {mic['skipped']:.2f} s: " + (", ".join(f"{a:.2f}-{b:.2f}" for a, b in skips) or "none"))
    checked = 0
    for a, b in spans:
        if b > t[-1] - 0.3 or any(a < y and b > x for x, y in skips):
            continue  # speech the session ended in the middle of, or that was skipped
        checked += 1
        inside = (t >= a + 0.1) & (t < b - 0.1)
        assert inside.sum() >= 10 and moving[inside].mean() >= 0.5, \
            f"the mouth moved in {moving[inside].mean():.0%} of the speech at {a:.2f}-{b:.2f} s"
    edges = [0.0] + [x for s in spans for x in s] + [t[-1]]
    quiet_frames = 0
    for a, b in zip(edges[::2], edges[1::2]):  # the silences, away from the moves into and out of speech
        quiet = (t >= a + 0.3) & (t < b - 0.3)
        quiet_frames += int(quiet.sum())
        assert not moving[quiet].any(), f"the mouth moved in the silence {a:.2f}-{b:.2f} s"
    # both sentences followed; one of them, where the server skipped audio to catch up
    assert quiet_frames >= 25 and checked >= (1 if skips else 2), (quiet_frames, checked, skips, t[-1])
    shown = np.asarray(shown)
    assert shown.max() > 150 and (shown == 0).mean() > 0.2, "the drawn head's jaw did not open and close"
    assert open_shot.exists()
