"""The suite as data: ``conformance/manifest.json`` names every vector, its face, its expected result.

Layout (paths relative to the folder holding the manifest)::

    {"suite": "mpeg4fa-fba-conformance", "version": 1,
     "faces":   {"adult": {"fdp": "faces/adult.fdp", "sha256": "...", "description": "..."}, ...},
     "vectors": [{"id": "syntax/quant-05", "group": "syntax", "confidence": "V",
                  "description": "...", "rules": ["SYNTAX.md 4.2 ..."],
                  "stream": "vectors/syntax/quant-05.fba", "sha256": "...",
                  "face": "adult" | null, "expect": "decode" | "reject",
                  "expected": "vectors/syntax/quant-05.expected.json", "expected_sha256": "..."}, ...]}

``confidence`` is the rule's: V verified on real streams, S stated in a source, M unverified.
A vector whose confidence is M is *informative*: reported, never failed (see :attr:`Vector.required`).

An expected file (JSON) for ``expect == "decode"``::

    {"frames": n, "fps": 25.0, "timestamps": [n seconds],
     "columns": [c, ...],                        # optional: the FAP columns (0-based, 0 = FAP 1) stored below
     "sent":  {"mask": [[68 0/1]], "values": [[68 int]], "viseme": [[4 int]], "expression": [[6 int]]},
     "shown": [[68 float]],                      # what a decoder shows: hold/interpolate, FAP 1/2 expanded
     "feature_points": {"labels": ["2.1", ...], "positions": [[[x, y, z], ...] per frame],   # with a face
                        "checkable": [[[0/1 x, y, z] per label] per frame]},   # or "axes": per label
     "tolerance": {"shown": float, "feature_points": float}}      # FAPU units / the FDP's length units

With ``columns``, rows of ``mask``, ``values`` and ``shown`` hold only those columns (every other
column is never sent and shows 0), and ``viseme`` / ``expression`` are left out unless column 0 /
1 is listed (they are then all 0): a long stream that moves one FAP stays small.
:meth:`Manifest.expected` (and :func:`full_width`) give the file with all 68 columns back.

and for ``expect == "reject"``: ``{"reject": true, "bit_offset": N, "frames_before": k}`` (the bit where
the fault is detectable, and how many frames decode before it).
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import asdict, dataclass, field
from pathlib import Path
from collections.abc import Sequence
from typing import Any

import numpy as np

from mpeg4fa import jsonio
from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.conformance.rules import check_rules, rule_of
from mpeg4fa.spec import N_FAPS
from mpeg4fa.spec.conformance_rules import CONFORMANCE_RULES

SUITE = "mpeg4fa-fba-conformance"
VERSION = 1
GROUPS = ("syntax", "semantics", "reject", "informative")
CONFIDENCES = ("V", "S", "M")


@dataclass(frozen=True)
class Face:
    name: str
    fdp: str
    sha256: str
    description: str = ""


@dataclass(frozen=True)
class Vector:
    id: str
    group: str
    confidence: str
    description: str
    stream: str
    sha256: str
    expect: str
    expected: str
    expected_sha256: str
    face: str | None = None
    rules: tuple[str, ...] = ()
    checks: tuple[tuple[str, str], ...] = ()

    @property
    def check_rules(self) -> dict[str, str]:
        """Rule id per check name (``spec/conformance_rules.csv``): the manifest's ``checks``, else the
        suite's table for this vector (:func:`mpeg4fa.conformance.rules.check_rules`)."""
        return dict(self.checks) if self.checks else check_rules(self.id, self.confidence)

    @property
    def required(self) -> bool:
        """Whether any check of this vector can fail the suite (some check's rule is V or S and required)."""
        rules = self.check_rules
        names = ("reject", "reject_offset") if self.expect == "reject" else ("timestamps", "sent", "shown",
                                                                             "feature_points")
        return any(rule_of(name, rules).required for name in names)


