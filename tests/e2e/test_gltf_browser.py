"""The exported GLB in a real browser: three.js's GLTFLoader (vendored) in Debian's chromium via Playwright.

A static server on 127.0.0.1 serves the test page (``gltf_viewer.html``), the vendored three.js and
the GLB. The page plays the GLB's animation to a time and draws it; screenshots go to
``test-artifacts/gltf/``. Checked: the loader reads the targets under their names and the animation,
the influences at a key time are the file's weights, the face covers the frame, and the mouth shows
its inside (the dark of the cavity, teeth) at the widest-open frame and not at the neutral first frame.
Morph animation runs on the generic head (skips when it is not built), vertex animation on both heads
(the procedural one has no mouth inside: there the jaw's drop is checked as the lower face changing).
"""
from __future__ import annotations

import functools
import shutil
import threading
from http.server import SimpleHTTPRequestHandler, ThreadingHTTPServer
from pathlib import Path

import numpy as np
import pytest

from e2e.browser import ARGS, CHROMIUM, require_browser

ROOT = Path(__file__).resolve().parents[2]
ARTEFACTS = ROOT / "test-artifacts" / "gltf"
THREE = ROOT / "mpeg4fa" / "web" / "static" / "vendor" / "three"
PAGE = Path(__file__).with_name("gltf_viewer.html")
BACKGROUND = 0x20
DARK = 45  # luma below this: the mouth's cavity (the lit skin, lips and teeth are far brighter)
TEETH_MIN, TEETH_SPREAD = 150, 40  # teeth: every channel above this, channels within this of each other

sync_api = require_browser()

from PIL import Image  # noqa: E402

from export.gltf_files import FPS, OPEN_FRAME, load, read_accessor, talk_stream  # noqa: E402
from mpeg4fa.export.gltf import MM, export_glb  # noqa: E402


class _Quiet(SimpleHTTPRequestHandler):
    def log_message(self, format, *args) -> None:  # noqa: A002 - the base class's name
        pass


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """(base URL, folder served): the page and three.js in it; each test adds its GLB."""
    root = tmp_path_factory.mktemp("gltf-site")
    shutil.copy(PAGE, root / PAGE.name)
    (root / "vendor").mkdir()
    (root / "vendor" / "three").symlink_to(THREE, target_is_directory=True)
    server = ThreadingHTTPServer(("127.0.0.1", 0), functools.partial(_Quiet, directory=str(root)))
    thread = threading.Thread(target=server.serve_forever, daemon=True)
    thread.start()
    yield f"http://127.0.0.1:{server.server_address[1]}", root
    server.shutdown()
    thread.join(10)


@pytest.fixture(scope="module")
def browser():
    ARTEFACTS.mkdir(parents=True, exist_ok=True)
    with sync_api.sync_playwright() as p:
        chromium = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        yield chromium
        chromium.close()


def _mouth_box(page, face) -> tuple[int, int, int, int]:
    """Pixel box (x0, y0, x1, y1) around the lips, from the lip corners down to below the open jaw."""
    def at(label):
        return np.array(page.evaluate("p => window.viewer.project(p)", (face.mesh.fp(label) * MM).tolist()))
    left, right, top, bottom = at("8.4"), at("8.3"), at("8.1"), at("8.2")
    x0, x1 = sorted((left[0], right[0]))
    return int(x0), int(top[1]), int(x1) + 1, int(bottom[1] + 1.5 * (bottom[1] - top[1])) + 1


def _play(browser, site, face, label: str, texture: np.ndarray | None = None, points: tuple[str, ...] = (),
          stream=None):
    base, root = site
    stream = talk_stream() if stream is None else stream
    name = f"{label}.glb"
    export_glb(stream, face, root / name, animation=label.partition("-")[0], texture=texture)
    page = browser.new_page(viewport={"width": 480, "height": 480})
    errors: list[str] = []
    page.on("pageerror", lambda e: errors.append(str(e)))
    page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    page.goto(f"{base}/{PAGE.name}?glb={name}")
    page.wait_for_function("document.body.dataset.ready === '1' || document.body.dataset.error", timeout=60_000)
    assert not page.evaluate("document.body.dataset.error"), page.evaluate("document.body.dataset.error")
    shots, influences = {}, {}
    for moment, frame in (("neutral", 0), ("open", OPEN_FRAME)):
        influences[moment] = np.array(page.evaluate("t => window.viewer.showAt(t)", frame / FPS))
        path = ARTEFACTS / f"{label}-{moment}.png"
        page.screenshot(path=str(path))
        shots[moment] = np.asarray(Image.open(path).convert("RGB")).astype(int)
    info = page.evaluate("({clip: window.viewer.clip, targets: window.viewer.targets})")
    box = _mouth_box(page, face)
    info["points"] = {label: page.evaluate("p => window.viewer.project(p)", (face.mesh.fp(label) * MM).tolist())
                      for label in points}
    page.close()
    assert not errors, errors
    return stream, root / name, shots, influences, info, box


