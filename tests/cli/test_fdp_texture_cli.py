"""`encode --fdp-out` from two photos, then `snapshot` / `play --fdp`: the skin wears the FDP's texture."""
import json

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.face import FaceModel
from mpeg4fa.fdp import Fdp, TextureImage, load_fdp, save_fdp
from mpeg4fa.formats import read_stream
from mpeg4fa.render import Renderer, frame_points, snapshot
from mpeg4fa.render.texture import uv_rasterise

pytestmark = pytest.mark.usefixtures("generic_head_installed")

PHOTO = 320


@pytest.fixture(scope="module")
def sent(tmp_path_factory):
    """A stream and the speaker's FDP, made by `encode` from an unlit front and left photo of a painted head."""
    folder = tmp_path_factory.mktemp("sender")
    face = FaceModel.default(auto_install=False)
    mesh = face.mesh
    p = uv_rasterise(mesh, 256).position.astype(float)
    paint = np.clip(np.stack([128 + 100 * np.sin(p[..., 1] / 14), 128 + 100 * np.cos(p[..., 2] / 12),
                              128 + 100 * np.sin((p[..., 0] + p[..., 1]) / 18)], -1), 0, 255).astype(np.uint8)
    for view, name in (("front", "front"), ("left", "side")):
        camera = frame_points(mesh.feature_points(), PHOTO, PHOTO, view=view, orthographic=True)
        with Renderer(face, width=PHOTO, height=PHOTO, camera=camera, texture=paint, lighting=False) as r:
            Image.fromarray(r.render(face.neutral())).save(folder / f"{name}.png")
        labels = [label for label in mesh.fp_labels if label != "11.5" and (view == "front" or mesh.fp(label)[0] >= 0)]
        xy = camera.project(np.array([mesh.fp(label) for label in labels]), PHOTO, PHOTO)[:, :2]
        (folder / f"{name}.json").write_text(json.dumps({label: xy[i].tolist() for i, label in enumerate(labels)}))
    return folder


def _encode(cli, folder):
    code, _, err = cli("encode", "Hello there", "-o", folder / "talk.fba", "--engine", "estimate",
                       "--fdp-out", folder / "face.fdp", "--front", folder / "front.png",
                       "--front-points", folder / "front.json", "--side", folder / "side.png",
                       "--side-points", folder / "side.json", "--side-view", "left")
    assert code == 0, err
    return folder / "talk.fba", folder / "face.fdp"


def _png(path) -> np.ndarray:
    return np.asarray(Image.open(path).convert("RGB"))


def test_snapshot_and_play_wear_the_fdp_texture(cli, sent, tmp_path):
    stream_path, fdp_path = _encode(cli, sent)
    code, _, err = cli("snapshot", stream_path, "--fdp", fdp_path, "--size", "128", "-o", tmp_path / "tex.png")
    assert code == 0, err
    assert "texture: front.png (320x320)" in err and "--no-fdp-texture" in err
    # the CLI renders what the API renders for the same FDP
    fdp = load_fdp(fdp_path)
    face = FaceModel.default(auto_install=False).calibrate(fdp)
    stream, _ = read_stream(stream_path)
    expected = snapshot(stream, face=face, fdp=fdp, width=128, height=128)
    textured = _png(tmp_path / "tex.png")
    assert np.array_equal(textured, expected)
    code, _, err = cli("snapshot", stream_path, "--fdp", fdp_path, "--size", "128", "--no-fdp-texture",
                       "-o", tmp_path / "plain.png")
    assert code == 0 and "texture:" not in err
    plain = _png(tmp_path / "plain.png")
    assert np.array_equal(plain, snapshot(stream, face=face, width=128, height=128))
    assert np.abs(textured.astype(int) - plain.astype(int)).max(axis=-1).mean() > 10.0
    # an explicit --texture wins
    Image.new("RGB", (32, 32), (200, 60, 40)).save(tmp_path / "red.png")
    code, _, err = cli("snapshot", stream_path, "--fdp", fdp_path, "--size", "128", "--texture", tmp_path / "red.png",
                       "-o", tmp_path / "red_snap.png")
    assert code == 0 and "texture:" not in err
    red = np.full((32, 32, 3), (200, 60, 40), np.uint8)
    assert np.array_equal(_png(tmp_path / "red_snap.png"), snapshot(stream, face=face, width=128, height=128,
                                                                      texture=red))
    # play's first frame is the snapshot's
    code, _, err = cli("play", stream_path, "--fdp", fdp_path, "--size", "128", "--no-audio", "-o", tmp_path / "frames")
    assert code == 0 and "texture: front.png" in err, err
    assert np.array_equal(_png(sorted((tmp_path / "frames").glob("*.png"))[0]), textured)


def test_bad_fdp_textures_are_one_line_errors(cli, sent, tmp_path):
    stream_path, fdp_path = _encode(cli, sent)
    fdp = load_fdp(fdp_path)
    save_fdp(Fdp(fdp.labels, fdp.points, textures=fdp.textures), tmp_path / "no_coords.fdp")
    code, _, err = cli("snapshot", stream_path, "--fdp", tmp_path / "no_coords.fdp", "-o", tmp_path / "a.png")
    assert code == 1 and len(err.strip().splitlines()) == 1, err
    assert "no_coords.fdp: texture 'front.png'" in err and "no texture coordinates" in err
    assert not (tmp_path / "a.png").exists()
    cut = TextureImage("front.png", "image/png", fdp.textures[0].data[:300])
    save_fdp(Fdp(fdp.labels, fdp.points, texture_coords=fdp.texture_coords, textures=(cut,)), tmp_path / "cut.fdp")
    code, _, err = cli("play", stream_path, "--fdp", tmp_path / "cut.fdp", "--no-audio", "-o", tmp_path / "f")
    assert code == 1 and len(err.strip().splitlines()) == 1 and "cut.fdp: texture 'front.png'" in err, err
    assert "cannot be decoded" in err and not (tmp_path / "f").exists()
    # the same FDP plays untextured on request
    code, _, err = cli("snapshot", stream_path, "--fdp", tmp_path / "cut.fdp", "--no-fdp-texture", "--size", "32",
                       "-o", tmp_path / "b.png")
    assert code == 0, err
