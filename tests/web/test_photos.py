"""Photo calibration through the editor's API, on synthetic photos of the procedural head.

As in tests/render/test_texture.py, the "photos" are orthographic front and left renders of the
head wearing a known colour field, so every feature point's true pixel position is the camera's
projection of the head's own point: dragging the guessed points there must calibrate the head
back onto itself, and the baked texture must return the colour field.
"""
import asyncio
import io

import httpx
import numpy as np
import pytest
from PIL import Image

from mpeg4fa.fdp import load_fdp
from mpeg4fa.render.camera import frame_points
from mpeg4fa.render.renderer import Renderer
from mpeg4fa.render.texture import uv_rasterise
from mpeg4fa.web import photos
from mpeg4fa.web.app import create_app
from web.local import LOCAL

PHOTO = 320
SIZE = 512  # the preview's texture size (photos.bake's default)


def field(p: np.ndarray) -> np.ndarray:
    """Smooth colours of 3D points, symmetric in x (the side photo is mirrored onto the far half)."""
    x, y, z = p[..., 0], p[..., 1], p[..., 2]
    r = 128 + 100 * np.sin(2 * np.pi * y / 90) * np.cos(2 * np.pi * x / 110)
    g = 128 + 100 * np.cos(2 * np.pi * z / 80 + 0.5)
    b = 128 + 100 * np.sin(2 * np.pi * (y + z) / 120)
    return np.clip(np.stack([r, g, b], -1), 0, 255)


class Synthetic:
    def __init__(self, face) -> None:
        self.face, self.mesh = face, face.mesh
        self.raster = uv_rasterise(self.mesh, SIZE)
        self.truth = np.rint(field(self.raster.position.astype(float))).astype(np.uint8)
        self.cameras = {v: frame_points(self.mesh.feature_points(), PHOTO, PHOTO, view=v, orthographic=True)
                        for v in ("front", "left")}
        self.png = {}
        for key, view in (("front", "front"), ("side", "left")):
            with Renderer(face, width=PHOTO, height=PHOTO, camera=self.cameras[view], texture=self.truth,
                          lighting=False) as r:
                image = r.render(face.neutral())
            buf = io.BytesIO()
            Image.fromarray(image).save(buf, format="PNG")
            self.png[key] = buf.getvalue()

    def true_points(self, key: str, labels) -> dict:
        cam = self.cameras["front" if key == "front" else "left"]
        xy = cam.project(np.array([self.mesh.fp(k) for k in labels]), PHOTO, PHOTO)[:, :2]
        return {k: [float(x), float(y)] for k, (x, y) in zip(labels, xy)}


@pytest.fixture(scope="module")
def synth(procedural_face):
    return Synthetic(procedural_face)


class MainThreadClient:
    """Requests served on this (the main) thread's event loop, as uvicorn serves them: the texture bake's GL
    context belongs to the thread that made it (the fixture's renders made it here), and TestClient would
    run the async routes on a thread of its own."""

    def __init__(self, app, out) -> None:
        self.app, self.out = app, out

    def request(self, method: str, url: str, **kw) -> httpx.Response:
        async def go():
            async with httpx.AsyncClient(transport=httpx.ASGITransport(app=self.app), base_url=LOCAL) as c:
                return await c.request(method, url, **kw)
        return asyncio.run(go())

    def get(self, url, **kw):
        return self.request("GET", url, **kw)

    def post(self, url, **kw):
        return self.request("POST", url, **kw)


@pytest.fixture
def client(tmp_path, procedural_face, synth):
    out = tmp_path / "out"
    out.mkdir()
    return MainThreadClient(create_app(out_dir=out, head=procedural_face, upload_limit=2_000_000), out)


def post_photos(client, synth, front=None, side=None):
    files = {"front": ("front.png", front or synth.png["front"], "image/png"),
             "side": ("side.png", side or synth.png["side"], "image/png")}
    return client.post("/api/photos", files=files, data={"side_view": "left"})


