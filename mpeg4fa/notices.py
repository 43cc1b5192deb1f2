"""Notes from the layers about slow work that is not an error or a warning (the codec compiling its kernels).

Why: a library does not print; the command line does. A layer calls :func:`note`; whoever runs it (the CLI
prints ``mpeg4fa CMD: ...`` on stderr) listens with :func:`listen`. Without a listener, notes go nowhere.
"""
from __future__ import annotations

from typing import Callable

_listener: Callable[[str], None] | None = None


def listen(listener: Callable[[str], None] | None) -> None:
    """Send every note to ``listener`` from now on (None: to nowhere)."""
    global _listener
    _listener = listener


def note(text: str) -> None:
    """Say ``text`` to the listener, if there is one."""
    if _listener is not None:
        _listener(text)