@dataclass
class Manifest:
    root: Path
    faces: dict[str, Face] = field(default_factory=dict)
    vectors: list[Vector] = field(default_factory=list)

    def path(self, relative: str) -> Path:
        """``relative`` inside the suite's folder; ConformanceError for a path that leaves it (``..``, absolute)."""
        inside = inside_suite(self.root, relative)
        if inside is None:
            raise ConformanceError(f"the path {relative!r} leaves the suite's folder", where=str(self.root / "manifest.json"),
                                   hint="paths in a manifest are relative to its folder and stay inside it")
        return inside

    def expected(self, vector: Vector) -> dict[str, Any]:
        """The vector's expected file, checked and with all 68 columns as arrays (:func:`full_width`)."""
        path = self.path(vector.expected)
        doc = jsonio.read_json(path, max_bytes=MAX_EXPECTED_BYTES, error=_located, what="an expected file")
        return checked_expected(doc, vector.expect, str(path))

    def groups(self) -> list[str]:
        return sorted({v.group for v in self.vectors}, key=lambda g: (GROUPS + (g,)).index(g))

    def save(self) -> Path:
        doc = {"suite": SUITE, "version": VERSION,
               "faces": {name: {k: v for k, v in asdict(face).items() if k != "name"}
                         for name, face in sorted(self.faces.items())},
               "vectors": [{**asdict(v), "rules": list(v.rules), "checks": dict(v.checks)} for v in self.vectors]}
        target = self.root / "manifest.json"
        target.write_text(json.dumps(doc, indent=1, ensure_ascii=False) + "\n", encoding="utf-8")
        return target


_WIDTHS = {"viseme": 4, "expression": 6}
_HIGH_LEVEL_COLUMN = {"viseme": 0, "expression": 1}


def compact(doc: dict[str, Any], columns: Sequence[int]) -> dict[str, Any]:
    """An expected decode file in the compact form: only ``columns`` of mask, values and shown."""
    cols = sorted(int(c) for c in columns)
    out = {**doc, "columns": cols, "shown": [[row[c] for c in cols] for row in doc["shown"]]}
    sent = {key: [[row[c] for c in cols] for row in doc["sent"][key]] for key in ("mask", "values")}
    for key, col in _HIGH_LEVEL_COLUMN.items():
        if col in cols:
            sent[key] = doc["sent"][key]
    out["sent"] = sent
    return out


MAX_EXPECTED_BYTES = 64 << 20
"""Largest expected file read (64 MiB; the suite's largest is 0.4 MB)."""
MAX_EXPECTED_FRAMES = 50_000
"""Most frames an expected file may hold (the suite's longest has 12,700): bounds the arrays
:func:`full_width` makes (68 columns a frame) whatever count a file claims."""


def full_width(doc: dict[str, Any], where: str = "expected file") -> dict[str, Any]:
    """An expected decode file with every column, as numpy arrays (``sent`` ints, ``shown`` floats),
    whether or not it was stored compact (see the module); ConformanceError when its parts disagree."""
    try:
        n = int(doc["frames"])
        if not 0 <= n <= MAX_EXPECTED_FRAMES:
            raise ValueError(f"{n} frames (at most {MAX_EXPECTED_FRAMES:,})")
        cols = [int(c) for c in doc["columns"]] if "columns" in doc else list(range(N_FAPS))
        if len(set(cols)) != len(cols) or not all(0 <= c < N_FAPS for c in cols):
            raise ValueError("columns must be distinct FAP columns 0..67")
        out = {key: value for key, value in doc.items() if key != "columns"}

        def widen(rows, dtype) -> np.ndarray:
            try:
                part = np.asarray(rows, dtype=dtype)
            except ValueError:
                raise ValueError("rows of unequal lengths: a row per frame, a value per listed columns") from None
            if part.shape != (n, len(cols)):
                raise ValueError(f"rows of shape {part.shape}, expected ({n}, {len(cols)}): a row per frame, a value per listed columns")
            full = np.zeros((n, N_FAPS), dtype=dtype)
            full[:, cols] = part
            return full

        shown = widen(doc["shown"], np.float64)
        if not np.isfinite(shown).all():
            raise ValueError("shown values not finite")
        out["shown"] = shown
        timestamps = np.asarray(doc["timestamps"], dtype=np.float64)
        if timestamps.shape != (n,) or not np.isfinite(timestamps).all():
            raise ValueError(f"timestamps of shape {timestamps.shape}, expected ({n},)")
        out["timestamps"] = timestamps
        given = doc.get("sent") or {}
        if not isinstance(given, dict):
            raise ValueError('"sent" is not an object')
        sent = {key: widen(given[key], np.int64) for key in ("mask", "values")}
        for key, col in _HIGH_LEVEL_COLUMN.items():
            if col in cols:
                sent[key] = np.asarray(given[key], dtype=np.int64)
                if sent[key].shape != (n, _WIDTHS[key]):
                    raise ValueError(f'"sent.{key}" of shape {sent[key].shape}')
            else:
                sent[key] = np.zeros((n, _WIDTHS[key]), dtype=np.int64)
        out["sent"] = sent
    except (TypeError, ValueError, IndexError, KeyError, OverflowError) as exc:
        problem = f"no {exc}" if isinstance(exc, KeyError) else str(exc)
        raise ConformanceError(f"an expected file that does not hold together: {problem}", where=where) from None
    return out


