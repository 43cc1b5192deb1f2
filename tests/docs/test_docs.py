"""The documentation site cannot drift: it builds strictly (no broken link, no missing reference, no
warning), and every shell example in it is either run here, in a temporary folder, or marked skipped
with its reason.

A fenced ``sh`` block in ``docs/`` is preceded by one marker line:
``<!-- run -->`` (run here), ``<!-- run: needs the generic head -->`` (run when the head is built),
``<!-- run: from the clone's root -->`` (reads the repository's own files, e.g. ``conformance/``: run in the
temporary folder with the repository's ``conformance``, ``spec`` and ``mpeg4fa`` linked into it, so what it writes lands
there), or ``<!-- skip: REASON -->`` (too slow, needs a display, a network, a photo...: the reason says which).
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from mpeg4fa.face import asset

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
BLOCK = re.compile(r"^(?P<marker><!--.*?-->\n)?```(?P<lang>sh|bash)\n(?P<body>.*?)^```", re.M | re.S)
MARKER = re.compile(r"<!-- (run|run: needs the generic head|run: from the clone's root|skip: \S.*) -->\n")
LINKED = ("conformance", "spec", "mpeg4fa")


def shell_blocks() -> list[tuple[str, str, str]]:
    """(place ``page:line``, marker, commands) of every sh block in the docs."""
    blocks = []
    for page in sorted(DOCS.rglob("*.md")):
        text = page.read_text(encoding="utf-8")
        for match in BLOCK.finditer(text):
            line = text.count("\n", 0, match.start("lang")) + 1
            blocks.append((f"{page.relative_to(ROOT)}:{line}", match.group("marker") or "", match.group("body")))
    return blocks


BLOCKS = shell_blocks()
RUN = [b for b in BLOCKS if b[1].startswith("<!-- run")]


def test_the_docs_have_runnable_examples():
    assert len(RUN) >= 8, [b[0] for b in BLOCKS]


@pytest.mark.parametrize("place, marker, body", BLOCKS, ids=[b[0] for b in BLOCKS])
def test_every_shell_block_says_whether_it_runs(place, marker, body):
    assert MARKER.fullmatch(marker), f"{place}: precede the block with <!-- run --> or <!-- skip: REASON -->"


@pytest.mark.parametrize("place, marker, body", RUN, ids=[b[0] for b in RUN])
def test_documented_commands_run(place, marker, body, tmp_path):
    if "generic head" in marker and not asset.is_installed():
        pytest.skip("generic head not built: run `mpeg4fa model install` (needs network once)")
    if re.search(r"^\s*[^#]*\bnode\b", body, re.M) and shutil.which("node") is None:
        pytest.skip("Node.js is not installed (fba.js runs in it)")
    if "clone's root" in marker:
        for name in LINKED:
            (tmp_path / name).symlink_to(ROOT / name, target_is_directory=True)
    env = dict(os.environ, PATH=f"{Path(sys.executable).parent}{os.pathsep}{os.environ['PATH']}")
    done = subprocess.run(["bash", "-euo", "pipefail", "-c", body], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, f"{place}: exit {done.returncode}\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}"


def test_site_builds_strictly(tmp_path):
    pytest.importorskip("mkdocs", reason="the docs extra is not installed (tools/dev.sh test or docs installs it)")
    pytest.importorskip("material", reason="mkdocs-material is not installed (tools/dev.sh docs)")
    pytest.importorskip("mkdocstrings", reason="mkdocstrings is not installed (tools/dev.sh docs)")
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q", "-d", str(tmp_path / "site")],
                          cwd=ROOT, capture_output=True, text=True, timeout=300,
                          env=dict(os.environ, NO_MKDOCS_2_WARNING="1"))  # Material's end-of-life banner
    log = done.stdout + done.stderr
    assert done.returncode == 0, log[-4000:]
    assert "WARNING" not in log, log[-4000:]
    site = tmp_path / "site"
    commands = (site / "reference" / "commands" / "index.html").read_text(encoding="utf-8")
    assert "mpeg4fa say" in commands and "usage: mpeg4fa encode" in commands  # generated from the parsers
    api = (site / "reference" / "api" / "index.html").read_text(encoding="utf-8")
    assert 'id="mpeg4fa.fba.decode"' in api  # generated from the docstrings
    for picture in ("media/say-hello.gif", "media/feature-points.png"):
        assert (site / picture).stat().st_size > 10_000


def test_pictures_the_pages_show_exist():
    for page in DOCS.rglob("*.md"):
        for target in re.findall(r"!\[[^\]]*\]\(([^)]+)\)", page.read_text(encoding="utf-8")):
            assert (page.parent / target).resolve().is_file(), f"{page.relative_to(ROOT)}: {target} is missing"


def test_readme_is_a_front_page_whose_links_resolve():
    readme = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(readme.splitlines()) <= 150
    for target in re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", readme):
        if "://" not in target:
            assert (ROOT / target).exists(), f"README.md links to {target}, which is missing"
