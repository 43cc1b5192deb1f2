"""What every browser test shares: Debian's chromium driven by Playwright (never a downloaded browser),
the flags it needs on a headless machine with a closed network, and the module-level skip saying what
to install when either is missing."""
from __future__ import annotations

import os
import socket

import pytest

CHROMIUM = "/usr/bin/chromium"
ARGS = ["--no-sandbox", "--disable-gpu", "--use-angle=swiftshader", "--enable-unsafe-swiftshader",
        "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run"]


def require_browser():
    """Playwright's sync API, or skip the calling test module saying what is missing."""
    sync_api = pytest.importorskip("playwright.sync_api",
                                   reason="playwright not installed (pip install playwright==1.65.2)")
    if not os.access(CHROMIUM, os.X_OK):
        pytest.skip(f"{CHROMIUM} not found: install Debian's chromium (apt-get install chromium)",
                    allow_module_level=True)
    return sync_api


def free_port() -> int:
    """A loopback port nobody listens on now."""
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]