def checked_expected(doc: Any, expect: str, where: str) -> dict[str, Any]:
    """An expected file checked for its kind: a reject file's ``bit_offset`` an integer, a decode file's
    arrays of matching shapes (:func:`full_width`); ConformanceError at ``where`` otherwise."""
    if not isinstance(doc, dict):
        raise ConformanceError("an expected file must be a JSON object", where=where)
    if expect == "reject":
        bit = doc.get("bit_offset")
        if isinstance(bit, bool) or not isinstance(bit, int) or bit < 0:
            raise ConformanceError('a reject vector\'s expected file needs "bit_offset", a bit count', where=where)
        return doc
    doc = full_width(doc, where)
    fp = doc.get("feature_points")
    if fp is not None:
        try:
            labels = [str(label) for label in fp["labels"]]
            positions = np.asarray(fp["positions"], dtype=np.float64)
            if positions.shape != (doc["frames"], len(labels), 3) or not np.isfinite(positions).all():
                raise ValueError(f"positions of shape {positions.shape}")
            from mpeg4fa.conformance.compare import pinned_axes
            pinned_axes(fp, int(doc["frames"]))
        except (TypeError, ValueError, KeyError) as exc:
            raise ConformanceError(f'"feature_points" does not hold together: {exc}', where=where) from None
    return doc


def inside_suite(root: Path, relative: Any) -> Path | None:
    """``root / relative`` when ``relative`` is a relative path that stays inside ``root``; else None."""
    if not isinstance(relative, str) or not relative or "\0" in relative:
        return None
    candidate = Path(relative)
    if candidate.is_absolute() or ".." in candidate.parts:
        return None
    path = root / candidate
    try:
        path.resolve().relative_to(root.resolve())
    except (ValueError, OSError):
        return None
    return path


def _located(path: str, line: int | None, column: int | None, problem: str, hint: str) -> ConformanceError:
    where = path if line is None else f"{path}:{line}" if column is None else f"{path}:{line}:{column}"
    return ConformanceError(problem, where=where, hint=hint)


def sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


_VECTOR_KEYS = {"id": str, "group": str, "confidence": str, "description": str, "stream": str, "sha256": str,
                "expect": str, "expected": str, "expected_sha256": str}