def _check_pictures(shots, box, animation):
    for label, img in shots.items():
        covered = (np.abs(img - BACKGROUND).sum(axis=2) > 12).mean()
        assert covered > 0.3, f"{label}: the head covers only {covered:.0%} of the frame"
    x0, y0, x1, y1 = box
    inside = {label: int(_mouth_inside(img[y0:y1, x0:x1]).sum()) for label, img in shots.items()}
    area = (x1 - x0) * (y1 - y0)
    assert area > 100, box
    assert inside["neutral"] < 0.02 * area, (animation, inside, area)
    # The open mouth shows what the closed one does not: at least twice its pixels (the lip line's dark
    # seam is all a closed mouth shows), and 2 % of the box more. The tongue, pink like the lips, covers
    # most of the opening and is not counted: the generic head's vertex frame shows 358 against 122
    # (its lips held to the corners' jaw share since rig.CORNER_HOLD_MM; 389 before).
    assert inside["open"] > 2 * inside["neutral"], (animation, inside, area)
    assert inside["open"] - inside["neutral"] > 0.02 * area, (animation, inside, area)


def _mouth_inside(pixels: np.ndarray) -> np.ndarray:
    """What only an open mouth shows: the dark of the cavity, or teeth (bright and grey-white; lips and
    skin are pink, far more saturated)."""
    luma = pixels @ [0.299, 0.587, 0.114]
    teeth = (pixels.min(axis=-1) > TEETH_MIN) & (np.ptp(pixels, axis=-1) < TEETH_SPREAD)
    return (luma < DARK) | teeth


def test_morph_animation_plays_in_three(browser, site, generic_face):
    stream, glb, shots, influences, info, box = _play(browser, site, generic_face, "morph")
    names = list(generic_face.mesh.face_units.names)
    assert info["targets"] == names and info["clip"]["duration"] == pytest.approx((len(stream) - 1) / FPS, abs=1e-6)
    gltf = load(glb)
    sampler = gltf.animations[0].samplers[0]
    weights = read_accessor(gltf, sampler.output).reshape(len(stream), -1)
    assert np.allclose(influences["open"], weights[OPEN_FRAME], atol=1e-6)
    assert not influences["neutral"].any() and influences["open"][names.index("jawOpen")] > 0.3
    _check_pictures(shots, box, "morph")


@pytest.mark.parametrize("which", ["procedural", "generic"])
def test_vertex_animation_plays_in_three(browser, site, request, which):
    face = request.getfixturevalue(f"{which}_face")
    stream, glb, shots, influences, info, box = _play(browser, site, face, f"vertex-{which}")
    gltf = load(glb)
    weights = read_accessor(gltf, gltf.animations[0].samplers[0].output).reshape(len(stream), -1)
    assert info["targets"] == gltf.meshes[0].extras["targetNames"]
    assert np.allclose(influences["open"], weights[OPEN_FRAME], atol=1e-5)
    if which == "generic":
        _check_pictures(shots, box, "vertex")
    else:  # a closed surface with no mouth inside: the jaw's drop shows as the lower face changing
        x0, y0, x1, y1 = box
        changed = np.abs(shots["open"] - shots["neutral"]).sum(axis=2)[y0:y1, x0:x1] > 60
        assert changed.mean() > 0.2, changed.mean()


def test_texture_lies_as_the_renderer_lays_it(browser, site, generic_face):
    """The UV flip: the renderer reads image row 0 at v = 1 (:meth:`Renderer.set_texture`); glTF reads it at
    v = 0. Image rows above the middle green, below red: the left ear (v 0.61 on the generic head's
    atlas, image row 0.39) must come out green and the right ear (v 0.36, row 0.64) red in three.js."""
    texture = np.zeros((256, 256, 3), np.uint8)
    texture[:128, :, 1] = 230
    texture[128:, :, 0] = 230
    *_, shots, _, info, _ = _play(browser, site, generic_face, "vertex-textured", texture=texture,
                                  points=("10.1", "10.2"))
    def colour_at(label):
        x, y = (int(round(c)) for c in info["points"][label])
        return shots["neutral"][y - 2:y + 3, x - 2:x + 3].reshape(-1, 3).mean(axis=0)
    left, right = colour_at("10.1"), colour_at("10.2")
    assert left[1] > 2 * left[0] and right[0] > 2 * right[1], (left, right)


def test_head_turn_plays_in_three(browser, site, generic_face):
    """Yaw (FAP 49) rising to 0.5 rad: the pivot node turns the head, and the face's pixels move sideways."""
    stream = talk_stream()
    stream.fap_mask[:, 48] = True
    stream.fap_values[:, 48] = np.round(np.linspace(0, 50000, len(stream)))
    *_, shots, _, _, _ = _play(browser, site, generic_face, "morph-turn", stream=stream)
    def centre_x(img):
        _, xs = np.nonzero(np.abs(img - BACKGROUND).sum(axis=2) > 12)
        return xs.mean()
    # OPEN_FRAME is about half way: yaw 0.25 rad, the face turned toward its left (+x, the image's right)
    assert centre_x(shots["open"]) - centre_x(shots["neutral"]) > 4
