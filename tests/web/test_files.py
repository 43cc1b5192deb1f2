"""The editor's mesh files: VRML 97 (VTK), glTF/GLB node scenes (trimesh), OBJ with its own indices, an OBJ
saved by the editor read back with its parts and feature points, and uploads of a model with its companion files.
Every file is written by the test itself."""
import json

import numpy as np
import pytest
import trimesh
from fastapi.testclient import TestClient

from mpeg4fa.errors import MpegFaError
from mpeg4fa.web.app import create_app
from web.local import LOCAL
from mpeg4fa.web.edits import EditError, make_mesh
from mpeg4fa.web.files import read_mesh, read_model, read_upload, save_model

# ---- VRML 97 --------------------------------------------------------------------------------------

TWO_SHAPES = b"""#VRML V2.0 utf8
# a skin quad and, under a Transform, a teeth triangle
DEF Skin Shape {
  appearance Appearance { material Material { diffuseColor 1 0.8 0.7 } }
  geometry IndexedFaceSet {
    coord Coordinate { point [ 0 0 0, 1 0 0, 1 1 0, 0 1 0 ] }
    coordIndex [ 0 1 2 3 -1 ]
  }
}
Transform {
  translation 10 0 0
  rotation 0 0 1 1.5707963267948966
  scale 2 2 2
  children [
    DEF Teeth Shape {
      geometry IndexedFaceSet {
        coord Coordinate { point [ 0 0 0, 1 0 0, 0 1 0 ] }
        coordIndex [ 0, 1, 2, -1 ]
      }
    }
  ]
}
"""


def _area(vertices, triangles):
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    return 0.5 * np.linalg.norm(np.cross(b - a, c - a), axis=1)


def test_vrml_two_shapes_a_transform_and_a_quad():
    mesh = read_mesh(TWO_SHAPES, "head.wrl")
    assert mesh.part_names == ("skin", "teeth")
    parts = np.array(mesh.parts)
    skin, teeth = mesh.triangles[parts == "skin"], mesh.triangles[parts == "teeth"]
    assert len(skin) == 2 and len(teeth) == 1  # the quad split into two triangles
    assert sorted(np.unique(skin).tolist()) == [0, 1, 2, 3]
    assert _area(mesh.vertices, skin).sum() == pytest.approx(1.0)
    assert np.allclose(mesh.vertices[:4], [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]])
    # scale 2, then a quarter turn about z, then +10 in x: (1,0,0) -> (10,2,0), (0,1,0) -> (8,0,0)
    assert np.allclose(mesh.vertices[np.unique(teeth)], [[10, 0, 0], [10, 2, 0], [8, 0, 0]], atol=1e-9)


def test_reading_vrml_leaves_the_renderers_gl_context_working():
    """VTK's OpenGL module takes the thread's current GL context away: it runs in a child process, so the
    process's shared EGL context still draws after a VRML upload (it failed with 'cannot create texture')."""
    from mpeg4fa.render.context import gl_context
    ctx = gl_context()
    ctx.texture((8, 8), 4, dtype="f4").release()
    read_mesh(TWO_SHAPES, "head.wrl")
    ctx.texture((8, 8), 4, dtype="f4").release()


def test_vrml_nested_transforms_and_a_use_become_parts(tmp_path):
    text = b"""#VRML V2.0 utf8
Transform { translation 0 5 0 children [
  Transform { scale 3 3 3 children [
    DEF Eye Shape { geometry IndexedFaceSet { coord Coordinate { point [ 0 0 0, 1 0 0, 0 1 0 ] } coordIndex [ 0 1 2 ] } }
  ] }
  Transform { translation 100 0 0 children [ USE Eye ] }
] }
"""
    mesh = read_mesh(text, "eyes.vrml")
    assert mesh.part_names == ("eye", "eye_2") and len(mesh.triangles) == 2
    assert np.allclose(mesh.vertices, [[0, 5, 0], [3, 5, 0], [0, 8, 0], [100, 5, 0], [101, 5, 0], [100, 6, 0]])


