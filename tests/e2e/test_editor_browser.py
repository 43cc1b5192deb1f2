"""The editor page in a real browser (Playwright driving Debian's chromium, WebGL through SwiftShader).

The app runs with uvicorn in a thread on a free 127.0.0.1 port, posing through the procedural head,
saving into ``tmp_path``. One scenario walks the page as a user would: load the head, click a face and
delete it, box-select around the hole and fill it, grow a teeth face to its region and split it off,
place feature points by clicking the mesh, mirror, read the FAPU table, move a FAP slider, undo and
redo, select vertices (click, shift-click, Alt-box), drag them with the move gizmo and move them by
numbers, undo and redo the moves (buttons and keys), rename a part, save. Each step leaves a screenshot in ``test-artifacts/editor/`` (ignored by git).
Clicks go to screen positions computed with three's ``Vector3.project`` (``window.editor.screenOf*``);
only the teeth, which no click reaches inside the closed mouth, are selected through a hook.
"""
from __future__ import annotations

import json
import os
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from e2e.browser import editor_page, free_port, fresh_folder, require_browser

ARTEFACTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "editor"
BACKGROUND = (0x2B, 0x2F, 0x36)

require_browser()  # skips the module, saying what to install, without playwright or chromium

import httpx  # noqa: E402
import uvicorn  # noqa: E402
from PIL import Image  # noqa: E402

from mpeg4fa.web.app import create_app  # noqa: E402


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
    fresh_folder(ARTEFACTS)
    with editor_page(server[0]) as pg:
        yield pg


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

    fill_from_vertices(page, api)
    drag, moved = move_vertices(page, api)
    teeth_faces = rename_part(page, api)

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
    parts = json.loads((out / "edited.parts.json").read_text())["parts"]
    assert "upper_teeth" in parts and "teeth" not in parts and parts["upper_teeth"] == teeth_faces
    assert len(points.get("points", points)) == 84
    # the OBJ holds the dragged vertices where the drag left them, the cheek point among them
    v_obj = np.array([[float(x) for x in line.split()[1:4]] for line in obj if line.startswith("v ")])
    assert np.allclose(v_obj, np.reshape(final["positions"], (-1, 3)), atol=1e-5)
    assert np.allclose(v_obj[moved], drag["after"][moved], atol=1e-5)
    cheek = points.get("points", points)["5.3"]
    assert cheek in moved and np.allclose(v_obj[cheek] - drag["before"][cheek], drag["delta"], atol=1e-5)
    assert page.errors == [], page.errors


def positions(api) -> np.ndarray:
    return np.reshape(model(api)["positions"], (-1, 3))


def fill_from_vertices(page, api) -> None:
    """Delete a face on the right cheek with the Delete key, then click the hole's three corners in
    Vertices mode and fill that boundary loop."""
    m = model(api)
    t0 = m["counts"]["triangles"]
    xy = page.evaluate(f"window.editor.screenOfVertex({m['points']['5.4']})")
    x, y = xy["x"] + 10, xy["y"] + 8
    face = page.evaluate(f"window.editor.pickAt({x}, {y})")["face"]
    corners = m["indices"][face * 3:face * 3 + 3]
    page.mouse.click(x, y)
    assert page.evaluate("[...window.editor.state.selected]") == [face]
    v = version(page)
    page.keyboard.press("Delete")
    settle(page, v)
    m = model(api)
    assert m["counts"]["triangles"] == t0 - 1 and m["counts"]["vertices"] == len(m["positions"]) // 3
    page.click("#btn-mode-vertices")
    for k, c in enumerate(corners):  # the hole's corners keep their numbers: no vertex went with the face
        s = page.evaluate(f"window.editor.screenOfVertex({c})")
        if k:
            page.keyboard.down("Shift")
        page.mouse.click(s["x"], s["y"])
        page.keyboard.up("Shift")
    assert sorted(page.evaluate("[...window.editor.state.vertices]")) == sorted(corners)
    shot(page, "13-hole-corners-selected")
    click_and_settle(page, "#btn-fill-hole")
    m = model(api)
    assert m["counts"]["triangles"] == t0 and "fill hole: done" in status(page)[1]
    new = m["indices"][-3:]
    assert sorted(new) == sorted(corners)
    page.click("#btn-mode-faces")


