"""`mpeg4fa serve`'s FBA player routes: the page, fba.js, and the head with its key (the face engine's rig)."""
from __future__ import annotations

import numpy as np
import pytest
from fastapi.testclient import TestClient

from mpeg4fa.export.gltf import ALBEDO_SIZE
from mpeg4fa.serve.app import create_app
from mpeg4fa.serve.fap_head import RIG_VERSION
from serve.live_server import face_for_tests


@pytest.fixture(scope="module")
def client():
    return TestClient(create_app(face_for_tests()), base_url="http://127.0.0.1")


def test_player_page_and_decoder_are_served(client):
    r = client.get("/player", follow_redirects=False)
    assert r.status_code in (302, 307) and r.headers["location"] == "/static/fbaplayer.html"
    page = client.get("/static/fbaplayer.html")
    assert page.status_code == 200 and "js/fbaplayer.js" in page.text
    for path in ("js/fbaplayer.js", "js/head.js", "js/facerig.js", "js/fba/fba.js", "js/fba/shown.js", "js/fba/spec.js"):
        assert client.get(f"/static/{path}").status_code == 200, path


def test_fap_head_carries_the_rig_of_the_face(client):
    face = face_for_tests()
    key = client.get("/static/fap-head.json").json()
    glb = client.get("/static/fap-head.glb")
    assert glb.status_code == 200 and glb.content[:4] == b"glTF"
    rig = key["rig"]
    assert rig["version"] == RIG_VERSION and rig["n_vertices"] == len(face.mesh.vertices)
    assert np.array_equal(np.reshape(rig["rest"], (-1, 3)), face.mesh.vertices)
    # every GL vertex of every part is a vertex of the face's mesh, and every drawn part is there
    sources = np.concatenate([np.asarray(v) for v in key["parts"].values()])
    assert sources.min() >= 0 and sources.max() < rig["n_vertices"]
    assert {"skin", "eye_l", "eye_r"} <= set(key["parts"])
    # the FAP -> feature point map is the rig's, entry for entry (FAPU x direction applied in Python)
    t = rig["translate"]
    dense = np.zeros_like(face.rig.translate)
    dense[t["rows"], np.asarray(t["faps"]) - 1] = t["values"]
    assert np.array_equal(dense, face.rig.translate)
    rest = np.array(key["feature_points"]["rest"])
    assert rest.shape == (84, 3) and np.isfinite(rest).all()


def test_a_bad_fdp_upload_is_one_located_error(client):
    r = client.post("/api/head?name=photo.fdp", content=b"\xff\xd8\xff\xe0" + bytes(60))
    assert r.status_code == 400
    answer = r.json()
    assert answer["where"].startswith("photo.fdp") and "not an FDP file" in answer["error"] and "JPEG" in answer["error"]
    r = client.post("/api/head?name=empty.fdp", content=b"")
    assert r.status_code == 400 and "empty" in r.json()["error"]
    assert client.get("/api/head/0123456789abcdef.glb").status_code == 404
    assert client.get("/api/head/0123456789abcdef.json").json()["error"].startswith("no such head")


def test_the_key_names_the_faces_own_deformer():
    """The pages pose with the feature-point deformer; a face served with another one says so (the page shows it)."""
    face = face_for_tests().with_deformer("muscle")
    key = TestClient(create_app(face), base_url="http://127.0.0.1").get("/static/fap-head.json").json()
    assert key["deformer"] == "muscle" and key["rig"]["version"] == RIG_VERSION


def test_a_served_texture_is_in_the_pages_head():
    """``serve --fdp`` passes the FDP's texture: the head the pages load carries it (a PNG in the GLB)."""
    import pygltflib

    image = np.zeros((64, 64, 3), np.uint8)
    image[..., 1] = 200
    glb = TestClient(create_app(face_for_tests(), texture=image), base_url="http://127.0.0.1").get("/static/fap-head.glb")
    gltf = pygltflib.GLTF2.load_from_bytes(glb.content)
    assert [i.name for i in gltf.images] == ["head", "eye", "teeth"] and gltf.images[0].mimeType == "image/png"
    assert _png_size(gltf) == (64, 64)
    plain = TestClient(create_app(face_for_tests()), base_url="http://127.0.0.1").get("/static/fap-head.glb")
    plain_gltf = pygltflib.GLTF2.load_from_bytes(plain.content)  # without one: the skin's own colours, baked
    # the lash strands: on the plain head only
    assert [i.name for i in plain_gltf.images] == ["head", "eye", "teeth", "lashes"]
    assert _png_size(plain_gltf) == (ALBEDO_SIZE, ALBEDO_SIZE)
    # the pages grow the GLB's lash cards by the key's layout; the photo head has its own lashes and no layout
    textured_key = TestClient(create_app(face_for_tests(), texture=image),
                              base_url="http://127.0.0.1").get("/static/fap-head.json").json()
    plain_key = TestClient(create_app(face_for_tests()), base_url="http://127.0.0.1").get("/static/fap-head.json").json()
    assert textured_key["lashes"] is None and len(plain_key["lashes"]["roots"]) == len(plain_key["lashes"]["rows"]) > 0


def _png_size(gltf) -> tuple[int, int]:
    import io

    from PIL import Image

    view = gltf.bufferViews[gltf.images[0].bufferView]
    blob = gltf.binary_blob()
    return Image.open(io.BytesIO(blob[view.byteOffset or 0:(view.byteOffset or 0) + view.byteLength])).size
