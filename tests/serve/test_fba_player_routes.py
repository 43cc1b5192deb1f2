"""`mpeg4fa serve`'s FBA player routes: the page, fba.js, and the per-FAP head with its key."""
from __future__ import annotations

import numpy as np
import pytest
from fastapi.testclient import TestClient

from mpeg4fa.serve.app import create_app
from mpeg4fa.serve.fap_head import HEAD_ROTATION, samples
from serve.live_server import face_for_tests


@pytest.fixture(scope="module")
def client():
    return TestClient(create_app(face_for_tests()), base_url="http://127.0.0.1")


def test_player_page_and_decoder_are_served(client):
    r = client.get("/player", follow_redirects=False)
    assert r.status_code in (302, 307) and r.headers["location"] == "/static/fbaplayer.html"
    page = client.get("/static/fbaplayer.html")
    assert page.status_code == 200 and "js/fbaplayer.js" in page.text
    for path in ("js/fbaplayer.js", "js/fba/fba.js", "js/fba/shown.js", "js/fba/spec.js"):
        assert client.get(f"/static/{path}").status_code == 200, path


def test_fap_head_has_two_targets_per_fap(client):
    key = client.get("/static/fap-head.json").json()
    glb = client.get("/static/fap-head.glb")
    assert glb.status_code == 200 and glb.content[:4] == b"glTF"
    targets, at = key["targets"], key["at"]
    assert targets.count(None) == 1  # the rest pose
    made = {(f, v) for f, v in zip(targets, at) if f is not None}
    want = {(f, v) for f in range(3, 69) if f not in HEAD_ROTATION for v in samples(f)}
    assert made == want and len(made) == len(targets) - 1
    assert key["rotation"] == [48, 49, 50] and len(key["pivot"]) == 3
    rest = np.array(key["feature_points"]["rest"])
    assert rest.shape == (84, 3) and np.isfinite(rest).all()
