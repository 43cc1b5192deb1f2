"""One photo -> FDP: the closed loop on a rendered head, the `mpeg4fa fdp` command, and bad photos."""
from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from conftest import require_generic
from mpeg4fa.fdp import load_fdp
from mpeg4fa.fdp.build import fdp_from_front
from mpeg4fa.fdp.model import FdpValueError
from mpeg4fa.tracking import SEEN_LABELS, feature_points, find_landmarks, photo_points


@pytest.fixture(scope="module")
def made(astronaut):
    require_generic()
    from mpeg4fa.tracking.photo import fdp_from_photo
    return fdp_from_photo(astronaut, where="astronaut.png")


@pytest.fixture(scope="module")
def textured(made):
    from mpeg4fa.tracking.photo import textured_head
    return textured_head(made)


def _loop_errors(made, textured, view):
    """Per feature point: |found in the render - the head's own point projected| over the face's width, in %."""
    from mpeg4fa.render import Renderer

    face, texture = textured
    with Renderer(face, width=512, height=512, samples=4, view=view, texture=texture) as renderer:
        frame = renderer.render(face.neutral())
        camera = renderer.camera
    labels = list(made.fdp.labels)
    true = camera.project(np.array([face.mesh.fp(label) for label in labels]), 512, 512)[:, :2]
    ears = camera.project(np.array([face.mesh.fp("10.7"), face.mesh.fp("10.8")]), 512, 512)
    width = float(np.ptp(ears[:, 0]))                  # the face's width at the ear lobes
    found, _, _ = photo_points(find_landmarks(frame, "render"))   # where the FDP puts them on the render
    return {label: float(np.linalg.norm(found[label] - true[i])) / width * 100 for i, label in enumerate(labels)}


@pytest.mark.parametrize("view", ["front", (15.0, 0.0)], ids=["front", "yaw15"])
def test_points_found_on_a_rendered_head_where_they_are(made, textured, view):
    """The head calibrated to the astronaut wears her photo (the FDP's texture, baked as a receiver does);
    rendered, its face is found again and each point the FDP would send lies where the head's own point
    projects. The issue's bar (every point within 3 % of the face's width, median under 1.5 %) holds from the
    front, and turned 15 degrees within 3.5 % (the FDP closes and levels her smiling lips, the neutral face's,
    while the texture keeps the photo's lips: measured front median 1.0 %, max 2.9 %; 15 degrees median 1.3 %,
    max 3.4 %; the table's own points, as this measured before the inner lip midpoints slid to the head's share of
    their contour: 0.9 / 2.8 and 1.3 / 5.1 %, and before the lips were levelled 1.0 / 2.7 and 1.2 / 3.6 %)."""
    errors = _loop_errors(made, textured, view)
    assert len(errors) == len(SEEN_LABELS)
    worst = max(errors, key=errors.get)
    assert errors[worst] < (3.0 if view == "front" else 3.5), (worst, errors[worst])
    assert np.median(list(errors.values())) < 1.5


def test_fdp_is_upright_frontal_and_textured(made):
    fdp = made.fdp
    assert set(fdp.labels) == set(SEEN_LABELS) and len(fdp.textures) == 1
    p = dict(zip(fdp.labels, fdp.points))
    # the head's frame: mm, +x the face's left, +y up, +z out of the face
    assert p["3.5"][0] > p["3.6"][0] and p["3.5"][1] > p["9.3"][1] > p["2.1"][1] and p["9.3"][2] > p["3.5"][2]
    assert 50 < p["3.5"][0] - p["3.6"][0] < 80                          # pupils a human distance apart (mm)
    assert abs(p["3.5"][1] - p["3.6"][1]) < 3 and abs(p["8.3"][1] - p["8.4"][1]) < 3   # no roll left
    uv = dict(zip(fdp.labels, fdp.texture_coords))
    assert np.allclose(uv["3.5"] * [512, 512], [made.pixels["3.5"][0], 512 - made.pixels["3.5"][1]])