def test_vrml_upload_through_the_api(tmp_path):
    with TestClient(create_app(out_dir=tmp_path), base_url=LOCAL) as client:
        r = client.post("/api/upload", files={"file": ("head.wrl", TWO_SHAPES, "model/vrml")})
        assert r.status_code == 200, r.text
        assert sorted(r.json()["parts"]) == ["skin", "teeth"] and r.json()["counts"]["triangles"] == 3
        bad = TWO_SHAPES.replace(b"1 1 0, 0 1 0", b"1 1 0, 0 x 0")
        r = client.post("/api/upload", files={"file": ("bad.wrl", bad, "model/vrml")})
        assert r.status_code == 422 and r.json()["where"] == "bad.wrl:6", r.json()


@pytest.mark.parametrize("text, where, problem", [
    (TWO_SHAPES.replace(b"1 1 0, 0 1 0", b"1 1 0, 0 x 0"), "f.wrl:6", "parse error"),
    (TWO_SHAPES.replace(b"Transform {", b"Transfrom {"), "f.wrl:10", "Unknown node type Transfrom"),
    (TWO_SHAPES[:-40], "f.wrl:18", "parse error"),  # cut short in line 18: the braces never close
    (TWO_SHAPES.replace(b"[ 0, 1, 2, -1 ]", b"[ 0, 1, 7, -1 ]"), "f.wrl: shape 2", "coordIndex 7 is out of range"),
    (b"#VRML V1.0 ascii\nSeparator { }\n", "f.wrl:1", "must begin with '#VRML V2.0"),
    (b"#VRML V2.0 utf8\n", "f.wrl", "no IndexedFaceSet"),
])
def test_vrml_faults_are_one_located_error(text, where, problem):
    with pytest.raises(EditError) as err:
        read_mesh(text, "f.wrl")
    assert err.value.where == where and problem in err.value.message, str(err.value)


# ---- glTF / GLB -----------------------------------------------------------------------------------

def _scene() -> trimesh.Scene:
    """A skin box and one eye triangle used by two nodes with different transforms."""
    scene = trimesh.Scene()
    tri = trimesh.Trimesh([[0, 0, 0], [1, 0, 0], [0, 1, 0]], [[0, 1, 2]], process=False)
    scene.add_geometry(trimesh.creation.box(), geom_name="Cube.001", node_name="Skin")
    left = trimesh.transformations.translation_matrix([5, 0, 0]) @ trimesh.transformations.scale_matrix(2)
    scene.add_geometry(tri, geom_name="eye", node_name="eye_l", transform=left)
    scene.add_geometry(tri, geom_name="eye", node_name="eye_r",
                       transform=trimesh.transformations.translation_matrix([-5, 0, 0]))
    return scene


def _check_scene_mesh(mesh):
    assert sorted(mesh.part_names) == ["eye_l", "eye_r", "skin"]
    parts = np.array(mesh.parts)
    for part, corners in (("eye_l", [[5, 0, 0], [7, 0, 0], [5, 2, 0]]), ("eye_r", [[-5, 0, 0], [-4, 0, 0], [-5, 1, 0]])):
        assert np.allclose(mesh.vertices[mesh.triangles[parts == part][0]], corners)
    assert len(mesh.triangles[parts == "skin"]) == 12


def test_glb_nodes_become_parts_with_their_transforms():
    _check_scene_mesh(read_mesh(_scene().export(file_type="glb"), "head.glb"))


def test_gltf_with_embedded_buffers_loads():
    files = _scene().export(file_type="gltf", embed_buffers=True)
    assert list(files) == ["model.gltf"] and b"data:" in files["model.gltf"]
    _check_scene_mesh(read_mesh(files["model.gltf"], "head.gltf"))


def test_gltf_with_external_buffers_needs_them_given_and_reads_beside_its_files(tmp_path):
    files = _scene().export(file_type="gltf")
    with pytest.raises(EditError, match="gltf_buffer_0.bin") as err:
        read_mesh(files["model.gltf"], "head.gltf")
    assert err.value.where == "head.gltf" and "together with" in err.value.hint
    for name, data in files.items():
        (tmp_path / name).write_bytes(data)
    _check_scene_mesh(read_model(tmp_path / "model.gltf"))


