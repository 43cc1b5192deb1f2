"""A batch manifest: the streams to render, each with its audio, FDP, output name and options.

Two forms, told apart by the file's suffix:

* JSON (``.json``): a list of jobs, or ``{"defaults": {...}, "jobs": [...]}`` where the defaults
  apply to every job that does not say otherwise; a job is an object (its options may also sit in
  an ``"options"`` object).
* CSV (any other suffix): a header row naming the columns, then one job a row; an empty cell is
  a key not given.

Keys: ``stream`` (required: a .fba or .fap file), ``audio`` (speech to mux; none unless given),
``fdp`` (the sender's FDP), ``output`` (a name under the output folder ending in .mp4/.mov/.m4v;
default: the stream's name with .mp4) and the options of ``mpeg4fa play``, which mean the same
and are checked by the same rules (:mod:`mpeg4fa.limits`, the frame rate by
:meth:`~mpeg4fa.fba.stream.FrameRate.from_fps`): ``size`` (``W``, ``WxH`` or
``[W, H]``, even), ``aa``, ``view``, ``fps``, ``fit``, ``crf``, ``deformer``, ``blocks``,
``method``, ``skull``, ``texture``, ``fdp_texture`` (true/false), ``face_mesh`` + ``face_points``.
Relative paths are taken from the manifest's folder. Every fault is collected with its place
(``job I at line N``) and all are raised at once in one :class:`.BatchError`: a manifest is fixed
in one edit, not one run per missing file.
"""
from __future__ import annotations

import csv
import difflib
import io
import json
import os
from dataclasses import dataclass, field
from pathlib import Path, PurePosixPath
from typing import Any, Callable

from mpeg4fa import jsonio
from mpeg4fa.batch.errors import BatchError
from mpeg4fa import limits
from mpeg4fa.errors import MpegFaError
from mpeg4fa.fba.stream import FrameRate
from mpeg4fa.face import calibrate, deformers
from mpeg4fa.render.camera import VIEWS
from mpeg4fa.render.player import FITS
from mpeg4fa.render.video import VIDEO_SUFFIXES

MAX_MANIFEST_BYTES = 64 << 20
"""A manifest larger than this is refused (a list of a million jobs is not a manifest)."""
MAX_DEPTH = 8
"""Deepest nesting of a JSON manifest read (it needs 3: the document, its jobs, a job)."""
INPUT_KEYS = ("stream", "audio", "fdp")
PATH_OPTIONS = ("texture", "face_mesh", "face_points")
SKULLS = ("triangles", "nurbs")


class _Bad(ValueError):
    """One option value that does not pass its rule (the text says why)."""


def _text(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float, str)):
        return str(value)
    raise _Bad(f"expected a string or a number, got {type(value).__name__}")


def _ruled(rule: Callable[[str], Any]) -> Callable[[Any], Any]:
    """A rule on text (:mod:`mpeg4fa.limits`: what the CLI's options take too), used on a manifest value."""
    def parse(value: Any) -> Any:
        try:
            return rule(_text(value))
        except (ValueError, MpegFaError) as exc:
            raise _Bad(str(exc)) from None
    return parse


def _fps(text: str) -> float:
    """A frame rate a stream carries (the codec's rule, as ``play --fps``)."""
    value = float(limits.Limit("frame rate").parse(text))
    FrameRate.from_fps(value)
    return value


def _choice(choices: tuple[str, ...]) -> Callable[[Any], str]:
    def parse(value: Any) -> str:
        text = _text(value)
        if text not in choices:
            raise _Bad(f"{text!r} is not one of {', '.join(choices)}")
        return text
    return parse


def _size(value: Any) -> tuple[int, int]:
    if isinstance(value, list):
        if len(value) != 2 or not all(isinstance(v, int) and not isinstance(v, bool) for v in value):
            raise _Bad(f"{value!r}: expected [W, H], two whole numbers")
        value = f"{value[0]}x{value[1]}"
    width, height = _ruled(limits.parse_size)(value)
    if width % 2 or height % 2:
        raise _Bad(f"{width}x{height} is odd; an MP4 (H.264) needs even sizes, "
                   f"e.g. {width + width % 2}x{height + height % 2}")
    return width, height


def _boolean(value: Any) -> bool:
    if isinstance(value, bool):
        return value
    text = _text(value).strip().lower()
    if text in ("true", "yes", "1"):
        return True
    if text in ("false", "no", "0"):
        return False
    raise _Bad(f"{text!r}: expected true or false")


def _names(value: Any) -> tuple[str, ...]:
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        names = tuple(v.strip() for v in value)
    else:
        names = tuple(n.strip() for n in _text(value).split(","))
    names = tuple(n for n in names if n)
    if not names:
        raise _Bad("expected block names, e.g. eye_l,eye_r,lip_t,lip_b")
    return names


