"""The committed suite: reproducible, intact, and what our decoder reads from it is what was sent."""
from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.faces import FACES, read_template
from mpeg4fa.conformance.generate import generate
from mpeg4fa.conformance.manifest import default_root, load_manifest, sha256
from mpeg4fa.conformance.reference import fapu_from_points
from mpeg4fa.fba import FbaError, decode
from mpeg4fa.fdp import load_fdp

ROOT = default_root()
MANIFEST = load_manifest(ROOT)
DECODE = [v for v in MANIFEST.vectors if v.expect == "decode"]
REJECT = [v for v in MANIFEST.vectors if v.expect == "reject"]


def _files(root: Path) -> dict[str, bytes]:
    return {p.relative_to(root).as_posix(): p.read_bytes() for p in root.rglob("*")
            if p.is_file() and p.name not in ("README.md", "__init__.py")
            and p.relative_to(root).parts[0] != "adapters"}  # example adapters: written by hand


def test_regenerating_gives_the_same_bytes(tmp_path: Path) -> None:
    generate(tmp_path)
    committed, fresh = _files(ROOT), _files(tmp_path)
    assert sorted(committed) == sorted(fresh)
    different = [name for name in committed if committed[name] != fresh[name]]
    assert not different, different


def test_every_sha256_matches() -> None:
    for face in MANIFEST.faces.values():
        assert sha256(MANIFEST.path(face.fdp)) == face.sha256, face.name
    for v in MANIFEST.vectors:
        assert sha256(MANIFEST.path(v.stream)) == v.sha256, v.id
        assert sha256(MANIFEST.path(v.expected)) == v.expected_sha256, v.id


@pytest.mark.parametrize("vector", DECODE, ids=lambda v: v.id)
def test_decode_vector_gives_what_was_sent(vector) -> None:
    expected = MANIFEST.expected(vector)
    got = decode(MANIFEST.path(vector.stream))
    assert len(got) == expected["frames"]
    assert got.fps == pytest.approx(expected["fps"], abs=0)
    assert np.array_equal(got.timestamps, np.asarray(expected["timestamps"], dtype=np.float64))
    sent = expected["sent"]
    mask = np.asarray(sent["mask"], dtype=bool)
    assert np.array_equal(got.fap_mask, mask)
    assert np.array_equal(np.where(mask, got.fap_values, 0), np.asarray(sent["values"]))
    assert np.array_equal(np.where(mask[:, :1], got.viseme, 0), np.asarray(sent["viseme"]))
    assert np.array_equal(np.where(mask[:, 1:2], got.expression, 0), np.asarray(sent["expression"]))
    assert np.asarray(expected["shown"]).shape == (expected["frames"], 68)


@pytest.mark.parametrize("vector", REJECT, ids=lambda v: v.id)
def test_reject_vector_is_rejected_where_argued(vector) -> None:
    expected = MANIFEST.expected(vector)
    assert expected["reject"] is True
    with pytest.raises(FbaError) as info:
        decode(MANIFEST.path(vector.stream))
    assert info.value.bit_offset == expected["bit_offset"]
    partial = info.value.partial
    assert (len(partial) if partial is not None else 0) == expected["frames_before"]


def test_faces_round_trip_and_differ() -> None:
    template = read_template(ROOT / "faces" / "template.csv")
    units = {}
    for spec in FACES:
        fdp = load_fdp(MANIFEST.path(MANIFEST.faces[spec.name].fdp))
        points = fdp.as_dict()
        assert set(points) == set(spec.labels or template)
        units[spec.name] = fapu_from_points(points)
    ratios = {name: (round(u["MW0"] / u["ES0"], 3), round(u["ENS0"] / u["ES0"], 3)) for name, u in units.items()}
    assert len(set(ratios.values())) == len(FACES), ratios  # proportions differ, not only sizes
    assert len({round(u["ES0"], 6) for u in units.values()}) == len(FACES)
    assert len(load_fdp(MANIFEST.path(MANIFEST.faces["subset"].fdp)).labels) < 84


