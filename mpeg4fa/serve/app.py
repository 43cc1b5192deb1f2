"""The live server (FastAPI): the player page, the head as GLB, and the ``/ws`` WebSocket of :mod:`.protocol`.

Per connection two tasks run: one reads the client's messages (``say``, ``buffer``, ``stop``;
malformed ones get an ``error`` and change nothing), one speaks the current utterance. That one
is a pipeline of two: a producer makes sentence after sentence in a worker thread
(:func:`.segments.make_segment`: speech and its FBA stream), at most one ready ahead of the one
being sent, and the sender passes each sentence's bitstream, then its audio, out in media-time
order as the client's buffer reports allow (:mod:`.flow`). So the first frame goes out once the
first sentence is made, and a slow or stalled client costs the server one sentence of memory.
The page decodes the bitstream itself (fba.js) and poses its head as the FBA player does.

HTTP routes: ``/`` (the live page), ``/static`` (its scripts), ``/vendor/three`` (three.js as
vendored for the editor, served from there), ``/api/info``; ``/player`` (the FBA player,
``static/fbaplayer.html``: streams decoded in the browser by fba.js); both pages pose the head
``/static/fap-head.glb`` with its rig ``/static/fap-head.json`` (:mod:`.fap_head`, built once);
``POST /api/head?name=FILE`` takes an FDP and answers where its calibrated head is (``/api/head/ID.glb``
and ``.json``, :mod:`.heads`). Unknown routes
answer ``{"error", "where"}`` with 404. Only the server's own page and loopback clients get in
(:class:`mpeg4fa.guard.LocalOnly`): a foreign ``Host`` or ``Origin``, or a WebSocket handshake without
``Origin``, is answered 403 before anything runs.
"""
from __future__ import annotations

import asyncio
import contextlib
import threading
import time
from collections import deque
from dataclasses import dataclass, field
from pathlib import Path

from fastapi import FastAPI, Request, WebSocket
from fastapi.responses import HTMLResponse, JSONResponse, RedirectResponse, Response
from fastapi.staticfiles import StaticFiles
from starlette.exceptions import HTTPException as StarletteHTTPException

from mpeg4fa.errors import MpegFaError
from mpeg4fa.face.model import FaceModel
from mpeg4fa.guard import LocalOnly
from mpeg4fa.serve import protocol
from mpeg4fa.serve.microphone import Microphone, is_microphone
from mpeg4fa.serve.heads import WORKER as HEAD_WORKER
from mpeg4fa.serve.heads import Heads
from mpeg4fa.serve.flow import STALL_TIMEOUT, WINDOW, Flow, Stalled
from mpeg4fa.serve.protocol import AUDIO_KIND, FBA_KIND, Buffer, ProtocolError, Say, Stop, error_message, pack
from mpeg4fa.serve.segments import Segment, chunks, make_segment
from mpeg4fa.serve.sentences import split_sentences

HOST = "127.0.0.1"
STATIC = Path(__file__).with_name("static")
THREE = Path(__file__).resolve().parents[1] / "web" / "static" / "vendor" / "three"
CHUNK = 0.2  # s of frames or audio per message
RECORDS = 100  # utterance records kept (for tests, benchmarks and a look at a running server)
CLOSE_POLICY = 1008  # WebSocket close code: policy violation (here: a stalled client)
BODY_LIMIT = 32 << 20  # bytes of an HTTP request body (only POST /api/head takes one: an FDP, photos included)


@dataclass
class Settings:
    engine: object
    face: FaceModel
    texture: object = None  # the skin's texture image, or None
    fps: float = 25.0
    window: float = WINDOW
    chunk: float = CHUNK
    stall_timeout: float = STALL_TIMEOUT
    utterances: deque = field(default_factory=lambda: deque(maxlen=RECORDS))  # the latest finished utterances
    connections: int = 0
    _glb_lock: threading.Lock = field(default_factory=threading.Lock)
    _fap_head: tuple[bytes, dict] | None = None
    heads: Heads = field(default_factory=Heads)

    def fap_head(self) -> tuple[bytes, dict]:
        """The pages' head (:mod:`.fap_head`: the GLB and the rig that poses it from FAPs), built once."""
        from mpeg4fa.serve.fap_head import fap_head

        with self._glb_lock:
            if self._fap_head is None:
                self._fap_head = fap_head(self.face, self.texture)
            return self._fap_head


def warm_up(settings: Settings) -> None:
    """Load the speech engine and compile the codec once, so the first ``say`` is not the slow one, and build
    the first microphone session's listener ahead (:meth:`Microphone.warm_up`)."""
    from mpeg4fa.serve.sentences import Sentence

    make_segment(Sentence(0, "Hello.", "Hello.", 0), 0.0, engine=settings.engine, fps=settings.fps)
    Microphone.warm_up(settings.fps)