# ---- OBJ and the editor's own saved model -----------------------------------------------------------

def test_obj_upload_keeps_the_files_vertex_indices():
    """Materials, normals and an unused vertex: trimesh alone would split or renumber; feature points need the file's.
    Groups (or objects) become parts."""
    text = (b"v 9 9 9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\n"
            b"usemtl a\nf 2//1 3//1 4//1\nusemtl b\nf 3//1 5//1 4//1\n")
    mesh = read_mesh(text, "m.obj")
    assert len(mesh.vertices) == 5 and mesh.vertices[0].tolist() == [9, 9, 9]
    assert mesh.triangles.tolist() == [[1, 2, 3], [2, 4, 3]] and mesh.part_names == ("skin",)
    grouped = read_mesh(text.replace(b"usemtl a", b"g Skin").replace(b"usemtl b", b"g teeth upper"), "g.obj")
    assert grouped.part_names == ("skin", "teeth_upper") and np.array_equal(grouped.triangles, mesh.triangles)
    objects = read_mesh(b"o Head\n" + text.replace(b"usemtl b", b"o Eye.L"), "o.obj")
    assert objects.parts == ["head", "eye_l"] and len(objects.vertices) == 5
    with pytest.raises(MpegFaError) as err:
        read_mesh(b"v 0 0 0\nv 1 0 0\nf 1 2 3\n", "bad.obj")
    assert err.value.where == "bad.obj:3:7"


def _edited():
    ball = trimesh.creation.icosphere(1)
    parts = ["skin"] * len(ball.faces)
    parts[3] = parts[7] = "teeth_upper"
    return make_mesh(ball.vertices, ball.faces, parts, {"2.1": 5, "9.3": 11})


def test_saved_obj_reads_back_with_its_parts_and_points(tmp_path):
    mesh = _edited()
    save_model(mesh, tmp_path, "head", required_points=mesh.points)
    back = read_model(tmp_path / "head.obj")
    assert np.allclose(back.vertices, mesh.vertices) and np.array_equal(back.triangles, mesh.triangles)
    assert back.parts == mesh.parts and back.points == mesh.points and back.source == "head.obj"
    # and so does `mpeg4fa edit head.obj`
    with TestClient(create_app(tmp_path / "head.obj", out_dir=tmp_path), base_url=LOCAL) as client:
        model = client.get("/api/model").json()
        assert sorted(model["parts"]) == ["skin", "teeth_upper"]
        assert client.app.state.session.mesh.points == {"2.1": 5, "9.3": 11}
    # without the files beside it, it is one skin without points
    (tmp_path / "head.parts.json").unlink()
    (tmp_path / "head.points.json").unlink()
    alone = read_model(tmp_path / "head.obj")
    assert alone.part_names == ("skin",) and alone.points == {}


@pytest.mark.parametrize("parts, points, where, problem", [
    ({"parts": {"skin": [0, 1]}}, None, "head.parts.json", "is in no part"),
    ({"parts": {"skin": list(range(80)), "teeth": [0]}}, None, "head.parts.json: parts/teeth", "repeats a triangle"),
    ({"parts": {"skin": [10**6]}}, None, "head.parts.json: parts/skin", "outside 0..79"),
    ("[1, 2", None, "head.parts.json:1:6", "invalid JSON"),
    (None, {"2.1": 10**6}, "head.points.json", "vertex 1000000"),
    (None, {"2.1": [0.1, 0.2, 0.3]}, "head.points.json", "a position, not a vertex index"),
])
def test_bad_files_beside_a_saved_obj_name_themselves(tmp_path, parts, points, where, problem):
    save_model(_edited(), tmp_path, "head", required_points=["2.1", "9.3"])
    if parts is not None:
        (tmp_path / "head.parts.json").write_text(parts if isinstance(parts, str) else json.dumps(parts))
    if points is not None:
        (tmp_path / "head.points.json").write_text(json.dumps(points))
    with pytest.raises(MpegFaError) as err:
        read_model(tmp_path / "head.obj")
    assert err.value.where.endswith(where) and problem in err.value.message, str(err.value)