OPTIONS: dict[str, tuple[Callable[[Any], Any], Any]] = {
    "size": (_size, (512, 512)),
    "aa": (_ruled(limits.SAMPLES.parse), 0),
    "view": (_choice(tuple(VIEWS)), "front"),
    "fps": (_ruled(_fps), None),
    "fit": (_choice(FITS), "pad"),
    "crf": (_ruled(limits.CRF.parse), 18),
    "deformer": (_choice(tuple(deformers.names())), deformers.names()[0]),
    "blocks": (_names, None),
    "method": (_choice(tuple(calibrate.METHODS)), "dffd"),
    "skull": (_choice(SKULLS), "triangles"),
    "fdp_texture": (_boolean, True),
}
"""Option -> (rule, default): the same meanings and checks as the options of ``mpeg4fa play``."""
KEYS = (*INPUT_KEYS, "output", *OPTIONS, *PATH_OPTIONS)


@dataclass(frozen=True)
class Job:
    """One stream to render: absolute input paths, the output's name under the output folder, its options."""

    index: int
    where: str                 # "job I at line N" of the manifest
    stream: Path
    output: str                # relative POSIX path under the output folder
    audio: Path | None = None
    fdp: Path | None = None
    options: dict[str, Any] = field(default_factory=dict)

    def inputs(self) -> dict[str, Path]:
        """Every file the job reads, by key (stream, audio, fdp, texture, face_mesh, face_points)."""
        found = {"stream": self.stream, "audio": self.audio, "fdp": self.fdp,
                 **{k: self.options.get(k) for k in PATH_OPTIONS}}
        return {k: v for k, v in found.items() if v is not None}


@dataclass(frozen=True)
class Manifest:
    path: Path
    jobs: tuple[Job, ...]


SHOWN_PROBLEMS = 20
"""Problems a manifest's error line spells out (all are in :attr:`.BatchError.problems`): 10,000 jobs of a
missing file made one line of 538 KB."""


def load_manifest(path: str | os.PathLike) -> Manifest:
    """Read and check a JSON or CSV manifest; one :class:`.BatchError` lists every fault with its place."""
    path = Path(path)
    text = _read_text(path)
    if path.suffix.lower() == ".json":
        defaults, entries = _json_entries(text, path)
    else:
        defaults, entries = {}, _csv_entries(text, path)
    if not entries:
        raise BatchError("the manifest lists no jobs", where=str(path),
                         hint="give one job (at least a 'stream') per entry or row")
    problems: list[str] = []
    base = path.resolve().parent
    defaults = _checked_defaults(defaults, base, problems)
    jobs = []
    for index, (line, entry) in enumerate(entries):
        job = _job(index, f"job {index} at line {line}", entry, defaults, base, problems)
        if job is not None:
            jobs.append(job)
    _check_outputs(jobs, problems)
    if problems:
        shown = "; ".join(problems[:SHOWN_PROBLEMS])
        if len(problems) > SHOWN_PROBLEMS:
            shown += f"; and {len(problems) - SHOWN_PROBLEMS:,} more"
        raise BatchError(f"{len(problems)} problem{'s' if len(problems) > 1 else ''}: {shown}",
                         where=str(path), hint="fix these entries of the manifest and run again",
                         problems=tuple(problems))
    return Manifest(path, tuple(jobs))


def _read_text(path: Path) -> str:
    """The manifest's text: at most :data:`MAX_MANIFEST_BYTES`, UTF-8 (a bad byte at its line:column)."""
    try:
        if not path.is_file():
            raise BatchError("no such manifest" if not path.exists() else "the manifest is not a file",
                             where=str(path), hint="give a .json or .csv manifest")
        with open(path, "rb") as fh:
            raw = fh.read(MAX_MANIFEST_BYTES + 1)
    except OSError as exc:
        raise BatchError(f"cannot read the manifest ({exc.strerror or exc})", where=str(path)) from None
    if len(raw) > MAX_MANIFEST_BYTES:
        raise BatchError(f"the manifest is over {MAX_MANIFEST_BYTES >> 20} MiB", where=str(path))
    return jsonio.json_text(raw, str(path), _located, "a manifest")


def _located(path: str, line: int | None, column: int | None, problem: str, hint: str) -> BatchError:
    """A :class:`BatchError` at ``path:line:column``: the error type :mod:`mpeg4fa.jsonio` reports through."""
    where = path if line is None else f"{path}:{line}" if column is None else f"{path}:{line}:{column}"
    return BatchError(problem, where=where, hint=hint)


# -- the two forms -----------------------------------------------------------------------------

_JSON_SPACE = " \t\n\r"