def test_calibrate_on_the_true_points_recovers_the_head(client, synth):
    assert client.post("/api/load", json={"source": "head"}).status_code == 200
    r = post_photos(client, synth)
    assert r.status_code == 200, r.text
    body = r.json()
    assert body["front"]["size"] == [PHOTO, PHOTO] and body["side"]["size"] == [PHOTO, PHOTO]
    guess = body["guess"]
    assert set(guess["front"]) == set(synth.mesh.fp_labels)
    assert "3.6" in guess["front"] and "3.6" not in guess["side"] and "3.5" in guess["side"]  # the left half
    front = synth.true_points("front", guess["front"])
    side = synth.true_points("side", guess["side"])
    # on a plain background the first box is around the head's silhouette: the points start near their places
    for key, truth, worst in (("front", front, 0.5), ("side", side, 2.5)):  # measured 0.26 and 1.65 px
        off = [np.hypot(*np.subtract(truth[k], guess[key][k])) for k in truth]
        assert max(off) < worst, (key, np.median(off), max(off))
    r = client.post("/api/calibrate", json={"front": front, "side": side, "method": "dffd"})
    assert r.status_code == 200, r.text
    out = r.json()
    head = synth.mesh
    positions = np.reshape(out["positions"], (-1, 3))
    assert positions.shape == head.vertices.shape
    height = float(np.ptp(head.vertices[head.part("skin")][:, 1]))
    err = max(np.linalg.norm(np.subtract(p, head.fp(k))) for k, p in out["points"].items())
    assert err < 1e-6 * height, err      # the calibrated feature points are the head's own (1e-13 mm)
    assert np.abs(positions - head.vertices).max() < 1e-5 * height
    assert out["report"]["points"] >= 60 and out["report"]["max_point_error_mm"] < 1e-6 * height

    # a dragged nose tip moves the calibrated nose: 10 side pixels forward (toward the image's left)
    px_per_mm = (PHOTO / 2) / (1.0 / synth.cameras["left"].projection[1, 1])
    side["9.3"] = [side["9.3"][0] - 10.0, side["9.3"][1]]
    tip = np.array(client.post("/api/calibrate", json={"front": front, "side": side, "method": "rbf"})
                   .json()["points"]["9.3"])
    assert tip[2] - head.fp("9.3")[2] == pytest.approx(10.0 / px_per_mm, rel=0.05)  # 8.20 vs 8.35 mm

    # the baked preview returns the colour field where the photos see the skin
    client.post("/api/calibrate", json={"front": front, "side": synth.true_points("side", guess["side"])})
    r = client.get("/api/texture-preview")
    assert r.status_code == 200 and r.headers["content-type"] == "image/png"
    baked = np.asarray(Image.open(io.BytesIO(r.content)).convert("RGB")).astype(int)
    assert baked.shape == (SIZE, SIZE, 3)
    diff = np.abs(baked - synth.truth.astype(int)).max(axis=-1)[synth.raster.skin]
    assert np.median(diff) <= 2 and np.percentile(diff, 75) <= 4, (np.median(diff), np.percentile(diff, 75))  # 1, 2

    r = client.post("/api/export", json={"name": "me"})
    assert r.status_code == 200, r.text
    assert sorted(p.name for p in client.out.iterdir()) == ["me.fdp", "me.texture.png"]
    fdp = load_fdp(client.out / "me.fdp")
    assert len(fdp.labels) >= 60 and fdp.texture_coords is not None and len(fdp.textures) == 1
    assert Image.open(io.BytesIO(fdp.textures[0].data)).size == (PHOTO, PHOTO)
    u, v = fdp.texture_coords[list(fdp.labels).index("9.3")]
    assert (u * PHOTO, (1 - v) * PHOTO) == pytest.approx(tuple(front["9.3"]), abs=1e-3)
    assert Image.open(client.out / "me.texture.png").size == (SIZE, SIZE)


