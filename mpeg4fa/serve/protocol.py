"""The live protocol of ``mpeg4fa serve``: one WebSocket, ``/ws``, JSON text messages and two binary kinds.

Client -> server (text, one JSON object each; anything else is answered with an ``error`` and
the connection stays open):

``{"type": "say", "text": "(joy, 40, 0.5) Hello there. How are you?", "id": "u1", "lang": "auto"}``
    Speak tagged text (the markup of :mod:`mpeg4fa.speech.markup`). ``id`` (optional, echoed),
    ``lang`` (``auto``, ``en``, ``zh``), ``voice`` and ``rate`` (espeak-ng words per minute) are
    optional. One utterance at a time: a ``say`` while one plays is refused (``busy``) unless
    a ``stop`` came first.
``{"type": "buffer", "received": 3.2, "buffered": 1.1}``
    Flow control. ``received``: the media time (s from the utterance's start) up to which the
    client holds frames and audio; ``buffered``: how much of that it has not played yet. The
    server takes ``received - buffered`` as the client's playhead and sends nothing that
    starts later than the playhead plus its window (``hello.window``). Before the first report
    the playhead is 0, so one window goes out at once. Report every ~100 ms of playing.
``{"type": "stop"}``
    End the current utterance now (a ``done`` with ``"stopped": true`` follows).

Server -> client, text:

``hello``      ``{"type": "hello", "protocol": 2, "fps": 25.0, "window": 2.0, "chunk": 0.2,
               "engine": "espeak", "stall_timeout": 30.0}`` on connecting.
``started``    ``{"type": "started", "id": ..., "sentences": n}``: the text was read.
``segment``    ``{"type": "segment", "id", "index", "start", "duration", "frames", "text", "rate",
               "bytes"}``: sentence ``index`` begins at media time ``start``; the next binary
               message is its face, the FBA bitstream itself (``bytes`` long, a complete
               fba_object of ``frames`` frames: decode it with fba.js or
               :func:`mpeg4fa.fba.iter_decode`; its frame timestamps plus ``start`` are media
               times; frames a skip folds in are absent: hold the previous one), and its audio
               follows in ``audio`` chunks at ``rate`` Hz. The page (``static/js/player.js``)
               decodes each one and poses its head from the FAPs (``static/js/head.js``), as the
               FBA player does; nothing else describes the face: 0.51 kbit/s of speech, where
               protocol 1's per-frame ARKit ``frames`` weights took 46.8 (92 times as much;
               ``tools/bench_serve.py``). A sentence's stream goes out whole when its start
               is within the window, so the face runs up to a sentence ahead of the audio.
``done``       ``{"type": "done", "id", "duration", "frames", "stopped"}``: nothing more for it.
``error``      ``{"type": "error", "error": one line, "where": the field, tag or step}``.

Server -> client, binary (little-endian): 4 bytes of kind, a float64 media time, the payload:
``FBA1`` + the media time of the stream's time 0 + one complete fba_object; ``AUD1`` + the chunk's
start + signed 16-bit mono PCM at the latest ``segment``'s ``rate``. Messages come in media-time
order. A page takes every ``FBA1`` message alike, whatever made it (a sentence spoken, or another
source of face frames on the same socket): decode, add the media time, play at that time.

The handshake must carry ``Origin: http://127.0.0.1:PORT`` (or ``localhost`` / ``[::1]``, the
server's own port) and a loopback ``Host``; anything else is answered 403 (:mod:`mpeg4fa.guard`).
A browser sends both by itself; a client outside one sends the origin
(:func:`mpeg4fa.serve.client.origin`). A message is read by :func:`mpeg4fa.jsonio.loads`: nested
deeper than 64 levels, or holding NaN or a number beyond a double, it gets an ``error`` like any
malformed message.

A client that sends no ``buffer`` report for ``stall_timeout`` seconds while the server has
something to send is told so (``error``, where ``flow``) and closed with code 1008; one that
closes mid-utterance ends its synthesis after the sentence under way.
"""
from __future__ import annotations

