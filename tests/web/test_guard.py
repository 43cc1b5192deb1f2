"""The editor lets in its own page and loopback clients only, refuses what its model cannot hold before
taking it, and cuts an upload at its limit as it streams (issue 26 item 8).

Every route of the app is found by walking ``app.routes``, so a new route is covered without a new test."""
from __future__ import annotations

import io
import json
import os
import socket
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from fastapi.routing import APIRoute
from fastapi.testclient import TestClient
from PIL import Image
from starlette.routing import Mount

from mpeg4fa.web.app import FORM_SLACK, create_app
from serve.live_server import running
from web.local import LOCAL

PORT = 8765  # LOCAL's
OWN = [{"origin": f"http://127.0.0.1:{PORT}"}, {"origin": f"http://localhost:{PORT}"},
       {"host": f"localhost:{PORT}"}, {"host": f"[::1]:{PORT}", "origin": f"http://[::1]:{PORT}"}, {}]
FOREIGN = [
    {"origin": "http://evil.example"},  # a cross-site form or fetch
    {"origin": "null"},  # a sandboxed frame, a file:// page
    {"origin": "http://127.0.0.1:9999"},  # another local server's page
    {"origin": f"https://127.0.0.1:{PORT}"},
    {"host": f"evil.example:{PORT}"},  # DNS rebinding: the name resolves to 127.0.0.1
    {"host": f"evil.example:{PORT}", "origin": f"http://evil.example:{PORT}"},
    {"host": "127.0.0.1:9999"},
    {"host": ""},
    {"sec-fetch-site": "cross-site", "sec-fetch-mode": "no-cors"},  # an <img> on another site's page
]


def obj_bytes(mesh: trimesh.Trimesh) -> bytes:
    return trimesh.exchange.obj.export_obj(mesh, include_normals=False, include_texture=False).encode()


def png(width: int = 240, height: int = 300) -> bytes:
    pixels = (np.random.default_rng(0).random((height, width, 3)) * 255).astype(np.uint8)
    buf = io.BytesIO()
    Image.fromarray(pixels).save(buf, "PNG")
    return buf.getvalue()


def requests_of(app) -> list[tuple[str, str]]:
    """(method, path) of every route: the API's methods, and one real file of each static mount."""
    out = []
    for route in app.routes:
        if isinstance(route, APIRoute):
            out += [(m, route.path) for m in sorted(route.methods - {"HEAD"})]
        elif isinstance(route, Mount):
            first = sorted(p for p in Path(route.app.directory).rglob("*") if p.is_file())[0]
            out.append(("GET", f"{route.path}/{first.relative_to(route.app.directory).as_posix()}"))
    return out


def bodies(path: str) -> dict:
    """A request body that changes the editor's state when let in (any other route: an empty JSON object)."""
    return {
        "/api/upload": {"files": {"file": ("ball.obj", obj_bytes(trimesh.creation.icosphere(1)), "text/plain")}},
        "/api/load": {"json": {"source": "head"}},
        "/api/edit": {"json": {"edit": {"op": "delete_faces", "faces": [0]}}},
        "/api/save": {"json": {"name": "stolen", "required_points": []}},
        "/api/photos": {"files": {"front": ("f.png", png(), "image/png"), "side": ("s.png", png(), "image/png")}},
        "/api/export": {"json": {"name": "stolen"}},
    }.get(path, {"json": {}})


@pytest.fixture
def client(tmp_path, procedural_face):
    out = tmp_path / "out"
    out.mkdir()
    with TestClient(create_app(out_dir=out, head=procedural_face, upload_limit=2_000_000), base_url=LOCAL) as c:
        c.out = out
        assert c.post("/api/load", json={"source": "head"}).status_code == 200
        yield c


def state(client) -> tuple:
    s = client.app.state.session
    return s.mesh, len(s.undo_stack), len(s.redo_stack), sorted(os.listdir(client.out))


def test_every_route_refuses_a_foreign_origin_or_host_and_changes_nothing(client):
    routes = requests_of(client.app)
    assert ("POST", "/api/upload") in routes and ("GET", "/") in routes and len(routes) >= 18
    before = state(client)
    for method, path in routes:
        for headers in FOREIGN:
            r = client.request(method, path, headers=headers, **(bodies(path) if method == "POST" else {}))
            assert r.status_code == 403, (method, path, headers, r.status_code, r.text[:200])
            assert set(r.json()) == {"error", "where"} and r.json()["where"] in ("Host", "Origin", "Sec-Fetch-Site")
    assert state(client) == before  # the same model object, no undo step, nothing saved
    assert client.get("/api/photos").json()["loaded"] is False