def test_box_refit_moves_the_points(client, synth):
    guess = post_photos(client, synth).json()["guess"]
    x0, y0, x1, y1 = guess["box"]["side"]
    r = client.post("/api/photos/box", json={"view": "side", "box": [x0 + 20, y0 + 10, x1 + 20, y1 + 10]})
    assert r.status_code == 200, r.text
    new = r.json()["guess"]
    assert new["front"] == guess["front"]
    shift = np.array([np.subtract(new["side"][k], guess["side"][k]) for k in guess["side"]])
    assert np.allclose(shift, [20, 10], atol=1e-2)
    x0, y0, x1, y1 = guess["box"]["front"]
    r = client.post("/api/photos/box", json={"view": "front", "box": [x0, y0, x0 + (x1 - x0) / 2, y1]})
    half = r.json()["guess"]["front"]
    k1, k2 = "3.5", "3.6"
    assert abs(half[k1][0] - half[k2][0]) == pytest.approx(abs(guess["front"][k1][0] - guess["front"][k2][0]) / 2,
                                                          abs=1e-2)


def test_first_box_without_a_plain_background_is_centred(client, synth):
    noise = np.random.default_rng(7).integers(0, 256, (240, 300, 3), dtype=np.uint8)
    buf = io.BytesIO()
    Image.fromarray(noise).save(buf, format="PNG")
    r = post_photos(client, synth, front=buf.getvalue())
    assert r.status_code == 200, r.text
    x0, y0, x1, y1 = r.json()["guess"]["box"]["front"]
    assert y1 - y0 == pytest.approx(photos.BOX_HEIGHT * 240) and (x0 + x1) / 2 == pytest.approx(150)
    _, outline = photos.head_outline(synth.mesh, "front")
    assert photos.silhouette_box(noise, outline) is None
    plain = np.zeros((100, 100, 3), np.uint8)
    assert photos.silhouette_box(plain, outline) is None  # nothing on it
    plain[30:, 40:60] = 200  # a head cut by the bottom: its box follows the head's aspect ratio
    assert photos.silhouette_box(plain, outline) == pytest.approx(
        [40, 30, 60, 30 + 20 * (outline[3] - outline[1]) / (outline[2] - outline[0])])
    plain[0:, 40:60] = 200  # touching the top: not a head seen whole
    assert photos.silhouette_box(plain, outline) is None


def test_pure_functions_fit_the_box(procedural_face):
    points, outline = photos.head_outline(procedural_face.mesh, "front")
    fitted = photos.fit_to_box(points, outline, [10, 20, 110, 220])
    xy = np.array(list(fitted.values()))
    assert xy[:, 0].min() >= 10 - 1e-6 and xy[:, 0].max() <= 110 + 1e-6 and xy[:, 1].max() <= 220 + 1e-6
    assert fitted["9.3"][1] > fitted["4.1"][1]  # y grows downward: the nose below the brows


@pytest.mark.parametrize("route,payload", [
    ("/api/photos/box", {"view": "front", "box": [0, 0, 10, 10]}),
    ("/api/calibrate", {"front": {"9.3": [1, 2]}, "side": {"9.3": [1, 2]}}),
])
def test_missing_photos(client, route, payload):
    client.post("/api/load", json={"source": "head"})
    r = client.post(route, json=payload)
    assert r.status_code == 422 and "POST /api/photos first" in r.json()["error"], r.text
    assert set(r.json()) == {"error", "where"}


