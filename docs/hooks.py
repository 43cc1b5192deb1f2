"""MkDocs hook: the command reference is generated from the argparse parsers the ``mpeg4fa`` command runs,
so the page cannot drift from ``--help``. A page holding ``<!-- mpeg4fa:commands -->`` gets every command."""
from __future__ import annotations

import argparse
import os

MARKER = "<!-- mpeg4fa:commands -->"


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


def on_page_markdown(markdown: str, page, config, files) -> str:
    if MARKER in markdown:
        markdown = markdown.replace(MARKER, commands_markdown())
    return markdown