def create_app(face: FaceModel | None = None, *, engine: str | object = "espeak", fps: float = 25.0,
               window: float = WINDOW, chunk: float = CHUNK, stall_timeout: float = STALL_TIMEOUT,
               warm: bool = False, texture=None) -> FastAPI:
    """The server's ASGI app. ``face``: the head to serve (default the generic head), ``texture``: its skin's
    (an ``(H, W, 3)`` uint8 image, e.g. the FDP's: ``serve --fdp``); ``engine``: a speech engine or its name;
    ``window``/``chunk``/``stall_timeout`` as in :mod:`.protocol`."""
    from mpeg4fa.speech.encoder import make_engine

    if not (window > 0 and chunk > 0 and stall_timeout > 0 and fps > 0):
        raise ValueError("window, chunk, stall_timeout and fps must be > 0")
    face = face if face is not None else FaceModel.default()
    settings = Settings(engine=make_engine(engine) if isinstance(engine, str) else engine, face=face, texture=texture, fps=float(fps), window=float(window), chunk=float(chunk),
                        stall_timeout=float(stall_timeout))
    if warm:
        warm_up(settings)
    app = FastAPI(title="mpeg4fa serve", docs_url=None, redoc_url=None, openapi_url=None)
    app.state.live = settings
    app.add_middleware(LocalOnly, body_limit=BODY_LIMIT)

    @app.exception_handler(StarletteHTTPException)
    async def _http(request: Request, exc: StarletteHTTPException):
        return JSONResponse({"error": str(exc.detail).lower(), "where": request.url.path}, status_code=exc.status_code)

    @app.get("/", response_class=HTMLResponse)
    def index():
        return (STATIC / "player.html").read_text(encoding="utf-8")

    @app.get("/api/info")
    def info():
        return hello(settings)

    @app.get("/player")
    def fba_player():
        """The FBA player page (fba.js decodes in the browser); relative URLs resolve under /static/."""
        return RedirectResponse("/static/fbaplayer.html")

    @app.get("/static/fap-head.glb")
    def fap_head_glb():
        return Response(settings.fap_head()[0], media_type="model/gltf-binary")

    @app.get("/static/fap-head.json")
    def fap_head_key():
        return JSONResponse(settings.fap_head()[1])

    @app.post("/api/head")
    async def calibrated_head(request: Request, name: str = "face.fdp"):
        """An FDP's bytes in; where the head calibrated to it is (its GLB and key), or what is wrong with it."""
        name = name.replace("/", "_")[:200] or "face.fdp"
        data = await request.body()
        try:
            return await asyncio.get_running_loop().run_in_executor(HEAD_WORKER, settings.heads.add, data, name)
        except MpegFaError as exc:
            message = f"{exc.message} ({exc.hint})" if exc.hint else exc.message
            return JSONResponse({"error": " ".join(message.split()), "where": exc.where or name}, status_code=400)

    @app.get("/api/head/{ident}.glb")
    def calibrated_glb(ident: str):
        made = settings.heads.get(ident)
        if made is None:
            raise StarletteHTTPException(404, "no such head (made by POST /api/head)")
        return Response(made[0], media_type="model/gltf-binary")

    @app.get("/api/head/{ident}.json")
    def calibrated_key(ident: str):
        made = settings.heads.get(ident)
        if made is None:
            raise StarletteHTTPException(404, "no such head (made by POST /api/head)")
        return JSONResponse(made[1])

    app.mount("/static", StaticFiles(directory=STATIC), name="static")
    app.mount("/vendor/three", StaticFiles(directory=THREE), name="three")

    @app.websocket("/ws")
    async def ws(socket: WebSocket):
        await socket.accept()
        settings.connections += 1
        try:
            await Connection(socket, settings).run()
        finally:
            settings.connections -= 1

    return app


def hello(settings: Settings) -> dict:
    return {"type": "hello", "protocol": protocol.PROTOCOL, "fps": settings.fps, "window": settings.window,
            "chunk": settings.chunk, "stall_timeout": settings.stall_timeout,
            "engine": getattr(settings.engine, "name", type(settings.engine).__name__)}


class _Gone(Exception):
    """The client went away (or was closed) while the server was sending."""


