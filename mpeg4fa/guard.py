"""The gate of the two local servers (``mpeg4fa edit`` and ``mpeg4fa serve``): their own page and
loopback clients only, and a request body cut at its limit as it streams.

Binding 127.0.0.1 keeps other machines out, not the user's own browser: any page it shows may post
a form to ``http://127.0.0.1:PORT/api/upload`` or open ``ws://127.0.0.1:PORT/ws``, and a name that
an attacker's DNS points at 127.0.0.1 (DNS rebinding) reads the answers. So every request passes
:class:`LocalOnly` first (an ASGI middleware, below both apps; neither imports the other):

- ``Host`` must be a loopback name (``localhost``, ``127.0.0.1``, ``[::1]``) with the server's own
  port: a rebound name (``evil.example:PORT``) is refused, whatever else the request carries.
- ``Origin``, when present, must be one of those same loopback origins (``http://127.0.0.1:PORT``...):
  a page of another site (or another local port, or ``null``) is refused on every route.
- A request without ``Origin`` is a non-browser client (curl, scripts) or a same-origin GET or a
  navigation; browsers send ``Origin`` on every cross-origin POST. It is let in on HTTP when the
  Host check passes; a browser's cross-site subresource GET (``Sec-Fetch-Site: cross-site`` or
  ``same-site`` outside a navigation, such as an ``<img>`` on another page) is refused too.
- A WebSocket handshake must carry a loopback ``Origin`` (browsers always send one; the Python
  client :mod:`mpeg4fa.serve.client` sends its server's own), so no page elsewhere can open one.

A refusal is ``403 {"error": one line, "where": "Host" | "Origin" | "Sec-Fetch-Site"}`` and nothing
of the app runs; a refused WebSocket handshake is closed before it is accepted, which the server
answers with a bare 403 (uvicorn logs an error for a handshake denied with a body of its own). A body larger than
``body_limit`` is refused with 413 at once when ``Content-Length`` says so, and otherwise (chunked
transfer) as soon as the bytes read pass the limit: reading stops there, so at most the limit (plus
what the server had read at once) was ever spooled. JSON the servers receive (bodies, uploaded
files, WebSocket messages) is read by the package's one reader, :mod:`mpeg4fa.jsonio` (nesting,
size and numbers capped).
"""
from __future__ import annotations

import json
import re
from collections.abc import Awaitable, Callable, MutableMapping
from typing import Any

LOOPBACK = ("localhost", "127.0.0.1", "[::1]")
"""The host names a local server answers to (with its own port)."""
_HOST = re.compile(r"^(localhost|127\.0\.0\.1|\[::1\])(?::(\d{1,5}))?$", re.IGNORECASE)
_ORIGIN = re.compile(r"^http://(localhost|127\.0\.0\.1|\[::1\])(?::(\d{1,5}))?$", re.IGNORECASE)

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]


def _port_of(scope: Scope) -> int | None:
    server = scope.get("server")
    return int(server[1]) if server and len(server) > 1 and server[1] is not None else None


def _matches(pattern: re.Pattern, value: str, port: int | None) -> bool:
    m = pattern.match(value)
    if m is None:
        return False
    given = int(m.group(2)) if m.group(2) else 80
    return port is None or given == port


def refusal(scope: Scope) -> tuple[str, str] | None:
    """Why this request (HTTP or WebSocket handshake) is refused, as (message, header), or None."""
    headers = {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", ())}
    port = _port_of(scope)
    own = f"http://127.0.0.1:{port}" if port else "http://127.0.0.1"
    host = headers.get("host", "")
    if not _matches(_HOST, host, port):
        return (f"Host {host[:80]!r} is not this server's loopback address "
                f"(localhost, 127.0.0.1 or [::1]{f' with port {port}' if port else ''}): open {own}/", "Host")
    origin = headers.get("origin")
    if origin is not None and not _matches(_ORIGIN, origin, port):
        return f"a page from {origin[:80]!r} may not use this server: only its own page ({own}) may", "Origin"
    if scope["type"] == "websocket" and origin is None:
        return f"a WebSocket handshake without an Origin header: send 'Origin: {own}'", "Origin"
    site, mode = headers.get("sec-fetch-site"), headers.get("sec-fetch-mode")
    if origin is None and site in ("cross-site", "same-site") and mode not in (None, "navigate"):
        return f"a request from another site's page ({site}, {mode}) may not use this server", "Sec-Fetch-Site"
    return None


class LocalOnly:
    """ASGI middleware: :func:`refusal` answered with 403, bodies over ``body_limit`` bytes with 413."""

    def __init__(self, app, *, body_limit: int) -> None:
        self.app, self.body_limit = app, int(body_limit)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            return await self.app(scope, receive, send)
        why = refusal(scope)
        if why is not None:
            return await _refuse(scope, send, 403, *why)
        if scope["type"] == "websocket":
            return await self.app(scope, receive, send)
        length = dict(scope.get("headers", ())).get(b"content-length", b"")
        if length.isdigit() and int(length) > self.body_limit:
            return await _refuse(scope, send, 413, f"request larger than {self.body_limit} bytes", "body")
        await self.app(scope, self._counted(receive), send)

    def _counted(self, receive: Receive) -> Receive:
        """``receive`` that stops the request once more than ``body_limit`` bytes came (chunked transfer):
        the route's reading fails with 413 there, and the rest of the body is never read."""
        seen = 0

        async def counted() -> Message:
            nonlocal seen
            message = await receive()
            if message["type"] == "http.request":
                seen += len(message.get("body", b""))
                if seen > self.body_limit:
                    from fastapi import HTTPException  # FastAPI passes its own HTTPException through body parsing

                    raise HTTPException(413, f"request larger than {self.body_limit} bytes")
            return message

        return counted


async def _refuse(scope: Scope, send: Send, status: int, error: str, where: str) -> None:
    body = json.dumps({"error": error, "where": where}).encode()
    head = [(b"content-type", b"application/json"), (b"content-length", str(len(body)).encode())]
    if scope["type"] == "http":
        await send({"type": "http.response.start", "status": status, "headers": head})
        await send({"type": "http.response.body", "body": body})
    else:  # a close before the accept: the server answers the handshake with 403
        await send({"type": "websocket.close", "code": 1008, "reason": error[:120]})