def test_fdp_from_front_checks_its_points():
    points = {"3.5": (30, 0, 0), "3.6": (-30, 0, 0), "2.1": (0, -80, 10)}
    pixels = {"3.5": (140, 100), "3.6": (100, 100), "2.1": (120, 180)}
    fdp = fdp_from_front(points, pixels, front_size=(240, 240))
    assert fdp.labels == ("2.1", "3.5", "3.6") and fdp.texture_coords is not None
    with pytest.raises(FdpValueError, match="wrong way across"):
        fdp_from_front(points, {**pixels, "3.5": (100, 100), "3.6": (140, 100)}, front_size=(240, 240))
    with pytest.raises(FdpValueError, match="same labels"):
        fdp_from_front(points, {"3.5": (140, 100)})


# ---- the command ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def photos(tmp_path_factory, astronaut):
    from skimage import data
    folder = tmp_path_factory.mktemp("photos")
    Image.fromarray(astronaut).save(folder / "astronaut.jpg", quality=92)
    Image.fromarray(data.coffee()).save(folder / "coffee.png")
    return folder


def test_fdp_command_end_to_end(cli, photos, tmp_path):
    require_generic()
    out, check = tmp_path / "me.fdp", tmp_path / "check.png"
    code, stdout, stderr = cli("fdp", photos / "astronaut.jpg", "-o", out, "--preview", check)
    assert code == 0, stderr
    assert "warning" not in stderr and "W0000" not in stderr and "INFO" not in stderr
    fdp = load_fdp(out)
    assert len(fdp.labels) == 59 and fdp.textures[0].media_type == "image/jpeg"
    preview = np.asarray(Image.open(check))
    assert preview.shape[0] == 384 and preview.shape[1] > 3 * 300
    # the three-quarter head (last panel) is textured skin, not the background, at its middle
    assert preview[192, -192].astype(int).sum() > preview[5, -5].astype(int).sum() + 100
    # she smiles with her lips apart: said, with the figures, and what the FDP makes of it
    assert "1.4" in stderr.split("mm per pixel")[0][-8:]                  # ~63 mm between the pupils, 43 px
    assert "the lips are 10 mm apart in the photo; closed in the FDP" in stderr
    assert "the lip corners sit 7 mm over the line of the lips in the photo (a smile); level in the FDP" in stderr


def test_a_neutral_face_gets_no_note_and_a_smile_does():
    """The notes come from the face as found, against the head's own: the generic head rendered at rest gives none
    (its corners read up to 1 mm high), at joy 63 it smiles with its lips apart."""
    require_generic()
    from mpeg4fa.face import FaceModel
    from mpeg4fa.render import Renderer
    from mpeg4fa.spec.profiles import EXPRESSION_PROFILES
    from mpeg4fa.tracking.photo import fdp_from_photo

    face = FaceModel.default()
    joy = np.asarray(EXPRESSION_PROFILES["joy"], float).copy()
    joy[:2] = 0
    with Renderer(face, width=512, height=512, samples=4, view="front") as r:
        assert fdp_from_photo(r.render(face.neutral()), texture=False).notes == ()
        notes = fdp_from_photo(r.render(face.pose_values(joy)), texture=False).notes
    assert len(notes) == 2 and "apart" in notes[0] and "(a smile)" in notes[1], notes


def test_no_face_is_one_line_and_nothing_written(cli, photos, tmp_path):
    out = tmp_path / "coffee.fdp"
    code, stdout, stderr = cli("fdp", photos / "coffee.png", "-o", out, "--preview", tmp_path / "c.png")
    assert code == 1 and stdout == ""
    assert stderr.count("\n") == 1 and "coffee.png: no face found in the photo" in stderr
    assert list(tmp_path.iterdir()) == []


def test_a_given_point_far_off_the_photo_names_its_file(cli, photos, tmp_path):
    """A --points file with a point a billion pixels off: one line naming the file (it named only "points/3.5"),
    exit 1, nothing written."""
    require_generic()
    given = tmp_path / "far.json"
    given.write_text('{"3.5": [1e9, 5]}')
    code, stdout, stderr = cli("fdp", photos / "astronaut.jpg", "--points", given, "-o", tmp_path / "far.fdp")
    assert code == 1 and stdout == "" and stderr.count("\n") == 1
    assert f"{given}: feature point 3.5" in stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["far.json"]