def move_vertices(page, api):
    """Vertices mode: click, shift-click, grow and Alt-box vertices around the cheek point 5.3; drag them
    up with the gizmo's Y arrow and across with its centre (real mouse events), move them along x by
    typing a centre, undo and redo. Returns the Y drag ({before, after, delta}) and the moved vertices,
    for the checks on the saved files."""
    page.click("#btn-mode-vertices")
    assert page.locator("#sel-count").get_attribute("data-mode") == "vertices"
    assert page.evaluate("window.editor.view.dots.visible")
    m = model(api)
    pos0 = positions(api)
    cheek = model(api)["points"]["5.3"]
    xy = page.evaluate(f"window.editor.screenOfVertex({cheek})")
    x, y = xy["x"], xy["y"]
    hit = page.evaluate(f"window.editor.pickAt({x}, {y})")["vertex"]
    page.mouse.click(x, y)
    assert page.evaluate("[...window.editor.state.vertices]") == [hit]
    assert np.linalg.norm(pos0[hit] - pos0[cheek]) < 6.0
    other = page.evaluate(f"window.editor.pickAt({x - 30}, {y})")["vertex"]
    assert other != hit
    page.keyboard.down("Shift")
    page.mouse.click(x - 30, y)
    page.keyboard.up("Shift")
    assert sorted(page.evaluate("[...window.editor.state.vertices]")) == sorted([hit, other])
    assert page.locator("#sel-count").get_attribute("data-count") == "2"
    shot(page, "14-vertices-clicked")

    # grow within the part: the corners of the connected skin faces around the first vertex that uses them
    page.check("#grow-same-part")
    page.click("#btn-grow")
    tris = np.reshape(m["indices"], (-1, 3))
    seeds = sorted({int(np.flatnonzero((tris == u).any(axis=1))[0]) for u in (hit, other)})
    region = set()
    for f in seeds:
        region |= set(api.post("/api/region", json={"face": f, "same_part": True}).json()["faces"])
    want = sorted(set(tris[sorted(region)].ravel().tolist()))
    page.wait_for_function(f"window.editor.state.vertices.size === {len(want)}", timeout=10_000)
    assert sorted(page.evaluate("[...window.editor.state.vertices]")) == want
    page.uncheck("#grow-same-part")

    half = 28
    page.keyboard.down("Alt")
    page.mouse.move(x - half, y - half)
    page.mouse.down()
    page.mouse.move(x + half, y + half, steps=6)
    page.mouse.up()
    page.keyboard.up("Alt")
    chosen = sorted(page.evaluate("[...window.editor.state.vertices]"))
    assert len(chosen) > 4 and cheek in chosen
    # each one projects inside the box and is what three's own raycast meets first there (not hidden)
    seen = page.evaluate("(vs) => vs.map((v) => { const s = window.editor.screenOfVertex(v);"
                         " const h = window.editor.pickAt(s.x, s.y); return [s.x, s.y, h ? h.point : null]; })", chosen)
    size = np.linalg.norm(pos0.max(axis=0) - pos0.min(axis=0))
    for v, (sx, sy, point) in zip(chosen, seen):
        assert abs(sx - x) <= half + 0.5 and abs(sy - y) <= half + 0.5
        assert point is not None and np.linalg.norm(np.subtract(point, pos0[v])) < 2e-3 * size, v
    assert page.evaluate("window.editor.view.selectedDots.geometry.attributes.position.count") == len(chosen)
    shot(page, "15-vertices-box-selected")

    # the gizmo on the selection's centre; drag its Y arrow 40 px up
    page.click("#btn-move-mode")
    assert page.locator("#btn-move-mode").get_attribute("aria-pressed") == "true"
    centre = pos0[chosen].mean(axis=0)
    shown = [float(page.locator(f"#move-{a}").input_value()) for a in "xyz"]
    assert np.allclose(shown, centre, atol=1e-3)
    assert np.allclose(page.evaluate("window.editor.view.pivot.position.toArray()"), centre, atol=1e-6)
    shot(page, "16-move-gizmo")
    handle = page.evaluate("window.editor.screenOfGizmoHandle('Y', 0.45)")
    page.mouse.move(handle["x"], handle["y"])
    assert page.evaluate("window.editor.view.gizmo.axis") == "Y", "the Y arrow is not under the pointer"
    cam = np.array(page.evaluate("window.editor.view.camera.position.toArray()"))
    target = np.array(page.evaluate("window.editor.view.controls.target.toArray()"))
    fov = page.evaluate("window.editor.view.camera.fov")
    height = page.locator("#canvas").bounding_box()["height"]
    forward = (target - cam) / np.linalg.norm(target - cam)
    per_pixel = 2 * np.dot(centre - cam, forward) * np.tan(np.radians(fov) / 2) / height
    lift = 40
    v = version(page)
    page.mouse.down()
    page.mouse.move(handle["x"], handle["y"] - lift / 2, steps=4)
    page.mouse.move(handle["x"], handle["y"] - lift, steps=4)
    preview = np.reshape(page.evaluate("Array.from(window.editor.view.positions)"), (-1, 3))
    assert preview[cheek][1] > pos0[cheek][1]  # the shown mesh follows the drag before the release
    shot(page, "17-dragging")
    page.mouse.up()
    settle(page, v)
    pos1 = positions(api)
    delta = pos1[chosen] - pos0[chosen]
    assert np.allclose(delta, delta[0], atol=1e-5), "the selection moved as one"
    dx, dy, dz = delta[0]
    # along y only (the arrow's axis), by the 40 px at the selection's depth (the gizmo's drag plane
    # is turned to face the eye only about y, hence the tolerance)
    assert abs(dx) < 1e-5 and abs(dz) < 1e-5 and dy > 0
    assert dy == pytest.approx(lift * per_pixel, rel=0.1), (dy, lift * per_pixel)
    others = np.setdiff1d(np.arange(len(pos0)), chosen)
    assert np.array_equal(pos1[others], pos0[others])
    assert "dragged: moved" in status(page)[1]
    assert sorted(page.evaluate("[...window.editor.state.vertices]")) == chosen  # the selection stays
    shot(page, "18-dragged")

    # the gizmo's centre moves in the view plane: 30 px right and 20 px down
    c1 = pos1[chosen].mean(axis=0)
    at = page.evaluate("window.editor.view.gizmoHandle('X', 0)")
    page.mouse.move(at["x"], at["y"])
    assert page.evaluate("window.editor.view.gizmo.axis") == "XYZ", "the gizmo's centre is not under the pointer"
    v = version(page)
    page.mouse.down()
    page.mouse.move(at["x"] + 15, at["y"] + 10, steps=4)
    page.mouse.move(at["x"] + 30, at["y"] + 20, steps=4)
    page.mouse.up()
    settle(page, v)
    pos_c = positions(api)
    d = pos_c[chosen] - pos1[chosen]
    assert np.allclose(d, d[0], atol=1e-5) and np.array_equal(pos_c[others], pos1[others])
    per_pixel1 = 2 * np.dot(c1 - cam, forward) * np.tan(np.radians(fov) / 2) / height
    assert d[0][0] == pytest.approx(30 * per_pixel1, rel=0.1) and d[0][1] == pytest.approx(-20 * per_pixel1, rel=0.1)
    assert abs(d[0][2]) < 0.1 * np.linalg.norm(d[0][:2])  # the view plane faces the camera (looking along -z)
    v = version(page)
    page.keyboard.press("Control+z")
    settle(page, v)
    assert np.allclose(positions(api), pos1, atol=1e-6)

    # numeric: type the centre's new x; y and z stay as shown, so only x moves
    assert float(page.locator("#move-y").input_value()) == pytest.approx(c1[1], abs=1e-3)
    page.fill("#move-x", f"{c1[0] + 2.5:.6f}")
    click_and_settle(page, "#btn-move-to")
    pos2 = positions(api)
    assert np.allclose(pos2[chosen] - pos1[chosen], [2.5, 0, 0], atol=1e-5)
    assert np.array_equal(pos2[others], pos1[others])
    shot(page, "19-numeric-move")

    # undo the numeric move (button), the drag (Ctrl+Z); redo the drag (Ctrl+Y)
    click_and_settle(page, "#btn-undo")
    assert np.allclose(positions(api), pos1, atol=1e-6)
    shot(page, "20-move-undone")
    for key, want in (("Control+z", pos0), ("Control+y", pos1)):
        v = version(page)
        page.keyboard.press(key)
        settle(page, v)
        assert np.allclose(positions(api), want, atol=1e-6), key
    page.click("#btn-move-mode")
    page.click("#btn-mode-faces")
    assert page.evaluate("window.editor.view.gizmo.object") is None
    return {"before": pos0, "after": pos1, "delta": np.array([dx, dy, dz])}, chosen