import math
import struct
from typing import Annotated, Literal, Union

from pydantic import BaseModel, ConfigDict, Field, TypeAdapter, ValidationError

from mpeg4fa.jsonio import JsonError, loads
from mpeg4fa.speech.markup import MAX_TEXT_CHARS

PROTOCOL = 2
FBA_KIND, AUDIO_KIND = b"FBA1", b"AUD1"
_HEAD = struct.Struct("<4sd")
MAX_SAY_CHARS = 20_000
"""The longest text one ``say`` may carry (a few minutes of speech); the markup reader's own limit is
larger (:data:`MAX_TEXT_CHARS`)."""
assert MAX_SAY_CHARS <= MAX_TEXT_CHARS


class ProtocolError(Exception):
    """A client message the server cannot take: answered with an ``error`` message, never a close."""

    def __init__(self, message: str, where: str) -> None:
        super().__init__(message)
        self.message, self.where = message, where


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Say(_Strict):
    type: Literal["say"]
    text: Annotated[str, Field(min_length=1, max_length=MAX_SAY_CHARS)]
    id: Annotated[str, Field(max_length=200)] | None = None
    lang: Literal["auto", "en", "zh"] = "auto"
    voice: Annotated[str, Field(max_length=100)] | None = None
    rate: Annotated[int, Field(ge=80, le=450)] | None = None


class Buffer(_Strict):
    type: Literal["buffer"]
    received: Annotated[float, Field(ge=0, allow_inf_nan=False)]
    buffered: Annotated[float, Field(ge=0, allow_inf_nan=False)]


class Stop(_Strict):
    type: Literal["stop"]


ClientMessage = Annotated[Union[Say, Buffer, Stop], Field(discriminator="type")]
_CLIENT = TypeAdapter(ClientMessage)


def parse_client(text: str | None, data: bytes | None = None) -> Say | Buffer | Stop:
    """One client message, validated; raises :class:`ProtocolError` saying what is wrong and where."""
    if text is None:
        raise ProtocolError(f"binary message of {len(data or b'')} bytes: the client sends JSON text only",
                            "message")
    try:
        raw = loads(text, "message", what="a message")
    except JsonError as exc:
        problem = f"not JSON: {exc.problem[len('invalid JSON: '):]}" if exc.problem.startswith("invalid JSON") \
            else exc.problem
        raise ProtocolError(problem + (f" (line {exc.line}, column {exc.column})" if exc.line else ""),
                            "message") from None
    if not isinstance(raw, dict):
        raise ProtocolError(f"a message is a JSON object, not {type(raw).__name__}", "message")
    if "type" not in raw:
        raise ProtocolError("no \"type\" (say, buffer or stop)", "type")
    if raw["type"] not in ("say", "buffer", "stop"):
        raise ProtocolError(f"unknown type {str(raw['type'])[:40]!r} (say, buffer or stop)", "type")
    try:
        return _CLIENT.validate_python(raw)
    except ValidationError as exc:
        first = exc.errors()[0]
        where = ".".join(str(p) for p in first["loc"][1:]) or "message"  # loc[0] is the union tag
        return _raise(f"{first['msg']}", where)


def _raise(message: str, where: str):
    raise ProtocolError(message, where)


def error_message(message: str, where: str) -> dict:
    return {"type": "error", "error": " ".join(str(message).split()), "where": where}


def pack(kind: bytes, t: float, payload: bytes) -> bytes:
    """A binary message: kind, media time, payload."""
    if not math.isfinite(t):
        raise ValueError(f"media time {t!r} is not finite")
    return _HEAD.pack(kind, t) + payload


def unpack(message: bytes) -> tuple[bytes, float, bytes]:
    """(kind, media time, payload) of a binary server message."""
    if len(message) < _HEAD.size:
        raise ValueError(f"binary message of {len(message)} bytes is shorter than its {_HEAD.size}-byte head")
    kind, t = _HEAD.unpack_from(message)
    return kind, t, message[_HEAD.size:]
