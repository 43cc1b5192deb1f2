"""Photo calibration in the editor page, in a real browser (Playwright driving Debian's chromium).

The photos are the synthetic front and left views of the procedural head that the API tests render
(tests/web/test_photos.py), written to files and picked in the page's file inputs. A user drags a box
edge and a feature point on each photo with the mouse, calibrates (DFFD), watches the calibrated head
(wearing the blended texture) in the small view beside the photos, drags again (the head is
recalibrated when the drag ends), exports, and the exported FDP and texture are checked. Each step
leaves a screenshot in ``test-artifacts/editor-photos/`` (ignored by git).

The server runs in a child process: the texture bake draws with GL, whose context belongs to the
thread that made it, and this process's GL context (the synthetic photos' renders, other tests')
lives on the main thread, which Playwright holds.
"""
from __future__ import annotations

import io
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest

from e2e.browser import editor_page, free_port, fresh_folder, require_browser


require_browser()  # skips the module, saying what to install, without playwright or chromium

import httpx  # noqa: E402
from PIL import Image  # noqa: E402

from mpeg4fa.fdp import load_fdp  # noqa: E402
from mpeg4fa.fdp.build import points_from_photos  # noqa: E402
from mpeg4fa.web import photos  # noqa: E402
from web.test_photos import PHOTO, SIZE, Synthetic  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
ARTEFACTS = ROOT / "test-artifacts" / "editor-photos"
BACKGROUND = (0x2B, 0x2F, 0x36)
SERVER = textwrap.dedent("""
    import sys
    sys.path.insert(0, sys.argv[1])
    import uvicorn
    from procedural_head import build_procedural_head
    from mpeg4fa.face.model import FaceModel
    from mpeg4fa.web.app import create_app
    app = create_app(out_dir=sys.argv[2], head=FaceModel(build_procedural_head()))
    uvicorn.run(app, host="127.0.0.1", port=int(sys.argv[3]), log_level="warning", lifespan="off")
""")


@pytest.fixture(scope="module")
def server(tmp_path_factory):
    out = tmp_path_factory.mktemp("photos-out")
    port = free_port()
    log = tmp_path_factory.mktemp("photos-log") / "server.log"
    with open(log, "wb") as sink:
        proc = subprocess.Popen([sys.executable, "-c", SERVER, str(ROOT / "tests"), str(out), str(port)],
                                cwd=ROOT, stdout=sink, stderr=subprocess.STDOUT)
    base = f"http://127.0.0.1:{port}"
    api = httpx.Client(base_url=base, timeout=60)
    deadline = time.monotonic() + 60
    while True:
        try:
            if api.get("/api/feature-points").status_code == 200:
                break
        except httpx.TransportError:
            pass
        if time.monotonic() > deadline or proc.poll() is not None:
            proc.kill()
            pytest.fail(f"the editor server did not start: {log.read_text(errors='replace')[-2000:]}")
        time.sleep(0.1)
    yield base, out, api
    proc.terminate()
    try:
        proc.wait(10)
    except subprocess.TimeoutExpired:
        proc.kill()


@pytest.fixture(scope="module")
def photo_files(tmp_path_factory, procedural_face):
    synth = Synthetic(procedural_face)
    folder = tmp_path_factory.mktemp("photos")
    paths = {}
    for key in ("front", "side"):
        paths[key] = folder / f"{key}.png"
        paths[key].write_bytes(synth.png[key])
    return synth, paths


@pytest.fixture(scope="module")
def page(server):
    fresh_folder(ARTEFACTS)
    with editor_page(server[0], height=860) as pg:
        pg.wait_for_selector("#panel-photos[data-ready='1']", state="attached", timeout=15_000)
        yield pg


def shot(page, name: str) -> Path:
    page.wait_for_timeout(200)  # the next animation frame has drawn
    path = ARTEFACTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


def idle(page) -> None:
    page.wait_for_selector("#panel-photos[data-busy='0']", state="attached", timeout=60_000)


def counter(page, name: str) -> int:
    return int(page.evaluate(f"document.getElementById('panel-photos').dataset.{name} || '0'"))


def wait_counter(page, name: str, above: int, timeout: int = 90_000) -> None:
    page.wait_for_function(f"Number(document.getElementById('panel-photos').dataset.{name} || 0) > {above}",
                           timeout=timeout)


def drag(page, start: dict, dx: float, dy: float) -> None:
    page.mouse.move(start["x"], start["y"])
    page.mouse.down()
    page.mouse.move(start["x"] + dx / 2, start["y"] + dy / 2, steps=4)
    page.mouse.move(start["x"] + dx, start["y"] + dy, steps=4)
    page.mouse.up()