def test_the_issue_reproducer_a_cross_site_upload_is_refused_and_the_page_s_own_works(client):
    mesh = client.app.state.session.mesh
    upload = bodies("/api/upload")
    r = client.post("/api/upload", headers={"origin": "http://evil.example", "host": f"evil.example:{PORT}"}, **upload)
    assert r.status_code == 403 and client.app.state.session.mesh is mesh
    assert "Host 'evil.example:8765'" in r.json()["error"]
    r = client.post("/api/upload", headers={"origin": "http://evil.example"}, **upload)
    assert r.status_code == 403 and r.json()["where"] == "Origin" and client.app.state.session.mesh is mesh
    for headers in OWN:  # the page (with its Origin on a POST), curl and scripts (none) on any loopback name
        r = client.post("/api/upload", headers=headers, **upload)
        assert r.status_code == 200, (headers, r.text)
        assert client.get("/api/model", headers=headers).status_code == 200
    assert client.app.state.session.mesh is not mesh
    assert client.get("/", headers={"sec-fetch-site": "cross-site", "sec-fetch-mode": "navigate"}).status_code == 200


def raw(body) -> dict:
    """A JSON body as Python writes it, NaN and Infinity included (httpx's ``json=`` refuses them)."""
    return {"content": json.dumps(body).encode(), "headers": {"content-type": "application/json"}}


def move(delta=None, positions=None, vertices=(0,)):
    edit = {"op": "move_vertices", "vertices": list(vertices)}
    edit.update({"delta": delta} if delta is not None else {"positions": positions})
    return raw({"edit": edit})


HUGE = 2**70
ABSURD = {
    "/api/load": [{"json": {"source": "x" * 1000}}],
    "/api/upload": [{"files": {"file": ("far.obj", b"v 1e308 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n", "text/plain")}},
                    {"files": {"file": ("nan.obj", b"v nan 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\n", "text/plain")}},
                    {"files": {"file": ("deep.gltf", b"[" * 100_000, "text/plain")}},
                    {"files": [("file", ("m.obj", obj_bytes(trimesh.creation.box()), "text/plain")),
                               ("file", ("m.parts.json", b"[" * 100_000, "text/plain"))]}],
    "/api/edit": [move(delta=[1e308, 0, 0]), move(delta=[2e9, 0, 0]), move(positions=[[1e308, 1e308, 1e308]]),
                  move(delta=[float("nan"), 0, 0]), move(positions=[[float("inf"), 0, 0]]),
                  move(delta=[1, 0, 0], vertices=[HUGE]), move(delta=[1, 0, 0], vertices=[-1]),
                  {"json": {"edit": {"op": "delete_faces", "faces": [HUGE]}}},
                  {"json": {"edit": {"op": "delete_vertices", "vertices": [2**63]}}},
                  {"json": {"edit": {"op": "fill_hole", "loop": [HUGE, 1, 2]}}},
                  {"json": {"edit": {"op": "split_part", "faces": [HUGE], "name": "x"}}},
                  {"json": {"edit": {"op": "assign_point", "label": "2.1", "vertex": HUGE}}},
                  {"json": {"edit": {"op": "mirror_points", "labels": ["1e308"]}}},
                  {"content": b'{"edit": ' + b"[" * 100_000, "headers": {"content-type": "application/json"}}],
    "/api/undo": [{}], "/api/redo": [{}],
    "/api/region": [{"json": {"face": HUGE}}, {"json": {"face": 2**63}}],
    "/api/validate": [{"json": {"required_points": ["1e308"] * 1000}}],
    "/api/save": [{"json": {"name": "x" * 100_000}}],
    "/api/pose": [{"json": {"faps": {"3": 1e308, "48": -1e308}}}, raw({"faps": {"3": float("nan")}}),
                  {"json": {"intensity": HUGE}}],
    "/api/photos": [{"files": {"front": ("f.png", b"\x89PNG\r\n\x1a\n" + b"\xff" * 100, "image/png"),
                               "side": ("s.png", png(), "image/png")}}],
    "/api/photos/box": [{"json": {"view": "front", "box": [-1e308, -1e308, 1e308, 1e308]}},
                        {"json": {"view": "front", "box": [0, 0, 1e12, 1e12]}},
                        {"json": {"view": "front", "box": [10, 10, 100, 100],
                                  "dragged": {"front": {"9.3": [1e308, 0]}}}},
                        raw({"view": "front", "box": [0, 0, float("nan"), 10]})],
    "/api/calibrate": [{"json": {"front": {k: [1e308 * (i % 2), -1e308] for i, k in enumerate(("9.3", "2.1", "11.1"))},
                                 "side": {k: [1e307, 1e308] for k in ("9.3", "2.1", "11.1")}}}],
    "/api/export": [{"json": {"name": "x" * 100_000}}],
    "/api/photos/find": [{"json": {"view": "x" * 100_000}}, {"json": {"view": "front", "extra": HUGE}},
                         {"content": b'{"view": ' + b"[" * 100_000, "headers": {"content-type": "application/json"}}],
}