def test_bad_input(client, synth):
    r = post_photos(client, synth, front=b"not an image")
    assert r.status_code == 422 and r.json()["where"] == "front", r.text
    r = client.post("/api/photos", files={"front": ("f.png", synth.png["front"], "image/png")})
    assert r.status_code == 422 and r.json()["where"] == "side"
    assert client.get("/api/texture-preview").status_code == 422
    assert post_photos(client, synth).status_code == 200
    assert client.get("/api/texture-preview").json()["where"] == "calibrate"
    r = client.post("/api/photos/box", json={"view": "front", "box": [50, 50, 10, 10]})
    assert r.status_code == 422 and r.json()["where"] == "box"
    r = client.post("/api/photos/box", json={"view": "top", "box": [0, 0, 10, 10]})
    assert r.status_code == 422 and r.json()["where"] == "view"
    client.post("/api/load", json={"source": "head"})
    r = client.post("/api/calibrate", json={"front": {"9.3": [1, 2]}, "side": {}, "method": "magic"})
    assert r.status_code == 422 and r.json()["where"] == "method"
    r = client.post("/api/calibrate", json={"front": {"99.9": [1, 2]}, "side": {"9.3": [1, 2]}})
    assert r.status_code == 422 and "99.9" in r.json()["error"]
    r = client.post("/api/calibrate", json={"front": {"9.3": [1, 2]}, "side": {"9.3": [1, 2]}})
    assert r.status_code == 422 and set(r.json()) == {"error", "where"}  # too few points to match the scales
    r = client.post("/api/export", json={"name": "../evil"})
    assert r.status_code == 422
    import trimesh
    obj = trimesh.exchange.obj.export_obj(trimesh.creation.icosphere(1), include_normals=False,
                                          include_texture=False).encode()
    client.post("/api/upload", files={"file": ("ball.obj", obj, "text/plain")})
    r = client.post("/api/calibrate", json={"front": {"9.3": [1, 2]}, "side": {"9.3": [1, 2]}})
    assert r.status_code == 422 and "head only" in r.json()["error"], r.text
    big = client.post("/api/photos", files={"front": ("f.png", b"\0" * 2_100_000, "image/png"),
                                            "side": ("s.png", synth.png["side"], "image/png")})
    assert big.status_code == 413


def test_dragged_points_stay_when_the_box_moves(client, synth):
    guess = post_photos(client, synth).json()["guess"]
    assert guess["dragged"] == {"front": [], "side": []}
    x0, y0, x1, y1 = guess["box"]["front"]
    put = [guess["front"]["9.3"][0] + 7.5, guess["front"]["9.3"][1] - 4.0]
    r = client.post("/api/photos/box", json={"view": "front", "box": [x0 + 12, y0, x1 + 12, y1],
                                             "dragged": {"front": {"9.3": put}, "side": {"9.3": [40.0, 150.0]}}})
    assert r.status_code == 200, r.text
    new = r.json()["guess"]
    assert new["front"]["9.3"] == put and new["dragged"] == {"front": ["9.3"], "side": ["9.3"]}
    assert new["side"]["9.3"] == [40.0, 150.0]  # a refit of one view keeps the other view's dragged points too
    others = [k for k in guess["front"] if k != "9.3"]
    assert np.allclose([np.subtract(new["front"][k], guess["front"][k]) for k in others], [12, 0], atol=1e-2)
    assert new["side"] == dict(guess["side"], **{"9.3": [40.0, 150.0]})
    # the server remembers the dragged points: a later refit (of either view) without them keeps them
    x0, y0, x1, y1 = new["box"]["front"]
    again = client.post("/api/photos/box", json={"view": "front", "box": [x0, y0 - 9, x1, y1 - 9]}).json()["guess"]
    assert again["front"]["9.3"] == put and again["front"]["2.1"][1] == pytest.approx(new["front"]["2.1"][1] - 9, abs=1e-2)
    sx0, sy0, sx1, sy1 = again["box"]["side"]
    side = client.post("/api/photos/box", json={"view": "side", "box": [sx0 - 5, sy0, sx1 - 5, sy1]}).json()["guess"]
    assert side["front"]["9.3"] == put
    assert client.get("/api/photos").json()["guess"] == side
    # an empty set lets the point follow the box again
    free = client.post("/api/photos/box", json={"view": "front", "box": again["box"]["front"],
                                                    "dragged": {"front": {}}})
    assert free.json()["guess"]["front"]["9.3"] == pytest.approx([guess["front"]["9.3"][0] + 12,
                                                                  guess["front"]["9.3"][1] - 9], abs=1e-2)
    # only labels the photo shows can be dragged (the side photo shows the face's left half)
    r = client.post("/api/photos/box", json={"view": "side", "box": side["box"]["side"],
                                             "dragged": {"side": {"3.6": [1, 2]}}})
    assert r.status_code == 422 and r.json()["where"] == "side" and "3.6" in r.json()["error"], r.text
    assert client.get("/api/photos").json()["guess"]["dragged"]["side"] == ["9.3"]  # a refused request changes nothing


