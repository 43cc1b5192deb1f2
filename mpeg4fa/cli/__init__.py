"""The ``mpeg4fa`` command: a thin shell over the Python API.

Each group of subcommands lives in its own module and registers itself on the
parser. The error contract: any layer's error (:class:`mpeg4fa.errors.MpegFaError`)
or an operating-system error becomes one line ``mpeg4fa COMMAND: error: ...`` on
stderr and exit status 1; options that do not go together (:class:`.UsageError`)
exit 2, as argparse's own errors do (one line too: no usage dump; ``--help`` has the usage);
an OS error names its file and what to do. Ctrl-C, SIGTERM and SIGHUP
(:func:`mpeg4fa.atomic.clean_up_on_signals`) unwind the same way and exit 1, as any other
stop short of the work does, after one line (``mpeg4fa COMMAND: interrupted`` or
``mpeg4fa COMMAND: terminated (SIGTERM)``). No traceback for any of
them, and outputs are written under temporary names (:mod:`mpeg4fa.atomic`), so a failed,
interrupted or killed command leaves no partial file. Every warning, whatever its category
or origin, is one ``mpeg4fa COMMAND: warning: ...`` line (no source lines).
"""
from __future__ import annotations

import argparse
import importlib
import sys
import warnings
from typing import Callable

from .. import __version__, notices
from ..atomic import Terminated, clean_up_on_signals
from ..errors import MpegFaError
from .errors import UsageError, os_error_line
from .media import one_line

MODULES: dict[str, tuple[str, ...]] = {
    "codec": ("info", "decode", "encode", "validate", "demo"),
    "model": ("model",),
    "play": ("play", "snapshot"),
    "texture": ("texture",),
    "fdp_photo": ("fdp",),
    "speech": ("say", "voices"),
    "conform": ("conform",),
    "edit": ("edit",),
    "export": ("export",),
    "batch": ("batch",),
    "serve": ("serve",),
}
"""Each module of this package that registers commands (in the order ``--help`` lists them) -> its commands.

Why: registering a command imports what its options list (the deformers, the calibration methods, the
camera views: the face and the renderer, ~1 s), so :func:`main` registers only the module of the command
it runs; ``mpeg4fa info x.fba`` then imports the codec alone. A command missing here still runs (a word
that names no command here builds the whole parser); ``tests/cli/test_imports.py`` checks the table
against what the modules register."""


class OneLineParser(argparse.ArgumentParser):
    """argparse with its errors in one line, ``mpeg4fa CMD: error: argument --fps: ...``, exit status 2.

    argparse prints the whole usage (9 to 17 lines for a command) before the error; the line
    that matters is then lost. ``--help`` shows the usage. Subparsers are made of the class of
    their parent, so every command (and ``model``'s subcommands) gets it.
    """

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {one_line(message)}\n")

    def defer(self, add_options: Callable[[argparse.ArgumentParser], object]) -> None:
        """Add options when this parser is first used (to parse or to help), not when it is made.

        Why: ``encode``'s text options list the speech layer's engines and levels; deferred, registering
        ``encode`` beside ``info`` does not import the speech layer that ``mpeg4fa info`` never uses.
        :func:`build_parser` of every command completes them all (what the reference docs read)."""
        self.__dict__.setdefault("_deferred", []).append(add_options)

    def complete(self) -> argparse.ArgumentParser:
        """Run the deferred option adders (:meth:`defer`), once; the parser."""
        deferred = self.__dict__.pop("_deferred", [])
        for add_options in deferred:
            add_options(self)
        return self

    def parse_known_args(self, args=None, namespace=None):
        return super(OneLineParser, self.complete()).parse_known_args(args, namespace)

    def format_usage(self) -> str:
        return super(OneLineParser, self.complete()).format_usage()

    def format_help(self) -> str:
        return super(OneLineParser, self.complete()).format_help()


def build_parser(only: tuple[str, ...] | None = None) -> argparse.ArgumentParser:
    """The whole ``mpeg4fa`` parser; ``only``: just the commands of these modules of :data:`MODULES` (what
    :func:`main` builds to run one command without importing every other command's layers)."""
    parser = OneLineParser(
        prog="mpeg4fa",
        description="MPEG-4 Face Animation: encode, decode, inspect and validate FBA streams and .fap files; "
                    "build, calibrate and pose the decoder's 3D face; render streams to video.",
        epilog="Run 'mpeg4fa COMMAND --help' for the options of a command.",
    )
    parser.add_argument("--version", action="version", version=f"mpeg4fa {__version__}")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for name in MODULES if only is None else only:
        importlib.import_module(f"{__name__}.{name}").register(commands)
    if only is None:
        _complete_all(parser)
    return parser


def _complete_all(parser: argparse.ArgumentParser) -> None:
    """Every deferred option of ``parser`` and its subcommands added (:meth:`OneLineParser.defer`)."""
    if isinstance(parser, OneLineParser):
        parser.complete()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                _complete_all(sub)


def _modules_for(argv: list[str]) -> tuple[str, ...] | None:
    """The module of :data:`MODULES` whose command ``argv`` runs; None (all of them) for ``--help``, no
    command or a word that names none; no module for ``--version``."""
    word = next((a for a in argv if not a.startswith("-")), None)
    if word is None:
        return () if "--version" in argv and not {"-h", "--help"} & set(argv) else None
    return next(((name,) for name, words in MODULES.items() if word in words), None)


def main(argv: list[str] | None = None) -> int:
    with warnings.catch_warnings(), clean_up_on_signals():
        warnings.showwarning = _one_line_warnings("mpeg4fa")
        try:
            argv = sys.argv[1:] if argv is None else list(argv)
            args = build_parser(_modules_for(argv)).parse_args(argv)
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
    notices.listen(lambda text: print(f"{command}: {text}", file=sys.stderr, flush=True))
    try:
        return int(args.run(args) or 0)
    except UsageError as exc:
        print(f"{command}: error: {exc}", file=sys.stderr)
        return 2
    except MpegFaError as exc:
        print(f"{command}: error: {one_line(_in_its_file(args, exc))}", file=sys.stderr)
        return 1
    except BrokenPipeError:  # output piped into head, less...: not an error
        sys.stderr.close()
        return 0
    except OSError as exc:
        print(f"{command}: error: {os_error_line(exc)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM/SIGHUP (Terminated): outputs already cleaned up
        return _stopped(command, exc)


def _in_its_file(args: argparse.Namespace, exc: MpegFaError) -> str:
    """The error as a line, led by the stream file it is in where the codec's place is only a bit offset and frame
    (``decode talk.fba``: ``talk.fba: marker bit ... at bit 1914 (byte 239), frame 0``)."""
    import os

    from ..fba import FbaError

    text = str(exc)
    source = getattr(args, "stream", None) or getattr(args, "input", None)  # encode's input may be text instead
    if isinstance(exc, FbaError) and isinstance(source, (str, os.PathLike)) and os.path.isfile(source) \
            and os.fspath(source) not in text:
        return f"{os.fspath(source)}: {text}"
    return text


def _stopped(command: str, exc: KeyboardInterrupt) -> int:
    """One line for an interruption, and exit status 1: the work was not done, and nothing of it was left."""
    if isinstance(exc, Terminated):
        print(f"{command}: terminated ({exc.signal_name})", file=sys.stderr)
    else:
        print(f"\n{command}: interrupted", file=sys.stderr)
    return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
