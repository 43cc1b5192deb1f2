"""The editor page's upload of several files in a real browser (Playwright driving Debian's chromium): an OBJ
saved by the editor chosen together with its NAME.points.json and NAME.parts.json comes back with its parts and
feature points, as ``mpeg4fa edit NAME.obj`` reads it; a .gltf chosen without its buffer shows the error naming
the buffer. Screenshots go to ``test-artifacts/editor-upload/`` (ignored by git)."""
from __future__ import annotations

import json
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from e2e.browser import editor_page, free_port, fresh_folder, require_browser

ARTEFACTS = Path(__file__).resolve().parents[2] / "test-artifacts" / "editor-upload"
BACKGROUND = (0x2B, 0x2F, 0x36)

require_browser()  # skips the module, saying what to install, without playwright or chromium

import trimesh  # noqa: E402
import uvicorn  # noqa: E402
from PIL import Image  # noqa: E402

from mpeg4fa.web.app import create_app  # noqa: E402
from mpeg4fa.web.edits import clear_point, from_head  # noqa: E402
from mpeg4fa.web.files import read_model, save_model  # noqa: E402


@pytest.fixture
def base(tmp_path, procedural_face):
    port = free_port()
    config = uvicorn.Config(create_app(out_dir=tmp_path / "out", head=procedural_face), host="127.0.0.1",
                            port=port, log_level="warning", lifespan="off")
    srv = uvicorn.Server(config)
    thread = threading.Thread(target=srv.run, daemon=True)
    thread.start()
    deadline = time.monotonic() + 20
    while not srv.started:
        if time.monotonic() > deadline or not thread.is_alive():
            pytest.fail("uvicorn did not start")
        time.sleep(0.05)
    yield f"http://127.0.0.1:{port}"
    srv.should_exit = True
    thread.join(10)


def test_upload_an_obj_with_its_sidecars_and_a_gltf_without_its_buffer(base, tmp_path, procedural_face):
    mesh = from_head(procedural_face.mesh)
    for label in ("2.1", "9.3", "3.5"):  # a model of the user's, not the head as the page loads it
        mesh = clear_point(mesh, label)
    paths = save_model(mesh, tmp_path / "saved", "myhead", required_points=list(mesh.points))
    by_path = read_model(paths[0])
    assert len(by_path.part_names) > 1 and len(by_path.points) == 81

    fresh_folder(ARTEFACTS)
    with editor_page(base) as page:
        assert page.locator("#upload-file").get_attribute("multiple") is not None

        page.set_input_files("#upload-file", [str(q) for q in paths])
        page.wait_for_function("window.editor.state.model && window.editor.state.model.source === 'myhead.obj'",
                               timeout=15_000)
        page.wait_for_selector("body[data-busy='0']", state="attached", timeout=15_000)
        page.wait_for_timeout(200)
        shot = ARTEFACTS / "01-obj-with-sidecars.png"
        page.screenshot(path=str(shot))
        listed = page.eval_on_selector_all("#parts li", "items => items.map(li => li.dataset.part)")
        assert listed == list(by_path.part_names)
        assert page.locator("#fp-count").inner_text() == "81/84 placed"
        assert page.locator("#status").inner_text() == "loaded myhead.obj with 2 more files"
        assert page.evaluate("Object.keys(window.editor.state.model.points).length") == 81
        canvas = page.locator("#canvas").bounding_box()
        img = np.asarray(Image.open(shot).convert("RGB").crop(
            (int(canvas["x"]), int(canvas["y"]), int(canvas["x"] + canvas["width"]),
             int(canvas["y"] + canvas["height"]))), dtype=np.int16)
        assert (np.abs(img - BACKGROUND).sum(axis=2) > 30).mean() > 0.05, "WebGL drew nothing over the background"

        # a .gltf chosen without one of its buffers: one error naming it, the loaded model kept
        files = trimesh.creation.box().export(file_type="gltf")
        doc = json.loads(files["model.gltf"])
        (tmp_path / "box.gltf").write_text(json.dumps(doc))
        kept = [tmp_path / "box.gltf"]
        for buffer in doc["buffers"][:-1]:
            (tmp_path / buffer["uri"]).write_bytes(files[buffer["uri"]])
            kept.append(tmp_path / buffer["uri"])
        page.set_input_files("#upload-file", [str(q) for q in kept])
        page.wait_for_function("document.getElementById('status').dataset.kind === 'error'", timeout=15_000)
        page.screenshot(path=str(ARTEFACTS / "02-gltf-missing-buffer.png"))
        text = page.locator("#status").inner_text()
        assert doc["buffers"][-1]["uri"] in text and "box.gltf" in text, text
        assert page.evaluate("window.editor.state.model.source") == "myhead.obj"
        errors = page.errors
    assert not errors, errors