def load_manifest(path: str | Path) -> Manifest:
    """The manifest at ``path`` (the file, or the folder holding ``manifest.json``), checked: a missing key,
    a wrong type, an unknown rule or a path that leaves the suite is one ConformanceError naming the entry."""
    path = Path(path)
    if path.is_dir():
        path = path / "manifest.json"
    where = str(path)
    doc = jsonio.read_json(path, max_bytes=MAX_EXPECTED_BYTES, error=_located, what="a suite manifest")
    if not isinstance(doc, dict) or doc.get("suite") != SUITE or doc.get("version") != VERSION:
        raise ConformanceError(f"not a {SUITE} manifest of version {VERSION}", where=where)
    faces_doc, vectors_doc = doc.get("faces", {}), doc.get("vectors")
    if not isinstance(faces_doc, dict):
        raise ConformanceError('"faces" must be an object of face name -> {"fdp", "sha256"}', where=where)
    if not isinstance(vectors_doc, list):
        raise ConformanceError('"vectors" must be a list of vector entries', where=where)
    root = path.parent
    faces = {}
    for name, entry in faces_doc.items():
        at = f"{where}: faces.{name}"
        if not isinstance(entry, dict) or not isinstance(entry.get("fdp"), str) \
                or not isinstance(entry.get("sha256", ""), str) or not isinstance(entry.get("description", ""), str):
            raise ConformanceError('a face must be an object with "fdp" (a path) and "sha256"', where=at)
        if inside_suite(root, entry["fdp"]) is None:
            raise ConformanceError(f"the FDP path {entry['fdp']!r} leaves the suite's folder", where=at)
        faces[name] = Face(name, entry["fdp"], entry.get("sha256", ""), entry.get("description", ""))
    vectors, seen = [], set()
    for i, entry in enumerate(vectors_doc):
        vectors.append(_vector(entry, f"{where}: vectors[{i}]", root, faces))
        if vectors[-1].id in seen:
            raise ConformanceError(f"vector {vectors[-1].id!r} is listed twice", where=f"{where}: vectors[{i}]")
        seen.add(vectors[-1].id)
    return Manifest(root, faces, vectors)


def _vector(entry: Any, at: str, root: Path, faces: dict[str, Face]) -> Vector:
    """One manifest entry as a :class:`Vector`, or a ConformanceError at ``at`` saying what is wrong."""
    if not isinstance(entry, dict):
        raise ConformanceError("a vector entry must be an object", where=at)
    for key, kind in _VECTOR_KEYS.items():
        if not isinstance(entry.get(key), kind):
            raise ConformanceError(f'"{key}" is missing or not a string', where=f"{at} ({entry.get('id', '?')})")
    at = f"{at} ({entry['id']})"
    if entry["expect"] not in ("decode", "reject") or entry["confidence"] not in CONFIDENCES:
        raise ConformanceError('"expect" must be decode or reject, "confidence" V, S or M', where=at)
    for key in ("stream", "expected"):
        if inside_suite(root, entry[key]) is None:
            raise ConformanceError(f"the {key} path {entry[key]!r} leaves the suite's folder", where=at)
    face = entry.get("face")
    if face is not None and (not isinstance(face, str) or face not in faces):
        raise ConformanceError(f"face {face!r} is not one of the manifest's faces", where=at)
    rules = entry.get("rules", [])
    checks = entry.get("checks", {})
    if not isinstance(rules, list) or not all(isinstance(r, str) for r in rules) or not isinstance(checks, dict) \
            or not all(isinstance(k, str) and isinstance(v, str) for k, v in checks.items()):
        raise ConformanceError('"rules" must be a list of strings and "checks" an object of check -> rule id', where=at)
    unknown = sorted(set(checks.values()) - set(CONFORMANCE_RULES))
    if unknown:
        raise ConformanceError(f"unknown rule{'s' if len(unknown) > 1 else ''} {', '.join(unknown)}", where=at,
                               hint="rules are the ids of spec/conformance_rules.csv")
    known = {k: entry[k] for k in _VECTOR_KEYS}
    return Vector(**known, face=face, rules=tuple(rules), checks=tuple(sorted(checks.items())))


def default_root() -> Path:
    """The suite committed with the project: ``conformance/`` at the top of a checkout, else the copy
    installed with the package (``mpeg4fa.conformance_data``)."""
    checkout = Path(__file__).resolve().parents[2] / "conformance"
    if (checkout / "manifest.json").is_file():
        return checkout
    from importlib import resources

    return Path(str(resources.files("mpeg4fa.conformance_data")))
