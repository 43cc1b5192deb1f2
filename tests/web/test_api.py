"""The editor's JSON API, in-process (FastAPI's TestClient), on meshes the tests make and the procedural head."""
import json
import os
import warnings

import numpy as np
import pytest
import trimesh
from fastapi.testclient import TestClient

from mpeg4fa.fdp.build import read_points_json
from mpeg4fa.web.app import create_app
from web.local import LOCAL


def obj_bytes(mesh: trimesh.Trimesh) -> bytes:
    return trimesh.exchange.obj.export_obj(mesh, include_normals=False, include_texture=False).encode()


@pytest.fixture
def client(tmp_path, procedural_face):
    out = tmp_path / "out"
    out.mkdir()
    with TestClient(create_app(out_dir=out, head=procedural_face, upload_limit=200_000), base_url=LOCAL) as c:
        c.out = out
        yield c


def upload(client, mesh, name="ball.obj"):
    return client.post("/api/upload", files={"file": (name, obj_bytes(mesh), "text/plain")})


def test_upload_edit_undo_save(client):
    ball = trimesh.creation.icosphere(2)
    r = upload(client, ball)
    assert r.status_code == 200, r.text
    model = r.json()
    assert model["counts"] == {"vertices": len(ball.vertices), "triangles": len(ball.faces)}
    assert np.allclose(np.reshape(model["positions"], (-1, 3)), ball.vertices)
    r = client.post("/api/edit", json={"edit": {"op": "delete_faces", "faces": [0]}})
    assert r.json()["counts"]["triangles"] == len(ball.faces) - 1 and r.json()["can_undo"]
    assert client.post("/api/undo").json()["counts"]["triangles"] == len(ball.faces)
    assert client.post("/api/redo").json()["counts"]["triangles"] == len(ball.faces) - 1
    client.post("/api/undo")
    client.post("/api/edit", json={"edit": {"op": "assign_point", "label": "2.1", "vertex": 7}})
    region = client.post("/api/region", json={"face": 0}).json()["faces"]
    assert len(region) == len(ball.faces)
    r = client.post("/api/save", json={"name": "ball", "required_points": ["2.1"]})
    assert r.status_code == 200, r.text
    assert sorted(os.listdir(client.out)) == ["ball.obj", "ball.parts.json", "ball.points.json"]
    assert read_points_json(client.out / "ball.points.json") == {"2.1": 7}
    back = trimesh.load(client.out / "ball.obj", process=False, maintain_order=True)
    assert np.allclose(back.vertices, ball.vertices) and len(back.faces) == len(ball.faces)
    assert json.loads((client.out / "ball.parts.json").read_text())["parts"]["skin"][:3] == [0, 1, 2]


def test_save_refuses_an_unfinished_model(client):
    upload(client, trimesh.creation.icosphere(1))
    r = client.post("/api/save", json={"name": "ball"})
    assert r.status_code == 422 and "84 feature points not placed" in r.json()["error"]
    assert os.listdir(client.out) == []


@pytest.mark.parametrize("name", ["../evil", "/tmp/evil", "a/b", "..", ".hidden", "x\\..\\y"])
def test_traversal_refused(client, name):
    upload(client, trimesh.creation.icosphere(1))
    r = client.post("/api/save", json={"name": name, "required_points": []})
    assert r.status_code == 422 and r.json()["where"] == "name", r.text
    assert os.listdir(client.out) == [] and not os.path.exists(client.out.parent / "evil.obj")


def test_symlink_out_of_the_folder_refused(client, tmp_path):
    (client.out / "link.obj").symlink_to(tmp_path / "elsewhere.obj")
    upload(client, trimesh.creation.icosphere(1))
    r = client.post("/api/save", json={"name": "link", "required_points": []})
    assert r.status_code == 422 and "outside" in r.json()["error"]
    assert not (tmp_path / "elsewhere.obj").exists()


def test_oversized_upload_refused(client):
    r = client.post("/api/upload", files={"file": ("big.obj", b"v 0 0 0\n" * 40_000, "text/plain")})
    assert r.status_code == 413 and set(r.json()) == {"error", "where"}


def test_malformed_json_is_one_error(client):
    r = client.post("/api/edit", content=b'{"edit": ', headers={"content-type": "application/json"})
    assert r.status_code == 400
    assert set(r.json()) == {"error", "where"} and r.json()["error"].startswith("invalid JSON")


