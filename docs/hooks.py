"""MkDocs hook: generated parts of pages, so they cannot drift from what they describe.

* A page holding ``<!-- mpeg4fa:commands -->`` gets every command's ``--help``, from the argparse parsers
  the ``mpeg4fa`` command runs.
* A page holding ``<!-- mpeg4fa:benchmarks -->`` gets the benchmarks' tables, from the JSON the benchmarks
  in tools/ write (``tools/docs_benchmarks.py``), and the site gets their plots (``pictures/bench/*.png``,
  drawn at each build, never committed).
"""
from __future__ import annotations

import argparse
import functools
import importlib.util
import os
import sys
from pathlib import Path

MARKER = "<!-- mpeg4fa:commands -->"
ROOT = Path(__file__).resolve().parents[1]
_PLOTTED: set[str] = set()


@functools.lru_cache(maxsize=1)
def _benchmarks():
    """tools/docs_benchmarks.py as a module (tools/ is no package)."""
    spec = importlib.util.spec_from_file_location("docs_benchmarks", ROOT / "tools" / "docs_benchmarks.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def commands_markdown() -> str:
    """Every command's ``--help``, in the order ``mpeg4fa --help`` lists them, one section each; a command
    with its own subcommands (``model install``...) gets a section per subcommand."""
    os.environ["COLUMNS"] = "88"  # argparse wraps to this width: the code blocks need no scrolling
    from mpeg4fa.cli import build_parser

    parts: list[str] = []
    _sections(build_parser(), "mpeg4fa", parts, set())
    return "\n".join(parts)


def _sections(parser: argparse.ArgumentParser, name: str, parts: list[str], seen: set[int]) -> None:
    level = "#" * min(2 + name.count(" ") // 2, 4)
    parts.append(f"{level} {name}\n")
    parts.append("```text\n" + parser.format_help().rstrip() + "\n```\n")
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for word, sub in action.choices.items():
                if id(sub) not in seen:  # an alias of a command already listed is skipped
                    seen.add(id(sub))
                    _sections(sub, f"{name} {word}", parts, seen)


def on_files(files, config):
    """Add the benchmark plots to the site as generated files."""
    from mkdocs.structure.files import File

    bench = _benchmarks()
    _PLOTTED.clear()
    for name, png in bench.plots().items():
        files.append(File.generated(config, f"{bench.PLOT_DIR}/{name}", content=png))
        _PLOTTED.add(name)
    return files


def on_page_markdown(markdown: str, page, config, files) -> str:
    if MARKER in markdown:
        markdown = markdown.replace(MARKER, commands_markdown())
    bench = _benchmarks()
    if bench.MARKER in markdown:
        markdown = markdown.replace(bench.MARKER, bench.page_markdown(set(_PLOTTED)))
    return markdown