def test_not_a_photo_is_one_line(cli, tmp_path):
    bad = tmp_path / "notes.jpg"
    bad.write_text("not an image")
    code, _, stderr = cli("fdp", bad, "-o", tmp_path / "x.fdp")
    assert code == 1 and stderr.count("\n") == 1 and "notes.jpg" in stderr
    assert not (tmp_path / "x.fdp").exists()


def test_background_takes_the_persons_nearest_colours():
    from mpeg4fa.tracking.segment import extend_person
    image = np.zeros((40, 40, 3), np.uint8)
    image[:, :20] = (200, 150, 120)             # the person on the left half, a blue wall on the right
    image[:, 20:] = (0, 0, 255)
    mask = np.zeros((40, 40), bool)
    mask[:, :20] = True
    out = extend_person(image, mask)
    assert (out == (200, 150, 120)).all(axis=2).all()
    assert extend_person(image, np.zeros((40, 40), bool)) is image     # no person: the photo as it is


def test_sent_texture_has_no_wall_beside_the_face(made):
    """The FDP's texture: the grey studio wall beside the astronaut's head is painted with her own colours."""
    from mpeg4fa.render.fdp_texture import decode_texture
    sent = decode_texture(made.fdp.textures[0])
    wall = sent[40:60, 440:500].reshape(-1, 3).astype(int)           # the grey wall, top right of the photo
    assert made.image[40:60, 440:500].std(axis=(0, 1)).max() < 25    # a plain wall (a soft gradient)
    assert np.abs(wall.mean(axis=0) - made.image[40:60, 440:500].reshape(-1, 3).mean(axis=0)).max() > 30


def test_sent_texture_has_no_teeth_or_eyes_of_its_own(made):
    """The astronaut smiles with her teeth showing: the sent texture paints the open mouth and the eye
    openings over from the skin around them, so a receiver's closed lips and lids wear no teeth or eyes."""
    import cv2

    from mpeg4fa.render.fdp_texture import decode_texture
    from mpeg4fa.tracking.landmarks import OPENING_RINGS

    sent = decode_texture(made.fdp.textures[0])
    for ring, bright_before in (("mouth", 0.2), ("eye_left", 0.1), ("eye_right", 0.1)):
        inside = np.zeros(sent.shape[:2], np.uint8)
        cv2.fillPoly(inside, [np.rint(made.landmarks.points[list(OPENING_RINGS[ring]), :2]).astype(np.int32)], 1)
        inside = inside.astype(bool)
        def white(image):  # teeth and eye whites: bright and grey, where skin, however bright, is rosy
            rgb = image[inside].astype(int)
            return float(((rgb.min(axis=1) > 150) & (rgb.max(axis=1) - rgb.min(axis=1) < 40)).mean())
        assert white(made.image) > bright_before, ring          # the photo shows them...
        assert white(sent) < 0.02, ring                          # ...the texture does not


def test_fdp_lips_are_in_contact_though_the_photo_smiles(made):
    """The neutral face's lips touch: the astronaut's open smile gives inner lip points as far apart as the
    generic head's own pairs (under 1.1 mm), not her 4+ mm gap, so the head at rest shows no teeth."""
    from mpeg4fa.face import FaceModel
    from mpeg4fa.tracking.neutral_face import INNER_LIP_PAIRS

    head = FaceModel.default().feature_points()
    found = feature_points(made.landmarks)
    for upper, lower in INNER_LIP_PAIRS:
        assert (found[lower][1] - found[upper][1]) * made.scale > 3.0         # apart in the photo (y down), mm
        gap = made.points[upper][1] - made.points[lower][1]
        assert gap == pytest.approx(max(head[upper][1] - head[lower][1], 0.0), abs=1e-9)


def _corner_heights(points) -> dict[str, float]:
    """Each lip corner's height over the line of the lips at the midline (mm, y up)."""
    line = (points["2.2"][1] + points["2.3"][1]) / 2.0
    return {label: float(points[label][1] - line) for label in ("8.3", "8.4", "2.4", "2.5")}