def test_suite_shape() -> None:
    groups = Counter(v.group for v in MANIFEST.vectors)
    assert set(groups) == {"syntax", "semantics", "reject", "informative"}
    for v in MANIFEST.vectors:
        assert (v.confidence == "M") == (v.group == "informative"), v.id
        assert v.id.startswith(v.group + "/")
    ids = {v.id for v in MANIFEST.vectors}
    assert all(f"semantics/fap-{fap:02d}" in ids for fap in range(3, 69))
    assert all(v.face for v in MANIFEST.vectors if v.group == "semantics")
    for v in DECODE:
        doc = json.loads(MANIFEST.path(v.expected).read_text())
        if v.face and "feature_points" in doc:
            fp = doc["feature_points"]
            assert np.asarray(fp["positions"]).shape == (doc["frames"], len(fp["labels"]), 3)


def test_every_moving_fap_has_its_feature_points_checked() -> None:
    """Each FAP whose motion the reference pins (translations, head rotations) is checked on a face with its points."""
    from mpeg4fa.conformance.reference import DIRECTIONS
    from mpeg4fa.spec import FAPS

    by_id = {v.id: v for v in MANIFEST.vectors}
    for f in FAPS[2:]:
        v = by_id[f"semantics/fap-{f.number:02d}"]
        doc = MANIFEST.expected(v)
        pinned = f.direction in DIRECTIONS and (f.fapu != "AU" or f.name.startswith("head_"))
        assert ("feature_points" in doc) == pinned, v.id
        if pinned:
            fp = doc["feature_points"]
            checked = {label for label, rows in zip(fp["labels"], np.asarray(fp["checkable"]).transpose(1, 0, 2))
                       if rows.any()}
            want = {label for label in f.feature_point} if f.fapu != "AU" else set(fp["labels"])
            assert want <= checked, (v.id, want - checked)
            if f.fapu == "AU":
                assert len(checked) == len(load_fdp(MANIFEST.path(MANIFEST.faces[v.face].fdp)).labels)


def test_expected_files_are_compact_and_widen_to_68_columns() -> None:
    from mpeg4fa.conformance.manifest import compact, full_width

    halving = next(v for v in DECODE if v.id == "syntax/adaptation-halving")
    assert MANIFEST.path(halving.expected).stat().st_size < 500_000       # 12,700 frames of one FAP
    stored = json.loads(MANIFEST.path(halving.expected).read_text())
    assert stored["columns"] == [2] and "viseme" not in stored["sent"]
    full = MANIFEST.expected(halving)
    assert np.asarray(full["shown"]).shape == (12_700, 68) and np.asarray(full["sent"]["viseme"]).shape == (12_700, 4)
    doc = {"frames": 2, "timestamps": [0.0, 0.04], "shown": [[0.0] * 68, [0.0] * 68],
           "sent": {"mask": [[0] * 68, [0] * 68], "values": [[0] * 68, [0] * 68],
                    "viseme": [[3, 0, 63, 0], [0] * 4], "expression": [[0] * 6, [0] * 6]}}
    doc["sent"]["mask"][0][0] = doc["sent"]["mask"][1][40] = 1
    doc["sent"]["values"][1][40], doc["shown"][1][40] = -7, -7.0
    small = compact(doc, [0, 40])
    assert "expression" not in small["sent"] and small["shown"] == [[0.0, 0.0], [0.0, -7.0]]
    wide = full_width(small)
    assert np.array_equal(wide["shown"], doc["shown"]) and np.array_equal(wide["timestamps"], doc["timestamps"])
    assert all(np.array_equal(wide["sent"][k], doc["sent"][k]) for k in doc["sent"])
    broken = {**small, "shown": [[0.0, 0.0, 1.0], [0.0, 0.0]]}
    with pytest.raises(ConformanceError, match="columns"):
        full_width(broken)
