"""facerig.js poses every vertex as the Python face's feature-point deformer does (issue 31: the player's lips).

The rig is :func:`mpeg4fa.serve.fap_head.rig_data` of the test face; the rows exercise each layer of the
deformer alone and together: the reach limiter (FAPs at their full I range), the lip corner rule (inner and outer corners sent against each other), lids,
tongue roll, jaw open/thrust/shift, eyeballs, head turns, and decoded speech from a real stream.
"""
from __future__ import annotations

import json
import subprocess

import numpy as np
import pytest

from mpeg4fa.decoded import clamp
from mpeg4fa.serve.fap_head import rig_data
from serve.live_server import face_for_tests

from .conftest import ROOT, SHARED, need_node

TOLERANCE_MM = 1e-6  # the same float64 steps in the same order: rounding only


def rows_to_check(rng: np.random.Generator) -> np.ndarray:
    rows = []

    def row(**faps):
        r = np.zeros(68)
        for name, v in faps.items():
            r[int(name[1:]) - 1] = v
        rows.append(r)

    row()
    row(f3=600)  # jaw open
    row(f3=400, f14=100, f15=-80)  # open, thrust, shift
    row(f6=150, f7=150)  # inner corners stretched: the outer ones pushed ahead (the corner rule)
    row(f6=120, f7=120, f53=-200, f54=-200)  # a smile over a rounded mouth: the rule splits the way
    row(f4=-100, f5=-200, f8=50, f9=50, f10=-80, f11=-80, f51=-100, f52=-150, f55=30, f56=30, f57=-60)
    row(f19=800, f20=400, f21=-200, f22=300)  # lids
    row(f19=1146, f20=1146, f21=369, f22=369, f25=640)  # a blink over raised lower lids: the lids meet
    row(f47=3000, f43=100, f44=60)  # tongue roll and tip
    row(f23=20000, f24=-15000, f25=10000, f26=-5000, f27=100, f28=-50)  # eyeballs
    row(f48=15000, f49=-20000, f50=8000)  # head
    row(f3=900, f48=69813, f49=30000, f50=-9000)  # a 40 degree bow, turned: the whole neck takes its excess
    row(f31=724, f32=724, f33=640, f34=640, f35=520, f36=520)  # brows x2 up: the guard lets the scalp slide
    row(f31=-400, f32=300, f33=-500, f34=600, f35=-300, f36=500)  # one side down, the other up
    row(f5=3720, f6=1200, f8=-1200, f14=600, f17=-1080)  # full I ranges: eased into the head's reach
    row(f5=-3720, f10=3000, f11=-2000, f15=1080, f16=-1080)
    for _ in range(6):  # everything at once, random
        r = rng.normal(0, 1, 68) * np.r_[0, 0, np.full(66, 120.0)]
        r[[22, 23, 24, 25, 46, 47, 48, 49]] *= 60  # angles in AU
        rows.append(r)
    return clamp(np.array(rows))[0]


@pytest.fixture(scope="module")
def face():
    return face_for_tests()


def pose_in_node(tmp_path, face, rows: np.ndarray) -> tuple[np.ndarray, dict]:
    rig, rows_path, out = tmp_path / "rig.json", tmp_path / "rows.json", tmp_path / "poses.bin"
    rig.write_text(json.dumps(rig_data(face)))
    rows_path.write_text(json.dumps(rows.tolist()))
    run = subprocess.run([need_node(), str(ROOT / "tests" / "js" / "pose_rig.mjs"), str(rig), str(rows_path), str(out)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    n = len(face.mesh.vertices)
    return np.fromfile(out, "<f8").reshape(len(rows), n, 3), json.loads(run.stdout)


def test_facerig_poses_every_vertex_as_python(tmp_path, face):
    rows = rows_to_check(np.random.default_rng(31))
    got, timing = pose_in_node(tmp_path, face, rows)
    print(timing)
    for k, row in enumerate(rows):
        want = face.pose_values(row).vertices
        err = np.abs(got[k] - want).max()
        assert err < TOLERANCE_MM, f"row {k}: a vertex {err:.3g} mm from the Python face's"
        if k:  # the rows do move the face (a rig that ignored them would pass the rest row only)
            assert np.abs(want - face.mesh.vertices).max() > 0.5, k


def test_facerig_on_real_speech(tmp_path, face):
    if not SHARED.is_dir():
        pytest.skip(f"{SHARED} is absent: the real streams are not on this machine")
    import warnings

    from mpeg4fa.decoded import resolve
    from mpeg4fa.fba import decode

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        values = resolve(decode(SHARED / "en" / "car-unlock.FBA"))
    rows = values[:: max(1, len(values) // 12)]
    got, _ = pose_in_node(tmp_path, face, rows)
    for k, row in enumerate(rows):
        assert np.abs(got[k] - face.pose_values(row).vertices).max() < TOLERANCE_MM, k


def test_neck_blend_rule_of_a_rig_without_partial_turns(tmp_path, face):
    """A rig made where the deformer blends the neck back by its share (``neck: blend``, the rule before partial
    turns) is posed by that rule: checked against the same steps in numpy."""
    from mpeg4fa.face import motion
    from mpeg4fa.face.deformers.feature_points import pose_in_head_frame

    data = rig_data(face)
    data["head"]["neck"] = "blend"
    rows = np.zeros((2, 68))
    rows[0, [47, 48, 49]] = (12000, -18000, 6000)
    rows[1, [2, 47, 48]] = (400, -9000, 15000)
    rig, rows_path, out = tmp_path / "rig.json", tmp_path / "rows.json", tmp_path / "poses.bin"
    rig.write_text(json.dumps(data))
    rows_path.write_text(json.dumps(rows.tolist()))
    run = subprocess.run([need_node(), str(ROOT / "tests" / "js" / "pose_rig.mjs"), str(rig), str(rows_path), str(out)],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr[-2000:]
    got = np.fromfile(out, "<f8").reshape(len(rows), -1, 3)
    r = face.rig
    fade_rows, fade_w = r.head_fade
    centre = r.rest[r.fp_vertex[r.head_fp]]
    for k, v in enumerate(rows):
        p, _ = pose_in_head_frame(r, v)
        turn = motion.head_rotation(*(v[[47, 48, 49]] * motion.ANGLE_UNIT_RAD))
        want = centre + (p - centre) @ turn.T
        want[fade_rows] = p[fade_rows] + fade_w[:, None] * (want[fade_rows] - p[fade_rows])
        assert np.abs(got[k] - want).max() < 1e-6, k