def test_fdp_lips_are_level_though_the_photo_smiles(made):
    """In the neutral face the line of the lips is horizontal at the corners' height (item 7): the astronaut's
    corners sit 7.5-10.8 mm over the line of her lips in the photo (6.6-8.0 mm once her pose is taken out); the
    FDP's within 0.5 mm of where the generic head's own sit over its line (0.5 mm; measured 0.14-0.33), so a head
    calibrated to her does not smile in every expression."""
    from mpeg4fa.face import FaceModel

    head = _corner_heights(FaceModel.default().feature_points())
    found = feature_points(made.landmarks)
    photo = {k: -v * made.scale for k, v in _corner_heights({k: p[:2] for k, p in found.items()}).items()}
    assert min(photo.values()) > 5.0                                  # raised in the photo (y down there)
    sent = _corner_heights(made.points)
    assert max(abs(sent[k] - head[k]) for k in head) < 0.5, sent


def test_a_smile_rendered_gives_the_heads_neutral_lips(made, textured):
    """Closed loop: the head calibrated to the astronaut, smiling (joy at 63) in a front render, gives an FDP
    whose lip corners sit over the line of the lips as the head's own neutral ones do, within 0.5 mm (measured
    0.08-0.21; 5.5-7.4 mm with the corners taken as found)."""
    from mpeg4fa.render import Renderer
    from mpeg4fa.spec.profiles import EXPRESSION_PROFILES
    from mpeg4fa.tracking.photo import fdp_from_photo

    face, texture = textured
    values = np.asarray(EXPRESSION_PROFILES["joy"], float).copy()
    values[:2] = 0
    with Renderer(face, width=512, height=512, samples=4, view="front", texture=texture) as renderer:
        frame = renderer.render(face.pose_values(values))
    got = _corner_heights(fdp_from_photo(frame, where="render", texture=False).points)
    own = _corner_heights(face.feature_points())
    assert max(abs(got[k] - own[k]) for k in own) < 0.5, (got, own)


def test_a_photo_taken_in_a_blink_gives_a_head_with_open_eyes():
    """The neutral face's lids are tangent to the iris, their opening IRISD0 (item 5): a photo taken in a blink
    (the generic head rendered with both upper lids shut) gave an FDP that no head could be calibrated to (IRISD0
    <= 0, "feature points out of order", in fdp --preview, say --photo and play --fdp alike). Each shut eye now opens
    to the head's own opening, said once per eye, and the head made from it blinks."""
    require_generic()
    from mpeg4fa.face import FaceModel
    from mpeg4fa.render import Renderer
    from mpeg4fa.tracking.photo import fdp_from_photo

    face = FaceModel.default()
    blink = np.zeros(68)
    blink[18] = blink[19] = 1000
    with Renderer(face, width=512, height=512, samples=4, view="front") as r:
        made = fdp_from_photo(r.render(face.pose_values(blink)), texture=False)
    assert [n.split(" is shut")[0] for n in made.notes] == ["the left eye", "the right eye"], made.notes
    head = made.calibrated()
    assert head.fapu.IRISD0 == pytest.approx(face.fapu.IRISD0, rel=0.1)
    fp = dict(zip(head.mesh.fp_labels, head.pose_values(blink).feature_points))
    assert abs(fp["3.1"][1] - fp["3.3"][1]) < 0.1 * head.fapu.IRISD0      # and it blinks


def _seal_line_steps(face, values: np.ndarray, view) -> int:
    """Steps of 2 px or more, column to column, in the bottom edge of the dark line where the lips meet (a lit
    300 px render of the mouth, between the inner corners less a tenth each side): a notched seal line has them."""
    from mpeg4fa.render import Renderer, frame_points

    pts = np.array([face.mesh.fp(label) for label in ("8.1", "8.2", "8.3", "8.4")])
    with Renderer(face, width=300, height=300, camera=frame_points(pts, 300, 300, view=view, margin=0.25)) as r:
        pose = face.deform(values)
        grey = r.render(pose).astype(float).mean(axis=2)
        idx = [face.mesh.fp_index(label) for label in ("2.4", "2.5", "2.2", "2.3")]
        (lx, _), (rx, _), (_, top), (_, bottom) = r.camera.project(pose.feature_points[idx], 300, 300)[:, :2]
    lo, hi = sorted((lx, rx))
    middle = int((top + bottom) / 2)
    band = grey[middle - 12:middle + 13]
    dark = band < 0.55 * np.median(band)
    inset = 0.1 * (hi - lo)
    edge = [np.flatnonzero(dark[:, c]).max() for c in range(int(np.ceil(lo + inset)), int(hi - inset)) if dark[:, c].any()]
    return int((np.abs(np.diff(edge)) >= 2).sum())