@pytest.mark.filterwarnings("ignore:FAP .* is outside")  # the pose clamps (and warns), as a decoder does
def test_absurd_values_on_every_route_are_refused_and_the_model_stays_served(client):
    """No 500 on any POST route, and GET /api/model answers 200 with the model as it was after each."""
    posts = {path for method, path in requests_of(client.app) if method == "POST"}
    assert set(ABSURD) == posts, "a new POST route needs its absurd requests here"
    r = client.post("/api/photos", **bodies("/api/photos"))  # the photo routes get photos to work on
    assert r.status_code == 200, r.text
    model = client.get("/api/model").json()
    for path, requests in ABSURD.items():
        for req in requests:
            r = client.post(path, **req)
            label = (path, json.dumps(req.get("json")) if "json" in req else req.get("content", list(req)))
            assert r.status_code < 500 and set(r.json()) >= {"error", "where"} or r.status_code == 200, (label, r.text)
            if path not in ("/api/pose", "/api/validate"):  # those answer, clamped or with problems; all else refuses
                assert r.status_code in (400, 413, 422), (label, r.status_code, r.text[:200])
            after = client.get("/api/model")
            assert after.status_code == 200 and after.json() == model, str(label)[:200]
    assert client.get("/api/fapu").status_code == 200 and os.listdir(client.out) == []


def test_a_move_by_1e308_is_422_before_it_is_applied(client):
    """The issue's reproducer: this answered 500, and every GET /api/model 500 after it until undo."""
    r = client.post("/api/edit", **move(delta=[1e308, 0, 0]))
    assert r.status_code == 422 and r.json()["where"] == "edit.move_vertices.delta.0", r.text
    assert client.get("/api/model").status_code == 200
    y = client.get("/api/model").json()["positions"][1]
    r = client.post("/api/edit", **move(delta=[0, 1e9 - y / 2, 0]))  # each number in range, the sum not
    assert r.status_code == 422 and "within +-1e+09" in r.json()["error"] and r.json()["where"] == "vertices", r.text
    assert not client.get("/api/model").json()["can_undo"]  # nothing was applied
    r = client.post("/api/edit", **move(delta=[1.5, 0, 0]))
    assert r.status_code == 200 and r.json()["can_undo"]


