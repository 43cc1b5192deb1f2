"""What every browser test shares: Debian's chromium driven by Playwright (never a downloaded browser),
the flags it needs on a headless machine with a closed network, and the module-level skip saying what
to install when either is missing."""
from __future__ import annotations

import contextlib
import os
import shutil
import socket
from pathlib import Path
from typing import Iterator

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


def fresh_folder(path: Path) -> Path:
    """An empty artefact folder (the screenshots of the last run removed)."""
    if path.exists():
        shutil.rmtree(path)
    path.mkdir(parents=True)
    return path


@contextlib.contextmanager
def editor_page(base: str, *, height: int = 820) -> Iterator:
    """The editor page at ``base`` in a new headless chromium, ready; ``page.errors`` collects script faults
    (the 400s a scenario provokes are logged by chromium as failed loads: those do not count)."""
    sync_api = require_browser()
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
        page = browser.new_page(viewport={"width": 1280, "height": height})
        errors: list[str] = []
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.on("console", lambda m: errors.append(m.text)
                if m.type == "error" and not m.text.startswith("Failed to load resource") else None)
        page.goto(base + "/")
        page.wait_for_selector("body[data-ready='1']", timeout=15_000)
        page.errors = errors
        try:
            yield page
        finally:
            browser.close()
