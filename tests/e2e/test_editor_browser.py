"""The editor page in a real browser (Playwright driving Debian's chromium, WebGL through SwiftShader).

The app runs with uvicorn in a thread on a free 127.0.0.1 port, posing through the procedural head,
saving into ``tmp_path``. One scenario walks the page as a user would: load the head, click a face and
delete it, box-select around the hole and fill it, grow a teeth face to its region and split it off,
place feature points by clicking the mesh, mirror, read the FAPU table, move a FAP slider, undo and
redo, save. Each step leaves a screenshot in ``test-artifacts/editor/`` (ignored by git).
Clicks go to screen positions computed with three's ``Vector3.project`` (``window.editor.screenOf*``);
only the teeth, which no click reaches inside the closed mouth, are selected through a hook.
"""
from __future__ import annotations

import json
import os
import shutil
import socket
import threading
import time
from pathlib import Path

import numpy as np
import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
        "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run"]
ARTEFACTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "editor"
BACKGROUND = (0x2B, 0x2F, 0x36)

sync_api = pytest.importorskip("playwright.sync_api", reason="playwright not installed (pip install playwright==1.65.2)")
if not os.access(CHROMIUM, os.X_OK):
    pytest.skip(f"{CHROMIUM} not found: install Debian's chromium (apt-get install chromium)", allow_module_level=True)

import httpx  # noqa: E402
import uvicorn  # noqa: E402
from PIL import Image  # noqa: E402

from mpeg4fa.web.app import create_app  # noqa: E402


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def server(tmp_path_factory, procedural_face):
    out = tmp_path_factory.mktemp("editor-out")
    port = free_port()
    config = uvicorn.Config(create_app(out_dir=out, head=procedural_face), host="127.0.0.1", port=port,
                            log_level="warning", lifespan="off")
    srv = uvicorn.Server(config)
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not srv.started:
        if time.monotonic() > deadline or not thread.is_alive():
            pytest.fail("uvicorn did not start")
        time.sleep(0.05)
    base = f"http://127.0.0.1:{port}"
    yield base, out, httpx.Client(base_url=base, timeout=30)
    srv.should_exit = True
    thread.join(10)


@pytest.fixture(scope="module")
def page(server):
    if ARTEFACTS.exists():
        shutil.rmtree(ARTEFACTS)
    ARTEFACTS.mkdir(parents=True)
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        pg = browser.new_page(viewport={"width": 1280, "height": 820})
        errors: list[str] = []
        pg.on("pageerror", lambda e: errors.append(str(e)))
        # the 400s the scenario provokes are logged by chromium as failed loads: only script faults count
        pg.on("console", lambda m: errors.append(m.text)
              if m.type == "error" and not m.text.startswith("Failed to load resource") else None)
        pg.goto(server[0] + "/")
        pg.wait_for_selector("body[data-ready='1']", timeout=15_000)
        pg.errors = errors
        yield pg
        browser.close()


def shot(page, name: str) -> Path:
    page.wait_for_timeout(150)  # the next animation frame has drawn
    path = ARTEFACTS / f"{name}.png"
    page.screenshot(path=str(path))
    return path


def settle(page, version_before: int) -> None:
    """Wait for the model to be shown again after an edit and every request to finish."""
    page.wait_for_function(f"window.editor.state.version > {version_before}", timeout=15_000)
    page.wait_for_selector("body[data-busy='0']", state="attached", timeout=15_000)


def version(page) -> int:
    return page.evaluate("window.editor.state.version")


def click_and_settle(page, selector: str) -> None:
    v = version(page)
    page.click(selector)
    settle(page, v)


def status(page) -> tuple[str, str]:
    el = page.locator("#status")
    return el.get_attribute("data-kind") or "", el.inner_text()


def model(api) -> dict:
    r = api.get("/api/model")
    assert r.status_code == 200, r.text
    return r.json()


def drawn_fraction(path: Path, box) -> float:
    img = np.asarray(Image.open(path).convert("RGB").crop(box), dtype=np.int16)
    return float((np.abs(img - BACKGROUND).sum(axis=2) > 30).mean())


def canvas_box(page):
    b = page.locator("#canvas").bounding_box()
    return (int(b["x"]), int(b["y"]), int(b["x"] + b["width"]), int(b["y"] + b["height"]))