def chunked_upload(base: str, total: int, chunk: int = 65536) -> tuple[bytes, int]:
    """POST ``total`` bytes of one multipart file to /api/upload with chunked transfer (no Content-Length),
    chunk by chunk, stopping once an answer is there; (the answer's bytes, the bytes sent)."""
    host, port = base.removeprefix("http://").split(":")
    boundary = "b0undary"
    head = (f"--{boundary}\r\nContent-Disposition: form-data; name=\"file\"; filename=\"big.obj\"\r\n"
            "Content-Type: text/plain\r\n\r\n").encode()
    line = b"v 0 0 0\n" * (chunk // 8)
    sent, answer = 0, b""
    with socket.create_connection((host, int(port)), timeout=10) as s:
        s.sendall((f"POST /api/upload HTTP/1.1\r\nHost: {host}:{port}\r\nTransfer-Encoding: chunked\r\n"
                   f"Content-Type: multipart/form-data; boundary={boundary}\r\n\r\n").encode())
        s.sendall(b"%x\r\n%s\r\n" % (len(head), head))
        s.setblocking(False)
        try:
            while sent < total:
                try:
                    answer += s.recv(65536)
                    break  # the server answered (or closed): stop sending
                except BlockingIOError:
                    pass
                try:
                    s.sendall(b"%x\r\n%s\r\n" % (len(line), line))
                    sent += len(line)
                except BlockingIOError:  # the server stopped reading: wait for its answer
                    time.sleep(0.01)
        except (BrokenPipeError, ConnectionResetError):
            pass
        s.settimeout(10)
        try:
            while not complete(answer):
                data = s.recv(65536)
                if not data:
                    break
                answer += data
        except (ConnectionResetError, TimeoutError, socket.timeout):
            pass
    return answer, sent


def complete(answer: bytes) -> bool:
    """Whether ``answer`` holds an HTTP response's head and all the body its Content-Length says."""
    head, sep, body = answer.partition(b"\r\n\r\n")
    lengths = [line.split(b":", 1)[1] for line in head.lower().split(b"\r\n") if line.startswith(b"content-length:")]
    return bool(sep) and bool(lengths) and len(body) >= int(lengths[0])


def open_temp_files() -> int:
    """Files this process holds open in the temporary folder (the multipart parser's spooled uploads)."""
    import tempfile

    tmp = os.path.realpath(tempfile.gettempdir())
    count = 0
    for fd in os.listdir("/proc/self/fd"):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        count += target.startswith(tmp + "/")
    return count


def test_a_chunked_upload_is_cut_at_the_limit_as_it_streams(tmp_path, procedural_face):
    """The issue's reproducer: a chunked 300 MB upload was refused only after 237 MiB had been spooled to disk.
    Here 20 MB are offered against a 1 MB limit; the app must stop reading within a chunk or two of it."""
    limit = 1_000_000
    app = create_app(out_dir=tmp_path, head=procedural_face, upload_limit=limit)
    read = {"bytes": 0}

    async def counting(scope, receive, send):  # what the server hands the app: the bytes it read for it
        async def counted():
            message = await receive()
            read["bytes"] += len(message.get("body", b""))
            return message
        await app(scope, counted, send)

    files_before = open_temp_files()
    with running(counting) as base:
        answer, sent = chunked_upload(base, 20_000_000)
    status = answer.split(b"\r\n", 1)[0]
    assert b" 413 " in status, answer[:300]
    body = json.loads(answer.split(b"\r\n\r\n", 1)[1])
    assert "larger than" in body["error"]
    # the limit with the form's slack, plus at most what the server had read from the socket at once (asyncio
    # reads up to 256 KiB): nowhere near the 20 MB offered, which the old code read to the end
    assert read["bytes"] <= limit + FORM_SLACK + 2 * 262144, read
    assert sent < 20_000_000  # the client was stopped, not drained
    assert app.state.session.mesh is None
    assert open_temp_files() <= files_before  # no spooled part left open (they are unlinked: gone with the fd)


@pytest.mark.parametrize("files, where", [
    ([("deep.gltf", b"[" * 100_000)], "deep.gltf:1:65"),
    ([("m.obj", obj_bytes(trimesh.creation.box())), ("m.parts.json", b'{"parts": ' + b"[" * 100_000)],
     "m.parts.json:1:74"),
])
def test_deep_json_in_an_upload_is_one_json_error(client, files, where):
    """The issue's reproducer: a 100,000-deep .gltf or NAME.parts.json gave a plain-text 500."""
    mesh = client.app.state.session.mesh
    r = client.post("/api/upload", files=[("file", (name, data, "text/plain")) for name, data in files])
    assert r.status_code == 422 and r.json()["where"] == where and "nested more than 64" in r.json()["error"], r.text
    assert client.app.state.session.mesh is mesh


@pytest.mark.parametrize("kind, headers, refused", [
    ("http", {"host": "127.0.0.1:8765"}, None),
    ("http", {"host": "LOCALHOST:8765", "origin": "http://Localhost:8765"}, None),
    ("http", {"host": "[::1]:8765", "origin": "http://[::1]:8765"}, None),
    ("http", {"host": "127.0.0.1:8765", "sec-fetch-site": "same-origin", "sec-fetch-mode": "cors"}, None),
    ("http", {"host": "127.0.0.1:8765", "sec-fetch-site": "cross-site", "sec-fetch-mode": "navigate"}, None),
    ("websocket", {"host": "127.0.0.1:8765", "origin": "http://localhost:8765"}, None),
    ("http", {"host": "127.0.0.1"}, "Host"),  # port 80, not the server's
    ("http", {"host": "127.0.0.1.evil.example:8765"}, "Host"),
    ("http", {"host": "localhost.:8765"}, "Host"),
    ("http", {"host": "127.0.0.2:8765"}, "Host"),
    ("http", {}, "Host"),
    ("http", {"host": "127.0.0.1:8765", "origin": "http://127.0.0.1:8765/"}, "Origin"),
    ("http", {"host": "127.0.0.1:8765", "origin": "http://127.0.0.1:8765.evil.example"}, "Origin"),
    ("http", {"host": "127.0.0.1:8765", "origin": "http://127.0.0.1:87650"}, "Origin"),
    ("http", {"host": "127.0.0.1:8765", "sec-fetch-site": "same-site", "sec-fetch-mode": "no-cors"}, "Sec-Fetch-Site"),
    ("websocket", {"host": "127.0.0.1:8765"}, "Origin"),
])
def test_the_rules(kind, headers, refused):
    from mpeg4fa.guard import refusal

    scope = {"type": kind, "server": ("127.0.0.1", 8765),
             "headers": [(k.encode(), v.encode()) for k, v in headers.items()]}
    why = refusal(scope)
    assert (why and why[1]) == refused, why