def part_faces(m: dict, name: str) -> list[int]:
    i = m["parts"].index(name)
    return [f for f, p in enumerate(m["triangle_parts"]) if p == i]


def rename_part(page, api) -> list[int]:
    """Rename the split-off teeth through the part list's controls (a bad name is refused); returns the
    part's faces, which the rename keeps."""
    faces = part_faces(model(api), "teeth")
    page.select_option("#part-select", "teeth")
    page.fill("#rename-to", "Upper Teeth")
    page.click("#btn-rename-part")
    page.wait_for_selector("#status[data-kind='error']", timeout=10_000)
    assert "bad part name" in status(page)[1]
    page.fill("#rename-to", "upper_teeth")
    click_and_settle(page, "#btn-rename-part")
    m = model(api)
    assert "upper_teeth" in m["parts"] and "teeth" not in m["parts"]
    assert part_faces(m, "upper_teeth") == faces
    assert page.locator("#parts li[data-part='upper_teeth']").count() == 1
    assert page.locator("#parts li[data-part='teeth']").count() == 0
    assert page.locator("#part-select").input_value() == "upper_teeth"
    shot(page, "21-part-renamed")
    return faces


def test_static_files_and_errors_are_served(server):
    _, _, api = server
    assert api.get("/static/vendor/three/three.module.js").status_code == 200
    assert api.get("/static/js/editor.js").headers["content-type"].startswith(("text/javascript", "application/javascript"))
    r = api.get("/static/nope.js")
    assert r.status_code == 404 and set(r.json()) == {"error", "where"}
