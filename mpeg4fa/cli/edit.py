"""``mpeg4fa edit [MODEL]``: the face model editor, served on 127.0.0.1 (a thin shell over :mod:`mpeg4fa.web`)."""
from __future__ import annotations

import argparse
import threading
import webbrowser
from pathlib import Path

from . import options
from .options import Commands


def register(commands: Commands) -> None:
    p = commands.add_parser("edit", help="edit a head model and place its feature points in the browser",
                            description="Start the face model editor on 127.0.0.1 only and open its page. "
                                        "MODEL: a mesh file (OBJ, VRML 97, GLB, glTF, OFF, PLY, STL); "
                                        "default the generic head. "
                                        "An OBJ saved by the editor gets its parts and feature points back "
                                        "from NAME.parts.json and NAME.points.json beside it. "
                                        "Only the editor's own page and clients on this machine get in: a request "
                                        "with another site's Origin or a Host other than localhost, 127.0.0.1 or "
                                        "[::1] with the port is refused (403).")
    p.add_argument("model", nargs="?", type=Path, metavar="MODEL", help="mesh to edit (default: the generic head)")
    p.add_argument("--port", type=options.port, default=8765, help="port (default 8765)")
    p.add_argument("--out", type=Path, default=Path("."), help="folder saved models are written into (default .)")
    p.add_argument("--no-browser", action="store_true", help="do not open the page")
    p.set_defaults(run=run_edit)


def run_edit(args: argparse.Namespace) -> int:
    from ..extras import require

    require("web", "fastapi", "uvicorn", "python_multipart")
    from ..web.app import HOST, create_app
    from .local_server import run_until_stopped

    app = create_app(args.model, args.out)
    if app.state.session.mesh is None:
        from ..web import edits
        from ..face import FaceModel
        app.state.session.load(edits.from_head(FaceModel.default().mesh))
    url = f"http://{HOST}:{args.port}/"
    print(f"mpeg4fa edit: serving {url} (Ctrl-C stops); saving into {args.out.resolve()}")
    if not args.no_browser:
        threading.Timer(1.0, webbrowser.open, (url,)).start()
    run_until_stopped(app, host=HOST, port=args.port, log_level="warning")
    return 0
