"""MkDocs hook: the command reference is generated from the argparse parsers the ``mpeg4fa`` command runs,
so the page cannot drift from ``--help``. A page holding ``<!-- mpeg4fa:commands -->`` gets every command."""
from __future__ import annotations

import argparse
import os

MARKER = "<!-- mpeg4fa:commands -->"


def commands_markdown() -> str:
    """Every command's ``--help``, in the order ``mpeg4fa --help`` lists them, one section each."""
    os.environ["COLUMNS"] = "100"  # argparse wraps to this width
    from mpeg4fa.cli import build_parser

    parser = build_parser()
    parts = ["## mpeg4fa\n", "```text\n" + parser.format_help().rstrip() + "\n```\n"]
    seen: set[int] = set()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                if id(sub) in seen:
                    continue  # an alias of a command already listed
                seen.add(id(sub))
                parts.append(f"## mpeg4fa {name}\n")
                parts.append("```text\n" + sub.format_help().rstrip() + "\n```\n")
    return "\n".join(parts)


def on_page_markdown(markdown: str, page, config, files) -> str:
    if MARKER in markdown:
        markdown = markdown.replace(MARKER, commands_markdown())
    return markdown
