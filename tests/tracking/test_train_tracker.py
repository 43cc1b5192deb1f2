"""tools/train_tracker.py's mirror images of its runs: each landmark's and each FAP's twin across the face, and a
run turned over (the map learns a face and its mirror image alike)."""
from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.tracking import learned

TOOL = Path(__file__).resolve().parents[2] / "tools" / "train_tracker.py"


@pytest.fixture(scope="module")
def tool():
    spec = importlib.util.spec_from_file_location("train_tracker_tool", TOOL)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_each_learned_fap_has_its_twin_on_the_other_side(tool):
    twin = tool.fap_mirror()
    assert np.array_equal(twin[twin], np.arange(68))  # twice across is itself
    pairs = {(3, 3), (4, 4), (5, 5), (6, 7), (12, 13), (19, 20), (21, 22), (31, 32), (35, 36), (37, 38), (51, 51),
             (53, 54), (59, 60)}
    for a, b in pairs:
        assert twin[a - 1] == b - 1 and twin[b - 1] == a - 1, (a, b)
    assert twin[48] == 48  # not learned (head yaw): itself, its sign is the angles' business


def test_landmark_twins_pair_a_face_with_its_mirror_image(tool):
    rng = np.random.default_rng(5)
    half = rng.uniform([10, 0, -5], [90, 120, 5], (229, 3))  # one side of a face about x = 100
    middle = np.column_stack([np.full(20, 100.0), rng.uniform(0, 120, 20), rng.uniform(-5, 5, 20)])
    face = np.concatenate([half, middle, half * [-1, 1, 1] + [200, 0, 0]])
    shuffle = rng.permutation(len(face))
    face = face[shuffle]
    twin = tool.landmark_mirror(face + rng.normal(0, 0.05, face.shape))  # a little noise: still the same pairs
    mirror = face[twin] * [-1, 1, 1] + [200, 0, 0]
    assert np.allclose(mirror, face) and np.array_equal(twin[twin], np.arange(len(face)))


def test_a_run_turned_over_twice_is_itself_and_once_reads_its_twin(tool):
    rng = np.random.default_rng(6)
    order = rng.permutation(learned.FACE_LANDMARKS)  # random pairs, the last 28 their own (any pairing will do)
    twin = np.arange(learned.FACE_LANDMARKS)
    twin[order[0:450:2]], twin[order[1:450:2]] = order[1:450:2], order[0:450:2]
    faps = tool.fap_mirror()
    run = {"moved": rng.normal(size=(4, learned.FACE_LANDMARKS, 3)).astype(np.float32),
           "angles": rng.normal(size=(4, 3)), "values": rng.normal(size=(4, 68)), "texture": "grace", "seed": 11}
    once = tool.mirrored(run, twin, faps)
    twice = tool.mirrored(once, twin, faps)
    for key in ("moved", "angles", "values"):
        assert np.allclose(twice[key], run[key])
    assert once["texture"] == "grace" and once["seed"] == 11  # still the same family and stream (left out together)
    assert np.allclose(once["values"][:, 31 - 1], run["values"][:, 32 - 1])  # the right brow's raise is the left's
    assert np.allclose(once["angles"], run["angles"] * [1, -1, -1])  # pitch kept, yaw and roll turned over
    k = int(np.flatnonzero(twin != np.arange(learned.FACE_LANDMARKS))[0])
    assert np.allclose(once["moved"][:, k], run["moved"][:, twin[k]] * [-1, 1, 1])
