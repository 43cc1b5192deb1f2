"""The command line starts quickly: what each command imports (issue 32 item 4).

``import mpeg4fa.cli`` once imported the renderer, the face, scipy and more (0.56 s, ~1 s for ``mpeg4fa
--version``), and ``mpeg4fa info`` of a small stream loaded numba (1-1.2 s, 208 MB). Now each command
registers and imports only its own module (:data:`mpeg4fa.cli.MODULES`), ``encode``'s speech options are
added when it runs (:meth:`OneLineParser.defer`), and a small stream decodes on the reference path
(:data:`mpeg4fa.fba.compiled.SMALL_STREAM`). These tests look at ``sys.modules`` in a fresh interpreter,
not at times, so they hold on a loaded machine.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys

import pytest

from mpeg4fa.cli import MODULES, build_parser

HEAVY = ("mpeg4fa.render", "mpeg4fa.face", "mpeg4fa.fdp", "mpeg4fa.speech", "mpeg4fa.web", "mpeg4fa.serve",
         "mpeg4fa.export", "mpeg4fa.batch", "mpeg4fa.conformance", "mpeg4fa.tracking", "scipy", "numba",
         "llvmlite", "moderngl", "glcontext", "matplotlib", "PIL", "trimesh", "networkx", "av", "geomdl",
         "fastapi", "uvicorn", "starlette", "dask", "distributed", "vtk", "pocketsphinx", "cv2", "mediapipe",
         "pypinyin", "pyttsx3", "espeakng_loader")
"""What neither ``import mpeg4fa.cli`` nor ``info``/``validate``/``decode`` of a small stream may load."""


def loaded_after(code: str) -> set[str]:
    """Top modules and mpeg4fa subpackages in ``sys.modules`` after running ``code`` in a fresh interpreter."""
    script = (f"import sys, json\n{code}\n"
              "print(json.dumps(sorted(sys.modules)), file=sys.__stderr__)")
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode in (0, 1), done.stderr
    names = json.loads(done.stderr.strip().splitlines()[-1])
    return {n for n in names if n.split(".")[0] != "mpeg4fa"} | {".".join(n.split(".")[:2]) for n in names}


def heavy_in(modules: set[str]) -> list[str]:
    return sorted(h for h in HEAVY if h in modules)


@pytest.fixture(scope="module")
def small_stream(tmp_path_factory):
    from mpeg4fa.fba import EncodeOptions, demo_stream, encode
    from mpeg4fa.fba.compiled import SMALL_STREAM

    path = tmp_path_factory.mktemp("imports") / "small.fba"
    path.write_bytes(encode(demo_stream(), EncodeOptions(fap_quant=1)))
    assert path.stat().st_size < SMALL_STREAM
    return path


def test_importing_the_cli_loads_no_layer():
    modules = loaded_after("import mpeg4fa.cli")
    assert heavy_in(modules) == []
    assert "numpy" not in modules  # --version and --help of nothing need no array


@pytest.mark.parametrize("argv", [["--version"], ["info", "{stream}"], ["info", "{stream}", "--json"],
                                  ["validate", "{stream}"], ["decode", "{stream}", "-o", "{out}"]])
def test_codec_commands_load_only_the_codec(argv, small_stream):
    argv = [a.format(stream=small_stream, out=small_stream.with_suffix(".fap")) for a in argv]
    code = ("from mpeg4fa.cli import main\ntry:\n    status = main(%r)\nexcept SystemExit as exc:\n"
            "    status = exc.code\nassert status == 0, status" % argv)
    modules = loaded_after(code)
    assert heavy_in(modules) == [], f"mpeg4fa {' '.join(argv)} imported these"


def test_encode_help_still_lists_its_speech_options():
    """encode's deferred options are there when it is the command, and in the whole parser (the docs read it)."""
    parser = build_parser(("codec",))
    text = _subparser(parser, "encode").format_help()
    assert "--level" in text and "--engine" in text and "--fdp-out" in text
    whole = _subparser(build_parser(), "encode")
    assert {"--level", "--engine", "--audio"} <= {o for a in whole._actions for o in a.option_strings}


def test_modules_table_matches_what_each_module_registers():
    """MODULES names every command (a command missing from it would run on the slow, whole parser)."""
    for name, commands in MODULES.items():
        assert tuple(_subcommands(build_parser((name,)))) == commands, name
    assert list(_subcommands(build_parser())) == [c for commands in MODULES.values() for c in commands]


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices


def _subparser(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    return _subcommands(parser)[name]
