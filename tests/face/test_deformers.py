"""The deformer registry (mpeg4fa.face.deformers): every name builds, options are checked, and the
CLI offers the same choices."""
import numpy as np
import pytest

from mpeg4fa.face import FaceError, deformers


@pytest.mark.parametrize("which", ["procedural", "generic"])
def test_every_registered_deformer_poses_the_neutral_face_unchanged(request, which):
    base = request.getfixturevalue(f"{which}_face")
    for name in deformers.names():
        if deformers.kind(name).needs_face_units and base.mesh.face_units is None:
            continue
        pose = base.with_deformer(name).neutral()
        assert np.abs(pose.vertices - base.mesh.vertices).max() < 1e-9, name


def test_options_are_checked_when_the_face_is_made(procedural_face):
    with pytest.raises(FaceError, match="has no option 'regions'"):
        procedural_face.with_deformer("fap", regions=("lip_t",))
    with pytest.raises(FaceError, match="unknown deformer"):
        procedural_face.with_deformer("nope")
    with pytest.raises(FaceError, match="unknown block 'nose'"):
        procedural_face.with_deformer("blocks", regions=("nose",))  # before any set-up
    with pytest.raises(FaceError, match="not a list of block names"):
        procedural_face.with_deformer("blocks", regions=None)
    assert [b.name for b in procedural_face.with_deformer("blocks", regions="mouth").posing.blocks] == ["mouth"]


@pytest.mark.parametrize("which", ["procedural", "generic"])
def test_block_regions_choose_the_blocks(request, which):
    face = request.getfixturevalue(f"{which}_face")
    lips = face.with_deformer("blocks", regions=("lip_t", "lip_b"))
    assert [b.name for b in lips.posing.blocks] == ["lip_t", "lip_b"]
    none = face.with_deformer("blocks", regions=())
    values = np.zeros(68)
    values[[30, 31, 50]] = (200, 200, 150)  # brows and a lip: nothing but the feature-point deformer's motion
    assert np.abs(none.deform(values).vertices - face.deform(values).vertices).max() < 1e-9
    calibrated = lips.calibrate(face.to_fdp(), method="rbf")
    assert calibrated.deformer == "blocks" and calibrated.deformer_options == {"regions": ("lip_t", "lip_b")}


def test_cli_blocks_option(cli, generic_face, capsys):
    code, _, err = cli("model", "pose", "--deformer", "fap", "--blocks", "lip_t", "--fap", "3=100")
    assert code == 2 and "--blocks goes with --deformer blocks" in err
    code, _, err = cli("model", "pose", "--deformer", "blocks", "--blocks", "nose", "--fap", "3=100")
    assert code == 1 and "unknown block 'nose'" in err and "Traceback" not in err
    code, out, _ = cli("model", "pose", "--deformer", "blocks", "--blocks", "lip_t,lip_b", "--fap", "51=100")
    assert code == 0 and "8.10" in out
    with pytest.raises(SystemExit):
        cli("model", "pose", "--help")
    out = capsys.readouterr().out
    assert all(name in out for name in deformers.names())  # the choices come from the registry
