"""Editor mesh files the fuzz campaigns of issue 26 item 9 broke (obj:1427@0, gltf:2142@2, trimesh overflow
warnings): each is one EditError naming the file and the node, part or reference at fault, before trimesh or
numpy does arithmetic on it; never an OverflowError, a ValueError from trimesh or a RuntimeWarning."""
from __future__ import annotations

import json
import struct
import warnings

import numpy as np
import pytest

from mpeg4fa.errors import MpegFaError
from mpeg4fa.web.edits import EditError
from mpeg4fa.web.files import read_mesh, read_model, read_upload
from web.test_files import _scene

TETRA = b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


@pytest.fixture(autouse=True)
def _no_stray_warnings():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        yield


@pytest.mark.parametrize("triangle", [2**63, 10**99, -(2**64)], ids=["2**63", "10**99", "-2**64"])
def test_a_parts_file_triangle_past_int64_names_the_file(triangle):
    parts = json.dumps({"parts": {"skin": [0, 1, 2, triangle]}}).encode()
    with pytest.raises(EditError) as info:
        read_upload([("m.obj", TETRA), ("m.parts.json", parts)])
    assert info.value.where == "m.parts.json: parts/skin" and "outside 0..3" in info.value.message, str(info.value)


def _gltf_doc() -> dict:
    return json.loads(_scene().export(file_type="gltf", embed_buffers=True)["model.gltf"])


def _glb(doc: dict) -> bytes:
    """The scene as a GLB whose JSON chunk is ``doc`` (the binary chunk as trimesh wrote it)."""
    glb = _scene().export(file_type="glb")
    size = struct.unpack_from("<I", glb, 12)[0]
    original = json.loads(glb[20:20 + size])
    doc = {**doc, "buffers": original["buffers"], "bufferViews": original["bufferViews"]}
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    rest = glb[20 + size:]
    body = struct.pack("<I", len(text)) + b"JSON" + text + rest
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def _broken(change) -> dict:
    doc = _gltf_doc()
    change(doc)
    return doc


CASES = {
    "matrix of 4 numbers": (lambda d: d["nodes"][1].update(matrix=[1, 0, 0, 1]), "nodes/1/matrix",
                            "node 1 ('eye_l'): 'matrix' must be 16 numbers"),
    "translation of 2": (lambda d: d["nodes"][2].update(translation=[1, 2]), "nodes/2/translation",
                         "'translation' must be 3 numbers"),
    "rotation with text": (lambda d: d["nodes"][0].update(rotation=["0", 0, 0, 1]), "nodes/0/rotation",
                           "node 0 ('Skin'): 'rotation' must be 4 numbers"),
    "scale of true": (lambda d: d["nodes"][0].update(scale=[True, 1, 1]), "nodes/0/scale", "'scale' must be 3"),
    "scale beyond the bound": (lambda d: d["nodes"][0].update(scale=[1, 1e300, 1]), "nodes/0/scale",
                               "'scale' holds a number beyond +-1e+09"),
    "mesh -1": (lambda d: d["nodes"][0].update(mesh=-1), "nodes/0/mesh", "'mesh' is -1, not an index into the 3"),
    "child 9": (lambda d: d["nodes"][0].update(children=[9]), "nodes/0/children", "child is 9"),
    "POSITION -1": (lambda d: d["meshes"][0]["primitives"][0]["attributes"].update(POSITION=-1),
                    "meshes/0/primitives/0/attributes/POSITION", "attribute POSITION is -1, not an index into the 4"),
    "indices 1.5": (lambda d: d["meshes"][1]["primitives"][0].update(indices=1.5), "meshes/1/primitives/0/indices",
                    "'indices' is 1.5"),
}


@pytest.mark.parametrize("form", ["gltf", "glb"])
@pytest.mark.parametrize("case", list(CASES))
def test_a_bad_node_or_reference_is_named_before_trimesh(case, form):
    change, where, problem = CASES[case]
    doc = _broken(change)
    data = json.dumps(doc).encode() if form == "gltf" else _glb(doc)
    with pytest.raises(EditError) as info:
        read_mesh(data, f"head.{form}")
    assert info.value.where.startswith(f"head.{form}") and info.value.where.endswith(where), str(info.value)
    assert problem in info.value.message, str(info.value)


def test_the_fuzz_gltf_case_names_its_position_accessor(tmp_path):
    """gltf:2142@2: POSITION -1 picked the index accessor, a (144, 1) array trimesh could not transform."""
    doc = _broken(CASES["POSITION -1"][0])
    (tmp_path / "head.gltf").write_text(json.dumps(doc))
    with pytest.raises(EditError, match="attribute POSITION is -1"):
        read_model(tmp_path / "head.gltf")


def test_node_scales_that_multiply_past_the_bound_are_refused_without_overflow():
    def nest(d):
        d["nodes"][1].pop("matrix")
        d["nodes"][1]["scale"] = [1e9] * 3
        d["nodes"].append({"name": "holder", "scale": [1e9] * 3, "children": [1]})
        d["scenes"][0]["nodes"] = [0, 3, 2]
    for form, data in (("gltf", json.dumps(_broken(nest)).encode()), ("glb", _glb(_broken(nest)))):
        with np.errstate(all="raise", under="ignore"), pytest.raises(EditError) as info:
            read_mesh(data, f"head.{form}")
        assert info.value.where == f"head.{form}" and "node 'eye_l'" in info.value.message, str(info.value)
        assert "within +-1e+09" in info.value.message


def test_a_glb_json_chunk_longer_than_the_file_is_refused_at_its_length():
    glb = bytearray(_scene().export(file_type="glb"))
    struct.pack_into("<I", glb, 12, 0xFFFF0000)
    with pytest.raises(EditError) as info:
        read_mesh(bytes(glb), "head.glb")
    assert info.value.where == "head.glb" and "JSON chunk (length at byte 12) claims 4,294,901,760 bytes" in str(
        info.value)


def test_a_glb_whose_json_is_damaged_is_located_in_its_chunk():
    glb = bytearray(_scene().export(file_type="glb"))
    glb[20] = ord("[")
    with pytest.raises(MpegFaError) as info:
        read_mesh(bytes(glb), "head.glb")
    assert info.value.where.startswith("head.glb (JSON chunk):1:"), str(info.value)


def test_good_files_still_read():
    assert len(read_mesh(_glb(_gltf_doc()), "head.glb").triangles) == 14
    assert len(read_mesh(json.dumps(_gltf_doc()).encode(), "head.gltf").triangles) == 14
    assert len(read_upload([("m.obj", TETRA), ("m.parts.json", b'{"parts": {"skin": [0, 1, 2, 3]}}')]).triangles) == 4


def test_a_reader_fault_that_says_nothing_still_gives_a_reason():
    """Fuzz of 2026-12-07: a glTF whose buffer claims 10**15 bytes made trimesh raise a bare AssertionError, and
    the answer read "cannot read the mesh: " with nothing after it."""
    doc = {"asset": {"version": "2.0"},
           "buffers": [{"uri": "data:application/octet-stream;base64,AAAA", "byteLength": 10 ** 15}],
           "bufferViews": [{"buffer": 0, "byteLength": 10 ** 15}],
           "accessors": [{"bufferView": 0, "componentType": 5126, "count": 10 ** 14, "type": "VEC3"}],
           "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}]}
    with pytest.raises(EditError) as caught:
        read_mesh(json.dumps(doc).encode(), "a.gltf")
    assert caught.value.where == "a.gltf" and "cannot read the mesh: " in str(caught.value)
    assert len(caught.value.message) > len("cannot read the mesh: ") + 10
