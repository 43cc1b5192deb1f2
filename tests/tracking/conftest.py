"""Shared photo fixtures of the tracking tests: the landmark model runs once per photo per session."""
from __future__ import annotations

import pytest

mp = pytest.importorskip("mediapipe", reason="the track extra (mediapipe) is not installed: tools/dev.sh test installs it")
skdata = pytest.importorskip("skimage.data", reason="scikit-image (test extra) gives the test photos")


@pytest.fixture(scope="session")
def astronaut():
    return skdata.astronaut()


@pytest.fixture(scope="session")
def astronaut_landmarks(astronaut):
    from mpeg4fa.tracking import find_landmarks
    return find_landmarks(astronaut, "astronaut")
