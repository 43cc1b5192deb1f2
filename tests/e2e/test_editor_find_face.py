"""The editor's "Find the face" button in a real browser: the astronaut as the front photo, her points placed.

A user picks a front photo of a real face (scikit-image's astronaut) and a side photo, loads them, clicks
"Find the face": the 59 points the landmark model sees land on her face (drawn as put by hand), the box
moves onto her head so the others follow, and a drag still moves a point. Screenshots go to
``test-artifacts/editor-find-face/``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from e2e.browser import editor_page, fresh_folder, require_browser

require_browser()
pytest.importorskip("mediapipe", reason="the track extra (mediapipe) is not installed: tools/dev.sh test installs it")
skdata = pytest.importorskip("skimage.data", reason="scikit-image (test extra) gives the test photo")

from PIL import Image  # noqa: E402

from e2e.test_editor_photos import drag, guess, idle, point_at, server  # noqa: E402,F401  (server: fixture)
from mpeg4fa.tracking import find_landmarks, photo_points  # noqa: E402
from web.test_photos import Synthetic  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
ARTEFACTS = ROOT / "test-artifacts" / "editor-find-face"


@pytest.fixture(scope="module")
def page(server):  # noqa: F811
    fresh_folder(ARTEFACTS)
    with editor_page(server[0], height=860) as pg:
        pg.wait_for_selector("#panel-photos[data-ready='1']", state="attached", timeout=15_000)
        yield pg


def test_find_the_face_fills_the_front_points(server, page, procedural_face, tmp_path):  # noqa: F811
    astronaut = skdata.astronaut()
    front, side = tmp_path / "astronaut.png", tmp_path / "side.png"
    Image.fromarray(astronaut).save(front)
    side.write_bytes(Synthetic(procedural_face).png["side"])
    truth, _, _ = photo_points(find_landmarks(astronaut, "astronaut"))   # as an FDP from the photo has them

    page.click("[data-testid=photos-toggle]")
    page.wait_for_selector("#panel-photos[data-open='1'] .photos-body", state="visible")
    assert page.locator("[data-testid=photos-find]").is_disabled()          # nothing to look at yet
    page.set_input_files("[data-testid=photo-front]", str(front))
    page.set_input_files("[data-testid=photo-side]", str(side))
    page.click("[data-testid=photos-load]")
    page.wait_for_selector("#panel-photos[data-loaded='1']", state="attached", timeout=30_000)
    idle(page)
    before = guess(page)

    page.click("[data-testid=photos-find]")
    page.wait_for_function("Number(document.getElementById('panel-photos').dataset.finds || 0) > 0",
                           timeout=60_000)
    idle(page)
    page.wait_for_timeout(200)
    page.screenshot(path=str(ARTEFACTS / "01-face-found.png"))
    after = guess(page)
    assert len(after["dragged"]["front"]) == 59
    assert page.locator("#svg-front circle.fp.dragged").count() == 59
    for label in after["dragged"]["front"]:
        assert np.allclose(after["front"][label], truth[label][:2], atol=0.05), label   # the editor's head: 0.02 px
    assert after["box"]["front"] != before["box"]["front"] and after["side"] == before["side"]
    assert "face found: 59 points" in page.locator("[data-testid=status]").inner_text()

    # the user corrects a point by dragging, as before
    scale = page.evaluate("window.photos.scale('front')")
    drag(page, point_at(page, "front", "2.1"), 0, 8)
    moved = guess(page)
    assert moved["front"]["2.1"][1] - after["front"]["2.1"][1] == pytest.approx(8 * scale, abs=1.5)
    page.screenshot(path=str(ARTEFACTS / "02-chin-dragged.png"))
