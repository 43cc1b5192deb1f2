"""Running ``serve`` and ``edit``'s web apps under uvicorn until Ctrl-C, SIGTERM or SIGHUP, each a clean stop.

Why not ``uvicorn.run``: it swallows KeyboardInterrupt, so a SIGTERM the CLI turns into
:class:`mpeg4fa.atomic.Terminated` ended in exit status 0; and uvicorn handles only SIGINT
and SIGTERM, so a SIGHUP (a closed terminal) cut the event loop mid-step (a traceback from
the app's lifespan). Here a SIGHUP asks the server to stop as SIGTERM does (connections
closed, the app's shutdown run), and then the command ends as every command does on a
signal: one line, exit status 1.
"""
from __future__ import annotations

import logging
import signal
import threading
from typing import Any

from ..atomic import Terminated

CLIENT_FAULTS = ("Invalid UTF-8 sequence received from client",)
"""Messages uvicorn logs with a traceback of its own code for what a client sent wrong (a text frame that is not
UTF-8: the connection is closed with 1007 and the server goes on): the console gets their one line."""


class _ClientFaultsInOneLine(logging.Filter):
    def filter(self, record: logging.LogRecord) -> bool:
        if record.exc_info and record.getMessage().startswith(CLIENT_FAULTS):
            record.exc_info, record.exc_text = None, None
        return True


def run_until_stopped(app: Any, **config: Any) -> None:
    """Serve ``app`` (uvicorn ``Config`` options) until a signal stops it; Terminated after a SIGHUP or SIGTERM."""
    import uvicorn

    server = uvicorn.Server(uvicorn.Config(app, **config))
    logger = logging.getLogger("uvicorn.error")
    if not any(isinstance(f, _ClientFaultsInOneLine) for f in logger.filters):
        logger.addFilter(_ClientFaultsInOneLine())
    hung_up: list[int] = []

    def on_hangup(signum: int, frame: Any) -> None:
        hung_up.append(signum)
        server.should_exit = True

    hup = getattr(signal, "SIGHUP", None)
    before = None
    if hup is not None and threading.current_thread() is threading.main_thread() \
            and signal.getsignal(hup) is not signal.SIG_IGN:
        before = signal.signal(hup, on_hangup)
    try:
        server.run()  # uvicorn raises SIGINT/SIGTERM again when it has stopped: KeyboardInterrupt, Terminated
    finally:
        if before is not None:
            signal.signal(hup, before)
    if hung_up:
        raise Terminated(hung_up[0])
