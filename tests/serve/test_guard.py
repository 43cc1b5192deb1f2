"""``mpeg4fa serve`` lets in its own page and loopback clients only (issue 26 item 8): every route, found by
walking ``app.routes`` (the WebSocket too), answers a foreign Origin or Host with 403, and a WebSocket
handshake needs a loopback Origin; the Python client and a browser-like handshake get in."""
from __future__ import annotations

import base64
import json
import os
from pathlib import Path

import httpx
import pytest
from fastapi.routing import APIRoute, APIWebSocketRoute
from starlette.routing import Mount
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from mpeg4fa.serve.app import create_app
from serve.live_server import face_for_tests, running

FOREIGN = [
    {"origin": "http://evil.example"},  # the reproducer: any page the user visits
    {"origin": "null"},
    {"origin": "http://localhost:1"},  # another local port
    {"host": "evil.example:{port}"},  # DNS rebinding
    {"host": "evil.example:{port}", "origin": "http://evil.example:{port}"},
    {"sec-fetch-site": "cross-site", "sec-fetch-mode": "no-cors"},
]


@pytest.fixture(scope="module")
def server():
    app = create_app(face_for_tests(), engine="estimate")
    with running(app) as base:
        yield app, base


def requests_of(app) -> list[tuple[str, str]]:
    """(kind, path) of every route: "GET" for the pages and API, "WS" for WebSockets, one real file per mount."""
    out = []
    for route in app.routes:
        if isinstance(route, APIRoute):
            out += [(m, route.path) for m in sorted(route.methods - {"HEAD"})]
        elif isinstance(route, APIWebSocketRoute):
            out.append(("WS", route.path))
        elif isinstance(route, Mount):
            first = sorted(p for p in Path(route.app.directory).rglob("*") if p.is_file())[0]
            out.append(("GET", f"{route.path}/{first.relative_to(route.app.directory).as_posix()}"))
    return out


def handshake(http: httpx.Client, path: str, headers: dict) -> httpx.Response:
    """A WebSocket opening handshake as a browser sends it (with ``headers`` added), answered or refused."""
    key = base64.b64encode(os.urandom(16)).decode()
    return http.get(path, headers={"connection": "Upgrade", "upgrade": "websocket", "sec-websocket-version": "13",
                                   "sec-websocket-key": key, **headers})


def test_every_route_refuses_a_foreign_origin_or_host(server):
    app, base = server
    port = base.rsplit(":", 1)[1]
    routes = requests_of(app)
    assert ("WS", "/ws") in routes and ("GET", "/static/fap-head.glb") in routes
    with httpx.Client(base_url=base, timeout=30) as http:
        for kind, path in routes:
            for foreign in FOREIGN:
                headers = {k: v.format(port=port) for k, v in foreign.items()}
                r = handshake(http, path, headers) if kind == "WS" else http.request(kind, path, headers=headers)
                assert r.status_code == 403, (kind, path, headers, r.status_code)
                assert kind == "WS" or set(r.json()) == {"error", "where"}, r.text
        assert http.get("/api/info").status_code == 200  # curl, scripts: no Origin, a loopback Host
        assert http.get("/api/info", headers={"origin": base}).status_code == 200
        assert http.get("/", headers={"host": f"localhost:{port}"}).status_code == 200
        assert handshake(http, "/ws", {}).status_code == 403
    assert app.state.live.connections == 0 and not app.state.live.utterances


def test_the_websocket_takes_its_own_page_only(server):
    app, base = server
    url = base.replace("http://", "ws://") + "/ws"
    with pytest.raises(InvalidStatus) as refused:  # the reproducer: this was accepted and served
        connect(url, origin="http://evil.example", open_timeout=10)
    assert refused.value.response.status_code == 403
    with pytest.raises(InvalidStatus):
        connect(url, open_timeout=10)  # no Origin: not a page of this server
    for origin in (base, base.replace("127.0.0.1", "localhost")):
        with connect(url, origin=origin, open_timeout=10) as ws:  # what the page (and mpeg4fa.serve.client) sends
            assert json.loads(ws.recv(timeout=10))["type"] == "hello"
            ws.send("[" * 100_000)  # deep JSON: an error message, the socket stays open (it closed with 1006)
            answer = json.loads(ws.recv(timeout=10))
            assert answer["type"] == "error" and "nested more than 64 levels" in answer["error"]
            ws.send(json.dumps({"type": "stop"}))
    assert not app.state.live.utterances
