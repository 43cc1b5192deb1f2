"""The ``mpeg4fa`` command: a thin shell over the Python API.

Each group of subcommands lives in its own module and registers itself on the
parser; errors of any layer become one line on stderr and exit status 1, and
warnings one ``mpeg4fa COMMAND: warning: ...`` line each (no source lines).
"""
from __future__ import annotations

import argparse
import sys
import warnings

from .. import __version__
from ..face import FaceError
from ..fba import FbaError
from ..formats import FormatError
from ..render.errors import RenderError
from ..speech.errors import MarkupError, TTSError
from . import codec, model, play, speech, texture
from .errors import UsageError


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mpeg4fa",
        description="MPEG-4 Face Animation: encode, decode, inspect and validate FBA streams and .fap files; "
                    "build, calibrate and pose the decoder's 3D face; render streams to video.",
        epilog="Run 'mpeg4fa COMMAND --help' for the options of a command.",
    )
    parser.add_argument("--version", action="version", version=f"mpeg4fa {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    codec.register(commands)
    model.register(commands)
    play.register(commands)
    texture.register(commands)
    speech.register(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    with warnings.catch_warnings():
        warnings.showwarning = _one_line_warnings(args.command)
        return _run(args)


def _one_line_warnings(command: str):
    def show(message, category, filename, lineno, file=None, line=None) -> None:
        print(f"mpeg4fa {command}: warning: {message}", file=sys.stderr)
    return show


def _run(args: argparse.Namespace) -> int:
    try:
        return int(args.run(args) or 0)
    except (FbaError, FormatError, FaceError, RenderError, MarkupError, TTSError) as exc:
        print(f"mpeg4fa {args.command}: error: {exc}", file=sys.stderr)
        return 1
    except UsageError as exc:
        print(f"mpeg4fa {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into head, less...: not an error
        sys.stderr.close()
        return 0
    except OSError as exc:
        print(f"mpeg4fa {args.command}: error: {exc.strerror or exc}: {exc.filename or ''}".rstrip(": "),
              file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
