"""Faces shared by the face, render and CLI tests, built once per session.

``procedural_face`` needs nothing but the code (see ``procedural_head.py``);
``generic_face`` is the CC0 head from the user cache and skips when it has not
been built: the tests never download it. ``deformed_face`` is each face under each
deformer that realises the FAPs exactly (``EXACT_DEFORMERS``), for the tests every
such deformer must pass; the block deformer realises some FAPs approximately and has
its measured errors in ``face/test_blocks.py``.
"""
from __future__ import annotations

import pytest

from mpeg4fa.face import asset, deformers
from mpeg4fa.face.model import FaceModel
from procedural_head import build_procedural_head

GENERIC_MISSING = "generic head not built: run `mpeg4fa model install` (needs network once)"
FACES = ("procedural", "generic")
APPROXIMATE_DEFORMERS = ("blocks",)
EXACT_DEFORMERS = tuple(d for d in deformers.names() if d not in APPROXIMATE_DEFORMERS)
_DEFORMED: dict[tuple[str, str], FaceModel] = {}


def require_generic() -> None:
    if not asset.is_installed():
        pytest.skip(GENERIC_MISSING)


@pytest.fixture
def cli(capsys):
    """``cli(*argv) -> (exit code, stdout, stderr)``: the command run in-process; arguments may be paths."""
    from mpeg4fa.cli import main

    def run(*argv):
        code = main([str(a) for a in argv])
        out, err = capsys.readouterr()
        return code, out, err
    return run


@pytest.fixture(scope="session")
def generic_head_installed() -> None:
    """Skips a test (``pytest.mark.usefixtures("generic_head_installed")``) when the head is not built."""
    require_generic()


@pytest.fixture(scope="session")
def procedural_head():
    return build_procedural_head()


@pytest.fixture(scope="session")
def procedural_face(procedural_head):
    return FaceModel(procedural_head)


@pytest.fixture(scope="session")
def generic_face():
    require_generic()
    return FaceModel.default(auto_install=False)


@pytest.fixture(scope="session")
def generic_head(generic_face):
    return generic_face.mesh


@pytest.fixture(scope="session", params=FACES)
def face(request):
    """Each of the two faces in turn (the generic one skips when it is not built)."""
    return request.getfixturevalue(f"{request.param}_face")


def face_under(request, which: str, deformer: str) -> FaceModel:
    """Face ``which`` posed by ``deformer``, set up once per session (skips where the head cannot have it)."""
    base = request.getfixturevalue(f"{which}_face")
    if deformer == "fap":
        return base
    if deformers.kind(deformer).needs_face_units and base.mesh.face_units is None:
        pytest.skip(f"the {which} head has no face units for the {deformer} deformer")
    key = (which, deformer)
    if key not in _DEFORMED:
        _DEFORMED[key] = base.with_deformer(deformer)
    return _DEFORMED[key]


@pytest.fixture(scope="session", params=[(f, d) for d in EXACT_DEFORMERS for f in FACES],
                ids=lambda p: f"{p[0]}-{p[1]}")
def deformed_face(request):
    """Each face under each exact deformer in turn."""
    return face_under(request, *request.param)
