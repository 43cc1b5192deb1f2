"""The ``mpeg4fa`` command: a thin shell over the Python API.

Each group of subcommands lives in its own module and registers itself on the
parser. The error contract: any layer's error (:class:`mpeg4fa.errors.MpegFaError`)
or an operating-system error becomes one line ``mpeg4fa COMMAND: error: ...`` on
stderr and exit status 1; options that do not go together (:class:`.UsageError`)
exit 2, as argparse's own errors do (one line too: no usage dump; ``--help`` has the usage);
an OS error names its file and what to do. Ctrl-C exits 130; SIGTERM and SIGHUP
(:func:`mpeg4fa.atomic.clean_up_on_signals`) unwind the same way and exit 128 + the signal
(143, 129) after one line ``mpeg4fa COMMAND: terminated (SIGTERM)``. No traceback for any of
them, and outputs are written under temporary names (:mod:`mpeg4fa.atomic`), so a failed,
interrupted or killed command leaves no partial file. Every warning, whatever its category
or origin, is one ``mpeg4fa COMMAND: warning: ...`` line (no source lines).
"""
from __future__ import annotations

import argparse
import sys
import warnings

from .. import __version__
from ..atomic import Terminated, clean_up_on_signals
from ..errors import MpegFaError
from . import batch, codec, conform, edit, export, model, play, serve, speech, texture
from .errors import UsageError, os_error_line
from .media import one_line


class OneLineParser(argparse.ArgumentParser):
    """argparse with its errors in one line, ``mpeg4fa CMD: error: argument --fps: ...``, exit status 2.

    argparse prints the whole usage (9 to 17 lines for a command) before the error; the line
    that matters is then lost. ``--help`` shows the usage. Subparsers are made of the class of
    their parent, so every command (and ``model``'s subcommands) gets it.
    """

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {one_line(message)}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(
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
    conform.register(commands)
    edit.register(commands)
    export.register(commands)
    batch.register(commands)
    serve.register(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    with warnings.catch_warnings(), clean_up_on_signals():
        warnings.showwarning = _one_line_warnings("mpeg4fa")
        try:
            args = build_parser().parse_args(argv)
        except KeyboardInterrupt as exc:  # before any work: nothing to clean up
            return _stopped("mpeg4fa", exc)
        warnings.showwarning = _one_line_warnings(_command(args))
        return _run(args)


def _command(args: argparse.Namespace) -> str:
    """``mpeg4fa CMD`` as its messages begin (with the subcommand: ``mpeg4fa model pose``), as argparse's do."""
    sub = getattr(args, "model_command", None)
    return f"mpeg4fa {args.command} {sub}" if sub else f"mpeg4fa {args.command}"


def _one_line_warnings(prefix: str):
    def show(message, category, filename, lineno, file=None, line=None) -> None:
        print(f"{prefix}: warning: {one_line(message)}", file=sys.stderr)
    return show


def _run(args: argparse.Namespace) -> int:
    command = _command(args)
    try:
        return int(args.run(args) or 0)
    except UsageError as exc:
        print(f"{command}: error: {exc}", file=sys.stderr)
        return 2
    except MpegFaError as exc:
        print(f"{command}: error: {one_line(exc)}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # output piped into head, less...: not an error
        sys.stderr.close()
        return 0
    except OSError as exc:
        print(f"{command}: error: {os_error_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM/SIGHUP (Terminated): outputs already cleaned up
        return _stopped(command, exc)


def _stopped(command: str, exc: KeyboardInterrupt) -> int:
    """One line for an interruption and the shell's exit status for it (130 for Ctrl-C, 128 + signal)."""
    if isinstance(exc, Terminated):
        print(f"{command}: terminated ({exc.signal_name})", file=sys.stderr)
        return exc.exit_status
    print(f"\n{command}: interrupted", file=sys.stderr)
    return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
