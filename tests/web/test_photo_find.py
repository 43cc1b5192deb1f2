"""The editor's "Find the face" (POST /api/photos/find): the landmark model places the front photo's points."""
from __future__ import annotations

import io

import numpy as np
import pytest

pytest.importorskip("mediapipe", reason="the track extra (mediapipe) is not installed: tools/dev.sh test installs it")
skdata = pytest.importorskip("skimage.data", reason="scikit-image (test extra) gives the test photo")

from PIL import Image  # noqa: E402

from mpeg4fa.tracking import find_landmarks, photo_points  # noqa: E402
from web.test_photos import client, synth  # noqa: E402,F401  (fixtures)


def _png(image: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, format="PNG")
    return buffer.getvalue()


def test_find_the_face_places_the_front_points(client, synth):  # noqa: F811
    astronaut = skdata.astronaut()
    files = {"front": ("astronaut.png", _png(astronaut), "image/png"),
             "side": ("side.png", synth.png["side"], "image/png")}
    assert client.post("/api/photos", files=files, data={"side_view": "left"}).status_code == 200
    answer = client.post("/api/photos/find", json={"view": "front"})
    assert answer.status_code == 200, answer.text
    found, guess = answer.json()["found"], answer.json()["guess"]
    truth, _, _ = photo_points(find_landmarks(astronaut, "astronaut"))   # as an FDP from the photo has them
    assert len(found) == 59 and set(found) == set(guess["dragged"]["front"])
    for label in found:
        assert np.allclose(guess["front"][label], truth[label][:2], atol=0.05), label   # the editor's head: 0.02 px
    # the box moved onto her face, so the points not found (the ears' tops, the hairline) follow it
    x0, y0, x1, y1 = guess["box"]["front"]
    assert 140 < x0 < truth["3.6"][0] and truth["3.5"][0] < x1 < 330 and y1 > truth["2.1"][1]
    assert x0 < guess["front"]["10.2"][0] < truth["3.6"][0] and truth["3.5"][0] < guess["front"]["10.1"][0] < x1
    assert guess["front"]["11.1"][1] < truth["4.3"][1]
    # a box drag afterwards leaves the found points where they are
    box = [x0 - 10, y0, x1, y1]
    held = {"front": {label: guess["front"][label] for label in found}}     # what the page sends back
    moved = client.post("/api/photos/box", json={"view": "front", "box": box, "dragged": held})
    assert moved.status_code == 200
    assert moved.json()["guess"]["front"]["3.5"] == guess["front"]["3.5"]


def test_no_face_is_one_located_error(client, synth):  # noqa: F811
    files = {"front": ("coffee.png", _png(skdata.coffee()), "image/png"),
             "side": ("side.png", synth.png["side"], "image/png")}
    assert client.post("/api/photos", files=files, data={"side_view": "left"}).status_code == 200
    answer = client.post("/api/photos/find", json={"view": "front"})
    assert answer.status_code == 422 and "no face found" in answer.json()["error"]
    assert answer.json()["where"] == "front"
    assert client.post("/api/photos/find", json={"view": "top"}).status_code == 422