def _skip(text: str, pos: int) -> int:
    while pos < len(text) and text[pos] in _JSON_SPACE:
        pos += 1
    return pos


def _json_entries(text: str, path: Path) -> tuple[dict, list[tuple[int, Any]]]:
    """``(defaults, [(line, job entry)])``: the document is parsed whole first, then walked for the lines."""
    document = jsonio.loads(text, str(path), max_bytes=4 * MAX_MANIFEST_BYTES, max_depth=MAX_DEPTH, error=_located,
                            what="a batch manifest")
    decoder = json.JSONDecoder()
    start = _skip(text, len(text) - len(jsonio.json_text(text, str(path))))  # where loads began: past a BOM it dropped
    if isinstance(document, dict):
        unknown = sorted(set(document) - {"defaults", "jobs"})
        if unknown:
            raise BatchError(f"unknown top-level key {unknown[0]!r}", where=str(path),
                             hint="the top level has 'defaults' and 'jobs'")
        jobs, defaults = document.get("jobs"), document.get("defaults") or {}
        if not isinstance(defaults, dict):
            raise BatchError("'defaults' is not an object", where=str(path))
        start = _member_start(text, start, "jobs", decoder)
    else:
        jobs, defaults = document, {}
    if not isinstance(jobs, list):
        raise BatchError("no list of jobs", where=str(path),
                         hint="a list of jobs, or {\"defaults\": {...}, \"jobs\": [...]}")
    return defaults, list(zip(_element_lines(text, start, decoder), jobs))


def _member_start(text: str, pos: int, name: str, decoder: json.JSONDecoder) -> int:
    """Where the value of the (last) member ``name`` of the object at ``pos`` begins."""
    found, pos = -1, _skip(text, pos + 1)
    while text[pos] != "}":
        key, pos = decoder.raw_decode(text, pos)
        pos = _skip(text, _skip(text, pos) + 1)  # past the colon
        if key == name:
            found = pos
        _, pos = decoder.raw_decode(text, pos)
        pos = _skip(text, pos)
        if text[pos] == ",":
            pos = _skip(text, pos + 1)
    return found


def _element_lines(text: str, pos: int, decoder: json.JSONDecoder) -> list[int]:
    """The line on which each element of the array at ``pos`` begins (the document is well formed)."""
    lines, pos, index = [], _skip(text, pos + 1), jsonio.LineIndex(text)
    while text[pos] != "]":
        lines.append(index.line(pos))  # line starts found once: linear, not a recount per job
        _, pos = decoder.raw_decode(text, pos)
        pos = _skip(text, pos)
        if text[pos] == ",":
            pos = _skip(text, pos + 1)
    return lines


def _csv_entries(text: str, path: Path) -> list[tuple[int, dict]]:
    reader = csv.reader(io.StringIO(text, newline=""), strict=True)  # an unclosed quote is an error, not a cell
    entries: list[tuple[int, dict]] = []
    header: list[str] | None = None
    try:
        while True:
            line = reader.line_num + 1
            try:
                row = next(reader)
            except StopIteration:
                break
            if not any(cell.strip() for cell in row):
                continue
            if header is None:
                header = [cell.strip() for cell in row]
                _check_header(header, path, line)
                continue
            if len(row) > len(header):
                raise BatchError(f"{len(row)} cells under a header of {len(header)} columns",
                                 where=f"{path}:{line}", hint="quote cells that hold commas")
            entries.append((line, {k: v.strip() for k, v in zip(header, row) if v.strip()}))
    except csv.Error as exc:
        raise BatchError(f"not valid CSV: {exc}", where=f"{path}:{reader.line_num}",
                         hint="close every quote a cell opens (cells holding commas are quoted)") from None
    if header is None:
        raise BatchError("the manifest is empty", where=str(path),
                         hint="a header row (stream,output,...) and one row a job")
    return entries


def _check_header(header: list[str], path: Path, line: int) -> None:
    for name in header:
        if name not in KEYS:
            raise BatchError(f"unknown column {name!r}{_did_you_mean(name)}", where=f"{path}:{line}",
                             hint=f"columns: {', '.join(KEYS)}")
    if "stream" not in header:
        raise BatchError("no 'stream' column", where=f"{path}:{line}", hint="the header names the columns: stream,...")
    twice = sorted({n for n in header if header.count(n) > 1})
    if twice:
        raise BatchError(f"column {twice[0]!r} is named twice", where=f"{path}:{line}")


def _did_you_mean(name: str) -> str:
    close = difflib.get_close_matches(name, KEYS, n=1)
    return f" (did you mean {close[0]!r}?)" if close else ""


# -- checking entries ----------------------------------------------------------------------------