def calibrate_true(client, synth, guess):
    front = synth.true_points("front", guess["front"])
    side = synth.true_points("side", guess["side"])
    r = client.post("/api/calibrate", json={"front": front, "side": side, "method": "dffd"})
    assert r.status_code == 200, r.text
    return r.json()


def test_a_mesh_change_clears_the_calibration(client, synth):
    assert client.get("/api/photos").json() == {"loaded": False, "calibrated": False, "cleared": None}
    client.post("/api/load", json={"source": "head"})
    guess = post_photos(client, synth).json()["guess"]
    state = client.get("/api/photos").json()
    assert state["loaded"] and not state["calibrated"] and state["cleared"] is None
    out = calibrate_true(client, synth, guess)
    head = synth.mesh
    n_skin = len(head.triangles["skin"])
    assert len(out["skin"]["indices"]) == 3 * n_skin and len(out["skin"]["uvs"]) == 6 * n_skin
    n_other = sum(len(t) for name, t in head.triangles.items() if name != "skin")
    assert len(out["other_indices"]) == 3 * n_other
    assert client.get("/api/photos").json()["calibrated"] is True

    # an edit: the calibration is gone, and the API says why
    model = client.get("/api/model").json()
    skin = model["parts"].index("skin")
    first_skin_face = model["triangle_parts"].index(skin)
    assert client.post("/api/edit", json={"edit": {"op": "delete_faces", "faces": [first_skin_face]}}).status_code == 200
    state = client.get("/api/photos").json()
    assert state["calibrated"] is False and "mesh changed" in state["cleared"]
    for r in (client.get("/api/texture-preview"), client.post("/api/export", json={"name": "stale"})):
        assert r.status_code == 422 and "calibration was cleared" in r.json()["error"], r.text
    assert list(client.out.iterdir()) == []
    out = calibrate_true(client, synth, guess)  # on the edited mesh: the deleted face has no texture to show
    assert len(out["skin"]["indices"]) == 3 * (n_skin - 1)
    assert client.get("/api/photos").json() | {"guess": None} == {
        **client.get("/api/photos").json(), "calibrated": True, "cleared": None, "guess": None}

    # a load (even of the same head) and an upload clear it too
    client.post("/api/load", json={"source": "head"})
    assert "mesh changed" in client.get("/api/photos").json()["cleared"]
    calibrate_true(client, synth, guess)
    import trimesh
    obj = trimesh.exchange.obj.export_obj(trimesh.creation.icosphere(1), include_normals=False,
                                          include_texture=False).encode()
    assert client.post("/api/upload", files={"file": ("ball.obj", obj, "text/plain")}).status_code == 200
    r = client.post("/api/export", json={"name": "stale"})
    assert r.status_code == 422 and r.json()["where"] == "calibrate" and "calibrate again" in r.json()["error"]
    # new photos start afresh: nothing calibrated, nothing cleared
    post_photos(client, synth)
    assert client.get("/api/photos").json()["cleared"] is None


def test_bytes_that_are_no_image_name_no_python_object():
    """Fuzz of 2026-12-07: the answer quoted Pillow's "cannot identify image file <_io.BytesIO object at 0x...>"."""
    from mpeg4fa.web.edits import EditError
    from mpeg4fa.web.photos import decode_photo

    with pytest.raises(EditError) as caught:
        decode_photo(b"this is text, not a photo" * 4, "front")
    assert "no image format" in str(caught.value) and "BytesIO" not in str(caught.value) and "0x" not in str(caught.value)
