"""``mpeg4fa serve``: the live streaming server on 127.0.0.1 (a thin shell over :mod:`mpeg4fa.serve`)."""
from __future__ import annotations

import argparse
import socket
import threading
import webbrowser

from . import options
from .model import face_options
from .options import Commands

DEFAULT_PORT = 8766


def register(commands: Commands) -> None:
    from ..serve.flow import STALL_TIMEOUT, WINDOW
    from ..speech.encoder import ENGINES

    p = commands.add_parser(
        "serve", help="speak tagged text live to a browser or any WebSocket client (127.0.0.1 only)",
        description="Start the live server on 127.0.0.1 only and open its player page. A client sends tagged "
                    "text over ws://127.0.0.1:PORT/ws; the server speaks it sentence by sentence and streams "
                    "each sentence's FBA bitstream and its audio, never more than --window seconds ahead of what "
                    "the client reports it has played. The page (http://127.0.0.1:PORT/) decodes the stream "
                    "itself (fba.js) and plays it on the head with three.js and WebAudio; "
                    "http://127.0.0.1:PORT/player plays .fba files. "
                    "The protocol is documented in mpeg4fa/serve/protocol.py. Only the server's own page and "
                    "clients on this machine get in: a WebSocket client outside a browser sends 'Origin: "
                    "http://127.0.0.1:PORT' (browsers send their page's); another site's Origin, or a Host other "
                    "than localhost, 127.0.0.1 or [::1] with the port, is refused (403).")
    p.add_argument("--port", type=options.port, default=DEFAULT_PORT,
                   help=f"port (default {DEFAULT_PORT})")
    p.add_argument("--engine", choices=ENGINES, default="espeak", help="speech engine (default espeak)")
    p.add_argument("--window", type=options.real(0.2, 60.0, what="window"), default=WINDOW,
                   help=f"seconds of media sent ahead of the client's playhead (default {WINDOW:g})")
    p.add_argument("--stall-timeout", type=options.real(1.0, 3600.0, what="stall timeout"), default=STALL_TIMEOUT,
                   help=f"close a client silent this many seconds with the window full (default {STALL_TIMEOUT:g})")
    face_options(p)
    p.add_argument("--no-browser", action="store_true", help="do not open the page")
    p.set_defaults(run=run_serve)


def run_serve(args: argparse.Namespace) -> int:
    from ..extras import require

    require("web", "fastapi", "uvicorn", "websockets")
    from ..serve.app import HOST, create_app
    from .local_server import run_until_stopped
    from .model import face_from_args

    with socket.socket() as probe:  # a port in use is one line now, not a log from uvicorn after the set-up
        try:
            probe.bind((HOST, args.port))
        except OSError as exc:
            raise OSError(exc.errno, f"port {args.port} on {HOST}: {exc.strerror}") from None
    face = face_from_args(args)
    texture = None
    if args.fdp is not None:  # the page's head wears the texture the FDP carries, as play --fdp shows it
        from ..serve.heads import fdp_texture

        texture = fdp_texture(face, args.fdp)
    app = create_app(face, texture=texture, engine=args.engine, window=args.window, stall_timeout=args.stall_timeout,
                     warm=True)
    url = f"http://{HOST}:{args.port}/"
    print(f"mpeg4fa serve: serving {url} (WebSocket ws://{HOST}:{args.port}/ws; the .fba player {url}player; "
          "Ctrl-C stops)")
    if not args.no_browser:
        threading.Timer(1.0, webbrowser.open, (url,)).start()
    run_until_stopped(app, host=HOST, port=args.port, log_level="warning", ws_max_size=1 << 20)
    return 0