# ---- uploads of several files: the model and the files it names -------------------------------------

def _png() -> bytes:
    import io

    from PIL import Image
    out = io.BytesIO()
    Image.new("RGB", (4, 4), (200, 150, 120)).save(out, format="PNG")
    return out.getvalue()


def _gltf_files(image="skin.png") -> dict[str, bytes]:
    """The scene as a .gltf with two external buffers and, named in its JSON, an external image."""
    files = dict(_scene().export(file_type="gltf"))
    doc = json.loads(files.pop("model.gltf"))
    doc["images"] = [{"uri": image}]
    doc["textures"] = [{"source": 0}]
    files["head.gltf"] = json.dumps(doc).encode()
    files[image.rsplit("/", 1)[-1]] = _png()
    return files


def _post(client, files: dict[str, bytes] | list[tuple[str, bytes]]):
    items = files.items() if isinstance(files, dict) else files
    return client.post("/api/upload", files=[("file", (name, data, "application/octet-stream")) for name, data in items])


@pytest.fixture
def client(tmp_path):
    with TestClient(create_app(out_dir=tmp_path / "out", upload_limit=200_000), base_url=LOCAL) as c:
        yield c


def test_gltf_uploaded_with_its_buffers_and_image_loads(client):
    files = _gltf_files()
    assert sorted(files) == [f"gltf_buffer_{i}.bin" for i in range(4)] + ["head.gltf", "skin.png"]
    r = _post(client, files)
    assert r.status_code == 200, r.text
    assert sorted(r.json()["parts"]) == ["eye_l", "eye_r", "skin"] and r.json()["source"] == "head.gltf"
    _check_scene_mesh(client.app.state.session.mesh)
    assert r.json()["counts"]["triangles"] == 14


def test_gltf_upload_without_a_buffer_names_it(client):
    files = _gltf_files()
    del files["gltf_buffer_1.bin"], files["gltf_buffer_3.bin"], files["skin.png"]
    r = _post(client, files)
    assert r.status_code == 422 and r.json()["where"] == "head.gltf", r.json()
    error = r.json()["error"]
    assert "names gltf_buffer_1.bin, gltf_buffer_3.bin, skin.png, not among the uploaded files" in error, error


def test_obj_uploaded_with_its_sidecars_is_as_read_by_path(client, tmp_path):
    mesh = _edited()
    paths = save_model(mesh, tmp_path, "head", required_points=mesh.points)
    by_path = read_model(tmp_path / "head.obj")
    r = _post(client, {p.name: p.read_bytes() for p in paths})
    assert r.status_code == 200, r.text
    up = client.app.state.session.mesh
    assert up.parts == by_path.parts == mesh.parts and up.points == by_path.points == {"2.1": 5, "9.3": 11}
    assert np.array_equal(up.vertices, by_path.vertices) and np.array_equal(up.triangles, by_path.triangles)
    assert sorted(r.json()["parts"]) == ["skin", "teeth_upper"] and r.json()["points"] == {"2.1": 5, "9.3": 11}
    # the OBJ alone is one skin without points, as read by path without its sidecars
    alone = _post(client, {"head.obj": paths[0].read_bytes()}).json()
    assert alone["parts"] == ["skin"] and alone["points"] == {}
    # a bad sidecar names itself, the uploaded name
    r = _post(client, {"head.obj": paths[0].read_bytes(), "head.points.json": b'{"2.1": 100000}'})
    assert r.status_code == 422 and r.json()["where"] == "head.points.json" and "vertex 100000" in r.json()["error"]


def test_obj_upload_takes_its_mtl_and_texture():
    obj = b"mtllib head.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl skin\nf 1 2 3\n"
    mtl = b"newmtl skin\nKd 1 1 1\nmap_Kd -s 1 1 1 skin.png\n"
    mesh = read_upload([("head.obj", obj), ("head.mtl", mtl), ("skin.png", _png())])
    assert len(mesh.triangles) == 1 and mesh.part_names == ("skin",)


