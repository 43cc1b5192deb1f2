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

from mpeg4fa.conformance.errors import ConformanceError
from mpeg4fa.spec import N_FAPS

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

    @property
    def required(self) -> bool:
        """Whether a decoder fails the suite when it fails this vector (not for unverified rules)."""
        return self.confidence != "M"


@dataclass
class Manifest:
    root: Path
    faces: dict[str, Face] = field(default_factory=dict)
    vectors: list[Vector] = field(default_factory=list)

    def path(self, relative: str) -> Path:
        return self.root / relative

    def expected(self, vector: Vector) -> dict[str, Any]:
        """The vector's expected file, with all 68 columns (:func:`full_width`)."""
        return full_width(json.loads(self.path(vector.expected).read_text(encoding="utf-8")))

    def groups(self) -> list[str]:
        return sorted({v.group for v in self.vectors}, key=lambda g: (GROUPS + (g,)).index(g))

    def save(self) -> Path:
        doc = {"suite": SUITE, "version": VERSION,
               "faces": {name: {k: v for k, v in asdict(face).items() if k != "name"}
                         for name, face in sorted(self.faces.items())},
               "vectors": [{**asdict(v), "rules": list(v.rules)} for v in self.vectors]}
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


def full_width(doc: dict[str, Any]) -> dict[str, Any]:
    """An expected decode file with every column, whether or not it was stored compact (see the module)."""
    if "columns" not in doc:
        return doc
    try:
        cols = [int(c) for c in doc["columns"]]
        n = int(doc["frames"])
        out = {key: value for key, value in doc.items() if key != "columns"}

        def widen(rows, fill=0):
            full = [[fill] * N_FAPS for _ in range(n)]
            for k, row in enumerate(rows):
                for c, x in zip(cols, row, strict=True):
                    full[k][c] = x
            return full

        out["shown"] = widen(doc["shown"], 0)
        sent = dict(doc.get("sent", {}))
        for key in ("mask", "values"):
            if key in sent:
                sent[key] = widen(sent[key])
        for key, col in _HIGH_LEVEL_COLUMN.items():
            if col not in cols:
                sent[key] = [[0] * _WIDTHS[key] for _ in range(n)]
        out["sent"] = sent
    except (TypeError, ValueError, IndexError, KeyError) as exc:
        raise ConformanceError(f"a compact expected file does not match its columns: {exc}") from None
    return out


def sha256(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def load_manifest(path: str | Path) -> Manifest:
    """The manifest at ``path`` (the file, or the folder holding ``manifest.json``)."""
    path = Path(path)
    if path.is_dir():
        path = path / "manifest.json"
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise ConformanceError(f"cannot read the manifest: {exc.strerror or exc}", where=str(path)) from None
    except ValueError as exc:
        raise ConformanceError(f"not JSON: {exc}", where=str(path)) from None
    if not isinstance(doc, dict) or doc.get("suite") != SUITE or doc.get("version") != VERSION:
        raise ConformanceError(f"not a {SUITE} manifest of version {VERSION}", where=str(path))
    faces = {name: Face(name, **entry) for name, entry in doc.get("faces", {}).items()}
    vectors = [Vector(**{**entry, "rules": tuple(entry.get("rules", ()))}) for entry in doc["vectors"]]
    return Manifest(path.parent, faces, vectors)


def default_root() -> Path:
    """The suite committed with the project: ``conformance/`` at the top of a checkout, else the copy
    installed with the package (``mpeg4fa.conformance_data``)."""
    checkout = Path(__file__).resolve().parents[2] / "conformance"
    if (checkout / "manifest.json").is_file():
        return checkout
    from importlib import resources

    return Path(str(resources.files("mpeg4fa.conformance_data")))