def _checked_defaults(defaults: dict, base: Path, problems: list[str]) -> dict:
    checked = {}
    for key, value in defaults.items():
        if key not in (*OPTIONS, *PATH_OPTIONS, "audio", "fdp"):
            problems.append(f"defaults: {'unknown key' if key not in KEYS else 'not a default'} {key!r}"
                            f"{_did_you_mean(key) if key not in KEYS else ''}")
        elif value is not None:
            checked[key] = value
    return checked


def _flattened(entry: dict, where: str, problems: list[str]) -> dict | None:
    """A JSON job with its ``options`` object merged in (a key given in both places is a fault)."""
    nested = entry.get("options")
    if nested is None:
        return {k: v for k, v in entry.items() if k != "options"}
    if not isinstance(nested, dict):
        problems.append(f"{where}: 'options' is not an object")
        return None
    both = sorted(set(nested) & set(entry))
    if both:
        problems.append(f"{where}: {both[0]!r} is given both in the job and in its options")
        return None
    return {**{k: v for k, v in entry.items() if k != "options"}, **nested}


def _job(index: int, where: str, entry: Any, defaults: dict, base: Path, problems: list[str]) -> Job | None:
    if not isinstance(entry, dict):
        problems.append(f"{where}: a job is an object with at least a 'stream', not {type(entry).__name__}")
        return None
    entry = _flattened(entry, where, problems)
    if entry is None:
        return None
    before = len(problems)
    for key in entry:
        if key not in KEYS:
            problems.append(f"{where}: unknown key {key!r}{_did_you_mean(key)}")
    given = {**defaults, **{k: v for k, v in entry.items() if v is not None and v != ""}}
    if "stream" not in given:
        problems.append(f"{where}: no 'stream'")
    paths = {key: _input_path(given[key], key, where, base, problems)
             for key in (*INPUT_KEYS, *PATH_OPTIONS) if key in given}
    chosen: dict[str, Any] = {}
    for key, (rule, default) in OPTIONS.items():
        try:
            chosen[key] = rule(given[key]) if key in given else default
        except _Bad as exc:
            problems.append(f"{where}: {key}: {exc}")
    _check_combinations(chosen, given, where, problems)
    output = _output_name(given, paths.get("stream"), where, problems)
    if len(problems) > before:
        return None
    chosen.update({key: paths.get(key) for key in PATH_OPTIONS})
    return Job(index=index, where=where, stream=paths["stream"], output=output, audio=paths.get("audio"),
               fdp=paths.get("fdp"), options=chosen)


def _input_path(value: Any, key: str, where: str, base: Path, problems: list[str]) -> Path | None:
    if not isinstance(value, str) or not value.strip():
        problems.append(f"{where}: {key}: expected a file path")
        return None
    path = base / Path(value.strip()).expanduser()
    try:
        if not path.is_file():
            problems.append(f"{where}: no such {key} file {value.strip()}" if not path.exists()
                            else f"{where}: {key} {value.strip()} is not a file")
            return None
    except OSError as exc:  # a name too long, a path through a file...: said, with the others
        problems.append(f"{where}: {key} {value.strip()[:80]!r}: {exc.strerror or exc}")
        return None
    return Path(os.path.abspath(path))


def _check_combinations(chosen: dict, given: dict, where: str, problems: list[str]) -> None:
    if chosen.get("blocks") is not None and chosen.get("deformer") != "blocks":
        problems.append(f"{where}: blocks goes with deformer blocks, not {chosen.get('deformer')}")
    if ("face_mesh" in given) != ("face_points" in given):
        problems.append(f"{where}: face_mesh and face_points go together "
                        "(an OBJ and its feature points, JSON label -> vertex index or [x, y, z])")


def _output_name(given: dict, stream: Path | None, where: str, problems: list[str]) -> str:
    value = given.get("output")
    if value is None:
        return f"{stream.stem}.mp4" if stream is not None else ""
    if not isinstance(value, str):
        problems.append(f"{where}: output: expected a file name")
        return ""
    name = PurePosixPath(value.strip().replace("\\", "/"))
    if name.is_absolute() or ".." in name.parts or not name.parts or name.name.startswith("."):
        problems.append(f"{where}: output {value!r} must be a name under the output folder "
                        "(no absolute path, no '..', not hidden)")
    elif name.suffix.lower() not in VIDEO_SUFFIXES:
        problems.append(f"{where}: output {value!r} is not a video name: end it in {', '.join(VIDEO_SUFFIXES)}")
    return str(name)


def _check_outputs(jobs: list[Job], problems: list[str]) -> None:
    seen: dict[str, Job] = {}
    for job in jobs:
        key = job.output.lower()  # case-insensitive file systems (macOS, Windows) would merge them
        if key in seen:
            problems.append(f"{job.where}: output {job.output} is also the output of {seen[key].where}")
        else:
            seen[key] = job