def test_a_user_edits_the_head(server, page):
    _, out, api = server
    assert "no model loaded" in status(page)[1]
    click_and_settle(page, "#btn-load-head")
    m0 = model(api)
    t0 = m0["counts"]["triangles"]
    assert page.locator("#counts").inner_text().startswith(f"{m0['counts']['vertices']} vertices, {t0} faces")
    path = shot(page, "01-loaded")
    assert drawn_fraction(path, canvas_box(page)) > 0.05, "WebGL drew nothing over the background"

    # click a face on the cheek (a real click where the raycast finds it) and delete it
    cheek = m0["points"]["5.3"]
    xy = page.evaluate(f"window.editor.screenOfVertex({cheek})")
    x, y = xy["x"] - 12, xy["y"] + 6
    face = page.evaluate(f"window.editor.pickAt({x}, {y})")["face"]
    page.mouse.click(x, y)
    assert page.evaluate("[...window.editor.state.selected]") == [face]
    assert page.locator("#sel-count").get_attribute("data-count") == "1"
    shot(page, "02-face-selected")
    click_and_settle(page, "#btn-delete-faces")
    assert model(api)["counts"]["triangles"] == t0 - 1
    shot(page, "03-face-deleted")

    # box select (Alt-drag) around the hole and fill its boundary loop
    page.keyboard.down("Alt")
    page.mouse.move(x - 30, y - 30)
    page.mouse.down()
    page.mouse.move(x, y, steps=4)
    page.mouse.move(x + 30, y + 30, steps=4)
    shot(page, "04-box-dragging")
    page.mouse.up()
    page.keyboard.up("Alt")
    n_box = int(page.locator("#sel-count").get_attribute("data-count"))
    assert n_box > 4
    shot(page, "05-box-selected")
    click_and_settle(page, "#btn-fill-hole")
    assert model(api)["counts"]["triangles"] == t0
    assert "fill hole: done" in status(page)[1]

    # the teeth: no click reaches inside the closed mouth, so one teeth face is selected through the hook
    m = model(api)
    upper = m["parts"].index("teeth_upper")
    seed = m["triangle_parts"].index(upper)
    page.evaluate(f"window.editor.selectFaces([{seed}])")
    page.click("#btn-grow")
    region = api.post("/api/region", json={"face": seed}).json()["faces"]
    page.wait_for_function(f"window.editor.state.selected.size === {len(region)}", timeout=10_000)
    page.fill("#part-name", "teeth")
    click_and_settle(page, "#btn-split")
    m = model(api)
    assert "teeth" in m["parts"]
    teeth = m["parts"].index("teeth")
    assert sorted(i for i, p in enumerate(m["triangle_parts"]) if p == teeth) == sorted(region)
    assert page.locator("#parts li[data-part='teeth']").count() == 1

    # a bad part name: the server's error and where it happened show in the status bar
    page.evaluate(f"window.editor.selectFaces([{seed}])")
    page.fill("#part-name", "Bad Name")
    page.click("#btn-split")
    page.wait_for_selector("#status[data-kind='error']", timeout=10_000)
    assert "bad part name" in status(page)[1] and "/api/edit" in status(page)[1]
    shot(page, "06-error-in-status-bar")
    page.click("#btn-clear-sel")

    # feature points: clear 2.1 and place it again by clicking the chin; clear 5.4 and mirror it from 5.3
    chin = m["points"]["2.1"]
    page.click("#fp-2-1")
    click_and_settle(page, "#btn-fp-clear")
    assert "2.1" not in model(api)["points"]
    xy = page.evaluate(f"window.editor.screenOfVertex({chin})")
    v = version(page)
    page.mouse.click(xy["x"], xy["y"])
    settle(page, v)
    shot(page, "07-point-placed-by-click")
    m = model(api)
    pos = np.reshape(m["positions"], (-1, 3))
    assert "2.1" in m["points"] and np.linalg.norm(pos[m["points"]["2.1"]] - pos[chin]) < 6.0
    page.click("#fp-2-1")  # disarm
    page.click("#fp-9-3")
    nose = m["points"]["9.3"]
    xy = page.evaluate(f"window.editor.screenOfVertex({nose})")
    v = version(page)
    page.mouse.click(xy["x"], xy["y"])
    settle(page, v)
    m = model(api)
    pos = np.reshape(m["positions"], (-1, 3))
    assert np.linalg.norm(pos[m["points"]["9.3"]] - pos[nose]) < 6.0
    page.click("#fp-9-3")
    page.click("#fp-5-4")
    click_and_settle(page, "#btn-fp-clear")
    assert "5.4" not in model(api)["points"]
    page.click("#fp-5-4")
    click_and_settle(page, "#btn-mirror")
    m = model(api)
    pos = np.reshape(m["positions"], (-1, 3))
    assert "5.4" in m["points"] and len(m["points"]) == 84
    a, b = pos[m["points"]["5.3"]], pos[m["points"]["5.4"]]
    assert abs(a[0] + b[0]) < 6.0 and abs(a[1] - b[1]) < 6.0  # mirrored across x = 0 (the head's midline)
    page.wait_for_function(f"document.getElementById('fapu-table').dataset.version === '{version(page)}'")
    fapu = {k: float(page.locator(f"#fapu-{k}").inner_text()) for k in ("IRISD0", "ES0", "ENS0", "MNS0", "MW0")}
    assert fapu == pytest.approx(api.get("/api/fapu").json()["fapu"], abs=1e-3) and min(fapu.values()) > 0
    shot(page, "08-points-mirrored")

    # try: open the jaw with FAP 3 and see the shown positions move
    neutral = np.array(page.evaluate("Array.from(window.editor.view.positions)"))
    pv = page.evaluate("window.editor.state.poseVersion")
    page.fill("#fap-3", "800")
    page.wait_for_function(f"window.editor.state.poseVersion > {pv}", timeout=20_000)
    posed = np.reshape(page.evaluate("Array.from(window.editor.view.positions)"), (-1, 3))
    chin_now = m["points"]["2.1"]
    assert np.linalg.norm(posed[chin_now] - neutral.reshape(-1, 3)[chin_now]) > 1.0
    assert page.locator("#fap-3-value").inner_text() == "800"
    shot(page, "09-jaw-open")
    pv = page.evaluate("window.editor.state.poseVersion")
    page.select_option("#viseme", "AA")
    page.wait_for_function(f"window.editor.state.poseVersion > {pv}", timeout=20_000)
    shot(page, "10-viseme-AA")
    pv = page.evaluate("window.editor.state.poseVersion")
    page.click("#btn-pose-reset")
    page.wait_for_function(f"window.editor.state.poseVersion > {pv}", timeout=20_000)
    assert np.allclose(page.evaluate("Array.from(window.editor.view.positions)"), neutral, atol=1e-3)

    # orbit with a real drag, then frame the model again
    before = page.evaluate("window.editor.view.camera.position.toArray()")
    box = page.locator("#canvas").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(cx, cy)
    page.mouse.down()
    page.mouse.move(cx - 220, cy - 40, steps=8)
    page.mouse.up()
    after = page.evaluate("window.editor.view.camera.position.toArray()")
    assert np.linalg.norm(np.subtract(after, before)) > 10
    shot(page, "11-orbited")
    page.click("#btn-frame")

    # undo the mirror, redo it
    click_and_settle(page, "#btn-undo")
    assert "5.4" not in model(api)["points"]
    click_and_settle(page, "#btn-redo")
    assert "5.4" in model(api)["points"]
    assert page.locator("#btn-redo").is_disabled() and not page.locator("#btn-undo").is_disabled()

    # save: validated, then written into the out folder
    page.fill("#save-name", "edited")
    page.click("#btn-save")
    page.wait_for_selector("#saved:has-text('edited.obj')", timeout=15_000)
    assert page.locator("#problems").get_attribute("data-count") == "0"
    shot(page, "12-saved")
    assert sorted(os.listdir(out)) == ["edited.obj", "edited.parts.json", "edited.points.json"]
    final = model(api)
    obj = (out / "edited.obj").read_text().splitlines()
    assert sum(line.startswith("f ") for line in obj) == final["counts"]["triangles"] == t0
    assert sum(line.startswith("v ") for line in obj) == final["counts"]["vertices"]
    points = json.loads((out / "edited.points.json").read_text())
    assert "teeth" in json.loads((out / "edited.parts.json").read_text())["parts"]
    assert len(points.get("points", points)) == 84
    assert page.errors == [], page.errors


def test_static_files_and_errors_are_served(server):
    _, _, api = server
    assert api.get("/static/vendor/three/three.module.js").status_code == 200
    assert api.get("/static/js/editor.js").headers["content-type"].startswith(("text/javascript", "application/javascript"))
    r = api.get("/static/nope.js")
    assert r.status_code == 404 and set(r.json()) == {"error", "where"}
