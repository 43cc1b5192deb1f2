"""`mpeg4fa texture` on the generic head (skips when it is not built)."""
import json

import numpy as np
import pytest
from PIL import Image

from mpeg4fa.face import FaceModel
from mpeg4fa.render import Materials, Renderer, frame_points

pytestmark = pytest.mark.usefixtures("generic_head_installed")



@pytest.fixture
def front_photo(tmp_path):
    """An unlit orthographic front view of the head in one known colour, and its feature points."""
    face = FaceModel.default(auto_install=False)
    fps = face.mesh.feature_points()
    camera = frame_points(fps, 200, 240, orthographic=True)
    colour = Materials().with_colours(skin=(0.2, 0.4, 0.8), lips=(0.2, 0.4, 0.8))
    with Renderer(face, width=200, height=240, camera=camera, lighting=False, materials=colour) as r:
        image = r.render(face.neutral())
    xy = camera.project(fps, 200, 240)[:, :2]
    points = {label: xy[i].tolist() for i, label in enumerate(face.mesh.fp_labels) if label[0] in "2389"}
    Image.fromarray(image).save(tmp_path / "front.png")
    (tmp_path / "front.json").write_text(json.dumps(points))
    return tmp_path / "front.png", tmp_path / "front.json"


def test_texture_bakes_and_previews(cli, tmp_path, front_photo):
    photo, points = front_photo
    code, out, err = cli("texture", photo, "--points", points, "--size", "256", "-o", tmp_path / "skin.png",
                         "--preview", tmp_path / "preview.png")
    assert code == 0, err
    skin = np.asarray(Image.open(tmp_path / "skin.png"))
    assert skin.shape == (256, 256, 3)
    # most of the texture carries the photo's colour (unlit 0.2, 0.4, 0.8)
    close = (np.abs(skin.astype(int) - (51, 102, 204)).max(axis=2) <= 6).mean()
    assert close > 0.5, close
    assert Image.open(tmp_path / "preview.png").size == (768, 384)
    assert "alignment residual" in err and "of the skin seen" in out


def test_texture_errors(cli, tmp_path, front_photo):
    photo, points = front_photo
    bad = tmp_path / "bad.json"
    bad.write_text('{"3.5": [1, 2],\n  "3.6": [3, }')
    code, _, err = cli("texture", photo, "--points", bad, "-o", tmp_path / "s.png")
    assert code == 1 and "bad.json:2:" in err
    code, _, err = cli("texture", photo, "--points", points, "--side", photo, "-o", tmp_path / "s.png")
    assert code == 2 and "--side-points" in err  # a usage clash: exit 2 like argparse
    code, _, err = cli("texture", tmp_path / "none.png", "--points", points, "-o", tmp_path / "s.png")
    assert code == 1 and "none.png" in err
    tiny = tmp_path / "tiny.png"  # fuzz of 2026-12-07: "photo: the photo is only 1x1 pixels", not its file
    Image.fromarray(np.zeros((1, 1, 3), np.uint8)).save(tiny)
    code, _, err = cli("texture", photo, "--points", points, "--side", tiny, "--side-points", points,
                       "-o", tmp_path / "s.png")
    assert code == 1 and f"{tiny}: the photo is only 1x1 pixels" in err and not (tmp_path / "s.png").exists()