class Connection:
    """One client: its message loop, its flow control and its utterance task."""

    def __init__(self, socket: WebSocket, settings: Settings) -> None:
        self.socket, self.settings = socket, settings
        self.flow = Flow(settings.window, settings.stall_timeout)
        self.task: asyncio.Task | None = None
        self.send_lock = asyncio.Lock()
        self.closed = False
        self.microphone: Microphone | None = None  # live lip sync of the page's microphone (:mod:`.microphone`)

    async def send(self, message: dict | bytes) -> None:
        if self.closed:
            raise _Gone
        try:
            async with self.send_lock:
                if isinstance(message, bytes):
                    await self.socket.send_bytes(message)
                else:
                    await self.socket.send_json(message)
        except Exception as exc:  # the peer is gone: Starlette, uvicorn and websockets each say it their way
            self.closed = True
            raise _Gone from exc

    async def run(self) -> None:
        try:
            await self.send(hello(self.settings))
            while not self.closed:
                message = await self.socket.receive()
                if message["type"] == "websocket.disconnect":
                    break
                await self.handle(message.get("text"), message.get("bytes"))
        except (_Gone, RuntimeError):  # RuntimeError: receive after the server closed a stalled client
            pass
        finally:
            self.closed = True
            await self.cancel()
            if self.microphone is not None:
                await self.microphone.close()

    async def handle(self, text: str | None, data: bytes | None) -> None:
        if is_microphone(data):
            if self.microphone is None:
                self.microphone = Microphone(self.send, self.settings.fps)
            await self.microphone.take(data)
            return
        try:
            message = protocol.parse_client(text, data)
        except ProtocolError as exc:
            await self.send(error_message(exc.message, exc.where))
            return
        if isinstance(message, Buffer):
            self.flow.report(message.received, message.buffered)
        elif isinstance(message, Stop):
            await self.cancel()
        elif isinstance(message, Say):
            if self.task is not None and not self.task.done():
                await self.send(error_message("an utterance is playing: send stop first, or wait for its done",
                                              "busy"))
                return
            self.task = asyncio.create_task(self.utter(message, time.monotonic()))

    async def cancel(self) -> None:
        task, self.task = self.task, None
        if task is not None and not task.done():
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, _Gone):
                await task

    # ---- one utterance -------------------------------------------------------------------------
    async def utter(self, say: Say, received_at: float) -> None:
        record = {"id": say.id, "sentences": 0, "frames": 0, "duration": 0.0, "first_frame_after": None,
                  "stopped": False, "stalled": False, "error": None}
        produced: asyncio.Queue = asyncio.Queue(maxsize=1)  # one sentence made ahead of the one being sent
        producer = None
        try:
            try:
                sentences = split_sentences(say.text, name="text")
            except MpegFaError as exc:
                record["error"] = str(exc)
                await self.send(error_message(f"{exc.message} ({exc.hint})" if exc.hint else exc.message,
                                              exc.where or "text"))
                return
            if not sentences:
                record["error"] = "nothing to say"
                await self.send(error_message("the text has nothing to speak (only tags or spaces)", "text"))
                return
            record["sentences"] = len(sentences)
            self.flow.restart()
            await self.send({"type": "started", "id": say.id, "sentences": len(sentences)})
            producer = asyncio.create_task(self.produce(sentences, say, produced))
            while (segment := await produced.get()) is not None:
                if isinstance(segment, BaseException):
                    raise segment
                await self.send_segment(segment, say, record, received_at)
            await self.send({"type": "done", "id": say.id, "duration": record["duration"],
                             "frames": record["frames"], "stopped": False,
                             "first_frame_after": record["first_frame_after"]})
        except MpegFaError as exc:  # the engine could not speak a sentence, say
            record["error"] = str(exc)
            with contextlib.suppress(_Gone):
                await self.send(error_message(f"{exc.message} ({exc.hint})" if exc.hint else exc.message,
                                              exc.where or "speech"))
        except Stalled as exc:
            record["stalled"] = True
            with contextlib.suppress(_Gone):
                await self.send(error_message(f"client stalled: {exc}", "flow"))
            self.closed = True
            with contextlib.suppress(Exception):
                await self.socket.close(code=CLOSE_POLICY, reason="stalled")
        except asyncio.CancelledError:
            record["stopped"] = True
            with contextlib.suppress(_Gone):
                if not self.closed:
                    await self.send({"type": "done", "id": say.id, "duration": record["duration"],
                                     "frames": record["frames"], "stopped": True,
                                     "first_frame_after": record["first_frame_after"]})
            raise
        except _Gone:
            record["stopped"] = True
        finally:
            if producer is not None:
                producer.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await producer
            record["waits"], record["reports"] = self.flow.waits, self.flow.reports
            self.settings.utterances.append(record)

    async def produce(self, sentences, say: Say, out: asyncio.Queue) -> None:
        s = self.settings
        start = 0.0
        try:
            for sentence in sentences:
                segment = await asyncio.to_thread(make_segment, sentence, start, engine=s.engine,
                                                  lang=say.lang, voice=say.voice, rate=say.rate, fps=s.fps)
                start = segment.end
                await out.put(segment)
            await out.put(None)
        except asyncio.CancelledError:
            raise
        except BaseException as exc:  # handed to the sender, which reports it
            await out.put(exc)

    async def send_segment(self, segment: Segment, say: Say, record: dict, received_at: float) -> None:
        await self.flow.wait_for(segment.start)
        await self.send({"type": "segment", "id": say.id, "index": segment.index, "start": segment.start,
                         "duration": segment.duration, "frames": len(segment.times), "text": segment.text,
                         "rate": segment.rate, "bytes": len(segment.fba)})
        await self.send(pack(FBA_KIND, segment.start, segment.fba))
        if record["first_frame_after"] is None:
            record["first_frame_after"] = time.monotonic() - received_at
        record["frames"] += len(segment.times)
        for t, samples in chunks(segment, self.settings.chunk):
            await self.flow.wait_for(t)
            await self.send(pack(AUDIO_KIND, t, samples.tobytes()))
        record["duration"] = segment.end