def test_bad_requests_say_where(client):
    assert client.get("/api/model").json()["where"] == "session"
    upload(client, trimesh.creation.icosphere(1))
    r = client.post("/api/edit", json={"edit": {"op": "explode"}})
    assert r.status_code == 422 and r.json()["where"].startswith("edit")
    r = client.post("/api/edit", json={"edit": {"op": "delete_faces", "faces": [10**6]}})
    assert r.status_code == 422 and "face 1000000 does not exist" in r.json()["error"]
    r = client.post("/api/upload", files={"file": ("head.wrl", b"#VRML V2.0 utf8\n", "text/plain")})
    assert r.status_code == 422 and "VRML" in r.json()["error"]
    assert client.get("/nowhere").status_code == 404
    assert client.get("/nowhere").json()["where"] == "/nowhere"


def test_pose_moves_the_head(client, procedural_face):
    model = client.post("/api/load", json={"source": "head"}).json()
    assert model["counts"]["vertices"] == procedural_face.mesh.n_vertices
    fapu = client.get("/api/fapu").json()["fapu"]
    assert fapu == pytest.approx(procedural_face.fapu.as_dict())
    neutral = np.reshape(model["positions"], (-1, 3))
    posed = np.reshape(client.post("/api/pose", json={"faps": {"3": 400}}).json()["positions"], (-1, 3))
    jaw = procedural_face.mesh.fp_vertex[procedural_face.mesh.fp_index("2.1")]
    assert np.linalg.norm(posed[jaw] - neutral[jaw]) > 1
    # after deleting faces the vertices still move with their own head vertex
    client.post("/api/edit", json={"edit": {"op": "delete_part", "name": "tongue"}})
    again = np.reshape(client.post("/api/pose", json={"viseme": "AA"}).json()["positions"], (-1, 3))
    assert len(again) < len(posed) and np.abs(again - np.reshape(
        client.get("/api/model").json()["positions"], (-1, 3))).max() > 0.1
    r = client.post("/api/pose", json={"faps": {"1": 5}})
    assert r.status_code == 422 and "faps" in r.json()["where"]
    assert client.post("/api/pose", json={"faps": {"3": 400}}).json()["warnings"] == []
    with warnings.catch_warnings():  # fuzz of 2026-12-07: each clamped FAP was a console line, every request
        warnings.simplefilter("error")
        said = client.post("/api/pose", json={"faps": {str(f): 1e300 for f in range(3, 69)}}).json()["warnings"]
    assert len(said) >= 60 and all("1e+300" in w or "clamp" in w or "range" in w for w in said), said[:3]


def test_index_page_lists_the_api(client):
    r = client.get("/")
    assert r.status_code == 200 and "/api/edit" in r.text


def test_glb_with_two_meshes_loads_as_two_parts(client):
    scene = trimesh.Scene()
    scene.add_geometry(trimesh.creation.icosphere(1), geom_name="Skin")
    scene.add_geometry(trimesh.creation.box(), geom_name="teeth upper")
    r = client.post("/api/upload", files={"file": ("head.glb", scene.export(file_type="glb"), "model/gltf-binary")})
    assert r.status_code == 200, r.text
    assert sorted(r.json()["parts"]) == ["skin", "teeth_upper"]


@pytest.mark.usefixtures("generic_head_installed")
def test_the_generic_head_loads_poses_and_saves(tmp_path, generic_face):
    with TestClient(create_app(out_dir=tmp_path), base_url=LOCAL) as client:
        model = client.post("/api/load", json={"source": "head"}).json()
        assert model["counts"]["vertices"] == generic_face.mesh.n_vertices
        assert client.get("/api/fapu").json()["fapu"] == pytest.approx(generic_face.fapu.as_dict())
        posed = client.post("/api/pose", json={"expression": "joy"}).json()["positions"]
        assert np.abs(np.subtract(posed, model["positions"])).max() > 0.5
        assert client.post("/api/validate", json={}).json() == {"ok": True, "problems": []}
        assert client.post("/api/save", json={"name": "generic"}).status_code == 200
    points = read_points_json(tmp_path / "generic.points.json")
    assert len(points) == 84 and points["2.1"] == generic_face.mesh.fp_vertex[generic_face.mesh.fp_index("2.1")]