@pytest.mark.parametrize("set_name,name", [("mpeg4", "PP"), ("zh", "bpm")])
def test_bilabials_seal_in_a_smooth_line_on_the_photo_head(made, set_name, name):
    """The head calibrated to the astronaut presses its lips for p, b, m in one smooth line, front and
    three-quarter, as the generic head does (0 steps): the FDP's inner lip midpoints sit at the head's own share
    of the way along their contour (measured 1 and 0 steps; 6 and 1 with the landmark table's own midpoints,
    which sheared the lips where they meet and notched the line)."""
    from mpeg4fa.spec.profiles import VISEME_PROFILES

    face = made.calibrated()
    values = np.asarray(VISEME_PROFILES[set_name][name], float)
    for view in ((0.0, 0.0), (30.0, 5.0)):
        assert _seal_line_steps(face, values, view) <= 2, view


def test_texture_and_encode_find_the_points_themselves(cli, photos, tmp_path):
    """`texture PHOTO` without --points and `encode --front PHOTO` without points or side photo."""
    require_generic()
    code, out, err = cli("texture", photos / "astronaut.jpg", "-o", tmp_path / "skin.png", "--size", 256)
    assert code == 0, err
    assert "face found, 59 feature points" in err and Image.open(tmp_path / "skin.png").size == (256, 256)
    code, out, err = cli("encode", "Hello", "--engine", "estimate", "-o", tmp_path / "a.fba",
                         "--fdp-out", tmp_path / "me.fdp", "--front", photos / "astronaut.jpg")
    assert code == 0, err
    fdp = load_fdp(tmp_path / "me.fdp")
    assert len(fdp.labels) == 59 and fdp.texture_coords is not None
    # given points win over the found ones
    (tmp_path / "given.json").write_text('{"3.5": [250.0, 104.0]}')
    code, out, err = cli("encode", "Hello", "--engine", "estimate", "-o", tmp_path / "b.fba",
                         "--fdp-out", tmp_path / "me2.fdp", "--front", photos / "astronaut.jpg",
                         "--front-points", tmp_path / "given.json")
    assert code == 0, err
    again = load_fdp(tmp_path / "me2.fdp")
    uv = dict(zip(again.labels, again.texture_coords))["3.5"]
    assert np.allclose(uv * 512, [250.0, 512 - 104.0])


def test_play_and_say_with_the_face_of_a_photo(cli, photos, tmp_path):
    """`snapshot/play --photo` and `say --photo`: the face found in the photo, calibrated and textured, talks."""
    require_generic()
    code, _, err = cli("encode", "Hello there", "--engine", "estimate", "-o", tmp_path / "hello.fba")
    assert code == 0, err
    code, _, err = cli("snapshot", tmp_path / "hello.fba", "--frame", 10, "--photo", photos / "astronaut.jpg",
                       "-o", tmp_path / "own.png", "--size", 128)
    assert code == 0 and "59 feature points found" in err, err
    code, _, err = cli("snapshot", tmp_path / "hello.fba", "--frame", 10, "-o", tmp_path / "generic.png", "--size", 128)
    assert code == 0, err
    own, generic = (np.asarray(Image.open(tmp_path / n)).astype(int) for n in ("own.png", "generic.png"))
    # her blond hair on the crown where the generic head is bare skin
    crown_own, crown_generic = own[25:35, 55:75].mean(axis=(0, 1)), generic[25:35, 55:75].mean(axis=(0, 1))
    assert np.abs(crown_own - crown_generic).max() > 20
    code, _, err = cli("snapshot", tmp_path / "hello.fba", "--photo", photos / "astronaut.jpg", "--fdp",
                       tmp_path / "x.fdp", "-o", tmp_path / "x.png")
    assert code == 2 and "--photo and --fdp" in err
    code, out, err = cli("say", "Hi.", "--engine", "estimate", "--photo", photos / "astronaut.jpg",
                         "-o", tmp_path / "hi.mp4", "--size", 64, "--aa", 0)
    assert code == 0 and (tmp_path / "hi.mp4").stat().st_size > 1000, err
