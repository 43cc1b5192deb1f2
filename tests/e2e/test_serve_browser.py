"""The live player page in a real browser (Playwright driving Debian's chromium, WebGL through SwiftShader).

The server runs in-process on a free 127.0.0.1 port with the generic head when it is built (its
GLB carries the 52 ARKit morph targets, so the mouth moves), else the procedural head (a GLB
without units: the page still plays frames and audio, and the mouth check is skipped, saying so).
A user types tagged text and presses Speak; the page receives the frames and audio over the
WebSocket, reports its buffer, plays the frames on the AudioContext's clock (chromium's fake
audio output runs it) and shows the face. Screenshots go to ``test-artifacts/serve/``.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest

from e2e.browser import ARGS, CHROMIUM, require_browser

ARTEFACTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "serve"
BACKGROUND = (0x2B, 0x2F, 0x36)
TEXT = "(joy, 40, 0.5) Hello there. Open wide, and say ah. Thank you!"

sync_api = require_browser()
ARGS = ARGS + ["--autoplay-policy=no-user-gesture-required"]  # the page plays speech unprompted

from PIL import Image  # noqa: E402

from mpeg4fa.serve.app import create_app  # noqa: E402
from serve.live_server import face_for_tests, running  # noqa: E402


@pytest.fixture(scope="module")
def app():
    return create_app(face_for_tests(), warm=True)


@pytest.fixture(scope="module")
def page(app):
    if ARTEFACTS.exists():
        shutil.rmtree(ARTEFACTS)
    ARTEFACTS.mkdir(parents=True)
    with running(app) as base, sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        pg = browser.new_page(viewport={"width": 900, "height": 700})
        errors: list[str] = []
        pg.on("pageerror", lambda e: errors.append(str(e)))
        pg.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        pg.goto(base + "/")
        pg.wait_for_function("window.player && window.player.ready && window.player.hello", timeout=60_000)
        pg.errors = errors
        yield pg
        browser.close()


def shot(page, name: str) -> Path:
    path = ARTEFACTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


def drawn_fraction(path: Path) -> float:
    img = np.asarray(Image.open(path).convert("RGB"), dtype=np.int16)[60:]  # below the header
    return float((np.abs(img - BACKGROUND).sum(axis=2) > 30).mean())


def test_a_user_hears_and_sees_the_head_speak(app, page):
    units = page.evaluate("window.player.units")
    rest = shot(page, "01-rest")
    assert drawn_fraction(rest) > 0.05, "WebGL drew nothing over the background"
    page.fill("#text", TEXT)
    page.click("#speak")
    page.wait_for_function("window.player.latencyMs !== null", timeout=30_000)
    if units:  # wait for a wide-open mouth to photograph it
        jaw = units.index("jawOpen")
        page.wait_for_function(f"window.player.weightsNow[{jaw}] > 0.25", timeout=30_000)
        shot(page, "02-speaking")
    page.wait_for_function("window.player.done !== null", timeout=60_000)
    page.wait_for_function("window.player.mediaTime > window.player.done.duration", timeout=30_000)
    shot(page, "03-done")
    s = page.evaluate("""() => { const p = window.player; return {frames: p.frames.length, shown: p.shownFrames,
        audio: p.audioChunks, fba: p.fbaBytes, segments: p.segments.length, latency: p.latencyMs,
        underruns: p.underruns, done: p.done, errors: p.errors, reports: p.reports, clock: p.clock,
        maxAhead: p.maxAhead, last: p.shown, window: p.hello.window, chunk: p.hello.chunk}; }""")
    print(f"\nbrowser: first frame after {s['latency']:.0f} ms, {s['frames']} frames ({s['shown']} shown), "
          f"{s['audio']} audio chunks, {s['segments']} segments, {s['fba']} FBA bytes, clock {s['clock']}, "
          f"underruns {s['underruns']}, {s['reports']} buffer reports")
    assert not page.errors and not s["errors"], (page.errors, s["errors"])
    assert s["segments"] == 3 and s["fba"] > 0 and s["frames"] == s["done"]["frames"] > 50
    # SwiftShader draws a few frames a second here, so the page skips frames: it must still get to the last one
    assert 0 < s["shown"] and s["last"] == s["frames"] - 1
    assert s["audio"] > 0 and s["reports"] > 0
    assert s["maxAhead"] <= s["window"] + s["chunk"] + 0.1  # flow control bounded what was sent
    record = app.state.live.utterances[-1]
    assert record["frames"] == s["frames"] and not record["stalled"] and record["error"] is None
    if not units:
        pytest.skip("the procedural head has no ARKit units: frames and audio played, the mouth cannot move")