@pytest.mark.parametrize("files, where, problem", [
    ([("a.obj", b"v 0 0 0\n"), ("b.glb", b"glTF")], "a.obj, b.glb", "here 2 model files (a.obj, b.glb)"),
    ([("head.points.json", b"{}")], "head.points.json", "here no model file"),
    ([], "upload", "here no model file"),
    ([("head.obj", b"v 0 0 0\n"), ("other.points.json", b"{}")], "other.points.json",
     "other.points.json not used by head.obj"),
    ([("head.stl", b"solid x\nendsolid x\n"), ("head.parts.json", b"{}")], "head.parts.json", "not used by head.stl"),
    ([("head.obj", b"v 0 0 0\n"), ("x/head.obj", b"v 0 0 0\n")], "head.obj", "two uploaded files are named head.obj"),
])
def test_upload_sets_refused_with_one_error(files, where, problem):
    with pytest.raises(EditError) as err:
        read_upload(files)
    assert err.value.where == where and problem in err.value.message, str(err.value)


def test_upload_refusals_through_the_api(client):
    r = _post(client, [("a.obj", b"v 0 0 0\n"), ("b.obj", b"v 0 0 0\n")])
    assert r.status_code == 422 and "2 model files" in r.json()["error"], r.json()
    # the limit is on the whole request: two files each under it, together over it
    big = b"v 0 0 0\n" * 13_000
    r = _post(client, [("head.obj", big), ("head.points.json", big)])
    assert r.status_code == 413 and "all files together" in r.json()["error"], r.json()
    assert client.get("/api/model").status_code == 422  # nothing was loaded


def test_traversal_looking_names_are_only_keys_among_the_uploaded_files(client, tmp_path):
    """Folders in an uploaded name are dropped; a URI finds only an uploaded file of its last name: a real file
    on disk at the URI's path is never read."""
    mesh = _edited()
    paths = save_model(mesh, tmp_path, "head", required_points=mesh.points)
    r = _post(client, [("../../head.obj", paths[0].read_bytes()), ("..\\..\\head.parts.json", paths[2].read_bytes()),
                       ("/etc/head.points.json", paths[1].read_bytes())])
    assert r.status_code == 200, r.text
    assert r.json()["source"] == "head.obj" and r.json()["points"] == {"2.1": 5, "9.3": 11}
    files = _gltf_files()
    doc = json.loads(files["head.gltf"])
    doc["buffers"][0]["uri"] = "../../../gltf_buffer_0.bin"
    doc["buffers"][1]["uri"] = "%2E%2E/gltf%5Fbuffer%5F1.bin"
    files["head.gltf"] = json.dumps(doc).encode()
    assert _post(client, files).status_code == 200
    _check_scene_mesh(client.app.state.session.mesh)
    # a buffer at an absolute path that exists on disk: refused as missing from the upload, not read
    on_disk = tmp_path / "gltf_buffer_0.bin"
    on_disk.write_bytes(files.pop("gltf_buffer_0.bin"))
    doc["buffers"][0]["uri"] = str(on_disk)
    files["head.gltf"] = json.dumps(doc).encode()
    r = _post(client, files)
    assert r.status_code == 422 and str(on_disk) in r.json()["error"], r.json()


def _gltf_with_indices(indices: list[int]) -> bytes:
    """A one-triangle .gltf with its buffer embedded, three vertices and the given indices."""
    import base64

    positions = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32).tobytes()
    index_bytes = np.array(indices, np.uint16).tobytes() + b"\0\0"
    blob = positions + index_bytes
    return json.dumps({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]},
                      {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
    }).encode()


def test_a_mesh_whose_triangles_name_missing_vertices_is_an_error_naming_the_file():
    """Fuzz finding (gltf): make_mesh's 'indices must lie in 0..N' reached the user without the file's name."""
    assert len(read_mesh(_gltf_with_indices([0, 1, 2]), "ok.gltf").triangles) == 1
    with pytest.raises(MpegFaError) as info:
        read_mesh(_gltf_with_indices([0, 1, 7]), "broken.gltf")
    assert info.value.where and "broken.gltf" in info.value.where