def point_at(page, view: str, label: str) -> dict:
    xy = page.evaluate(f"window.photos.screenOfPoint('{view}', '{label}')")
    hit = page.evaluate(f"document.elementFromPoint({xy['x']}, {xy['y']}).dataset.label || null")
    assert hit == label, f"the {label} circle on the {view} photo is covered by {hit}"
    return xy


def guess(page) -> dict:
    return page.evaluate("JSON.parse(JSON.stringify(window.photos.state.guess))")


def drawn_fraction(path: Path, box) -> float:
    img = np.asarray(Image.open(path).convert("RGB").crop(box), dtype=np.int16)
    return float((np.abs(img - BACKGROUND).sum(axis=2) > 30).mean())


def box_of(page, selector: str):
    b = page.locator(selector).bounding_box()
    return (int(b["x"]), int(b["y"]), int(b["x"] + b["width"]), int(b["y"] + b["height"]))


def test_a_user_calibrates_the_head_on_two_photos(server, page, photo_files):
    _, out, api = server
    synth, files = photo_files
    v = page.evaluate("window.editor.state.version")
    page.click("[data-testid=load-head]")
    page.wait_for_function(f"window.editor.state.version > {v}", timeout=15_000)
    model = api.get("/api/model").json()
    page.click("[data-testid=photos-toggle]")
    page.wait_for_selector("#panel-photos[data-open='1'] .photos-body", state="visible")
    shot(page, "01-head-loaded-panel-open")

    # the two photos, picked in the file inputs: drawn with the head's box and points over them
    page.set_input_files("[data-testid=photo-front]", str(files["front"]))
    page.set_input_files("[data-testid=photo-side]", str(files["side"]))
    page.click("[data-testid=photos-load]")
    page.wait_for_selector("#panel-photos[data-loaded='1']", state="attached", timeout=30_000)
    idle(page)
    g0 = guess(page)
    assert page.locator("#svg-front circle.fp").count() == len(g0["front"]) == 84
    assert page.locator("#svg-side circle.fp").count() == len(g0["side"]) < 84
    path = shot(page, "02-photos-loaded")
    for view in ("front", "side"):  # the photo shows (the head on the dark background)
        assert drawn_fraction(path, box_of(page, f"#svg-{view}")) > 0.2
        bx = page.locator(f"[data-testid=box-{view}]").bounding_box()
        sv = page.locator(f"#svg-{view}").bounding_box()
        assert sv["x"] <= bx["x"] and bx["x"] + bx["width"] <= sv["x"] + sv["width"] + 1  # the box on the photo
    scale = {v: page.evaluate(f"window.photos.scale('{v}')") for v in ("front", "side")}  # photo px per screen px
    assert 1.0 < scale["front"] < 2.0 and 1.0 < scale["side"] < 2.0

    # drag the front box's right edge 15 px right and the side box's top edge 10 px down
    refits = counter(page, "refits")
    drag(page, page.evaluate("window.photos.screenOfEdge('front', 'right', 0.2)"), 15, 0)
    wait_counter(page, "refits", refits)
    drag(page, page.evaluate("window.photos.screenOfEdge('side', 'top', 0.25)"), 0, 10)
    wait_counter(page, "refits", refits + 1)
    idle(page)
    g1 = api.get("/api/photos").json()["guess"]
    assert g1["box"]["front"][2] - g0["box"]["front"][2] == pytest.approx(15 * scale["front"], abs=1.5)
    assert g1["box"]["side"][1] - g0["box"]["side"][1] == pytest.approx(10 * scale["side"], abs=1.5)
    assert g1["front"]["10.10"][0] > g0["front"]["10.10"][0]  # the guessed points followed the box
    assert g1 == guess(page)
    shot(page, "03-boxes-dragged")

    # drag the chin 10 px down on the front photo and the nose tip 12 px forward (left) on the side
    drag(page, point_at(page, "front", "2.1"), 0, 10)
    drag(page, point_at(page, "side", "9.3"), -12, 0)
    g2 = guess(page)
    assert g2["front"]["2.1"][1] - g1["front"]["2.1"][1] == pytest.approx(10 * scale["front"], abs=1.5)
    assert g1["side"]["9.3"][0] - g2["side"]["9.3"][0] == pytest.approx(12 * scale["side"], abs=1.5)
    assert page.locator("#svg-front circle.fp.dragged").count() == 1
    # a box refit now keeps them where they were put (only the guesses follow)
    drag(page, page.evaluate("window.photos.screenOfEdge('front', 'left', 0.2)"), -8, 0)
    wait_counter(page, "refits", refits + 2)
    idle(page)
    g3 = api.get("/api/photos").json()["guess"]
    assert g3["dragged"] == {"front": ["2.1"], "side": ["9.3"]}
    assert g3["front"]["2.1"] == pytest.approx(g2["front"]["2.1"], abs=1e-2)
    assert g3["side"]["9.3"] == pytest.approx(g2["side"]["9.3"], abs=1e-2)
    assert g3["front"]["2.10"][0] != pytest.approx(g2["front"]["2.10"][0], abs=0.5)
    shot(page, "04-points-dragged")

    # calibrate with DFFD: the small view shows the calibrated head wearing the blended texture
    page.select_option("[data-testid=calib-method]", "dffd")
    page.click("[data-testid=calibrate]")
    wait_counter(page, "calibrated", 0)
    wait_counter(page, "textures", 0)
    idle(page)
    assert "dffd" in page.locator("[data-testid=calib-report]").inner_text()
    assert page.evaluate("document.getElementById('texture-preview').naturalWidth") == SIZE
    assert page.evaluate("window.photos.live.skin.material.map !== null")
    path = shot(page, "05-calibrated")
    assert drawn_fraction(path, box_of(page, "#calib-canvas")) > 0.15, "the live view drew no head"
    tex = np.asarray(Image.open(path).convert("RGB").crop(box_of(page, "#texture-preview")), dtype=float)
    assert tex.std(axis=(0, 1)).min() > 10, "the texture preview is blank"
    nose = model["points"]["9.3"]
    z_before = page.evaluate(f"window.photos.live.positions[{nose} * 3 + 2]")

    # drag the nose tip further forward: the head is recalibrated once the drag ends (debounced)
    updates = counter(page, "liveUpdates")
    drag(page, point_at(page, "side", "9.3"), -10, 0)
    wait_counter(page, "liveUpdates", updates)
    wait_counter(page, "textures", 1)
    idle(page)
    assert counter(page, "liveUpdates") == updates + 1  # one recalibration for the whole drag
    z_after = page.evaluate(f"window.photos.live.positions[{nose} * 3 + 2]")
    assert z_after > z_before + 2.0, (z_before, z_after)
    shot(page, "06-recalibrated-after-drag")

    # export: the FDP (points, the front photo as texture, texture coordinates) and the baked texture
    g4 = api.get("/api/photos").json()["guess"]
    page.fill("[data-testid=export-name]", "me")
    page.click("[data-testid=export]")
    page.wait_for_selector("#exported li[data-file='me.texture.png']", timeout=60_000)
    assert page.locator("#exported").inner_text().split() == ["me.fdp", "me.texture.png"]
    shot(page, "07-exported")
    assert sorted(p.name for p in out.iterdir()) == ["me.fdp", "me.texture.png"]
    fdp = load_fdp(out / "me.fdp")
    labels = list(fdp.labels)
    assert len(labels) >= 60 and fdp.texture_coords is not None and len(fdp.textures) == 1
    assert Image.open(io.BytesIO(fdp.textures[0].data)).size == (PHOTO, PHOTO)
    front = page.evaluate("JSON.parse(JSON.stringify(window.photos.state.guess.front))")
    u, v = fdp.texture_coords[labels.index("2.1")]
    assert (u * PHOTO, (1 - v) * PHOTO) == pytest.approx(tuple(front["2.1"]), abs=1e-2)
    # against the same photos' points without the two point drags: the chin went down, the nose forward
    fitted = photos.guess(synth.mesh, {"front": (PHOTO, PHOTO), "side": (PHOTO, PHOTO)}, "left", g4["box"])
    undragged = {"front": dict(g4["front"], **{"2.1": fitted["front"]["2.1"]}),
                 "side": dict(g4["side"], **{"9.3": fitted["side"]["9.3"]})}
    base = points_from_photos(undragged["front"], undragged["side"], side_view="left")
    points = {k: np.asarray(p) for k, p in zip(labels, fdp.points)}
    assert points["2.1"][1] < base["2.1"][1] - 5  # (its x stayed where the drag left it: the texture coordinate)
    assert points["9.3"][2] > base["9.3"][2] + 5  # (y mixes both photos, scaled by the chin's height: not checked)
    texture = np.asarray(Image.open(out / "me.texture.png").convert("RGB"))
    assert texture.shape == (SIZE, SIZE, 3) and texture.std(axis=(0, 1)).min() > 10
    shown = Image.open(io.BytesIO(api.get("/api/texture-preview").content)).convert("RGB")
    assert np.array_equal(np.asarray(shown), texture)  # what the page previews is what was exported

    # loading the head again makes the calibration stale: the panel says so and export is off
    v = page.evaluate("window.editor.state.version")
    page.click("[data-testid=load-head]")
    page.wait_for_function(f"window.editor.state.version > {v}", timeout=15_000)
    page.wait_for_selector("#panel-photos[data-cleared='1']", state="attached", timeout=15_000)
    assert "mesh changed" in page.locator("[data-testid=photos-state]").inner_text()
    assert page.locator("[data-testid=export]").is_disabled()
    shot(page, "08-calibration-cleared")
    assert page.errors == [], page.errors
