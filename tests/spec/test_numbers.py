"""The standard's numbers live in spec/ and are loaded, never retyped.

Two kinds of check: the columns that replaced rules in code (counterpart FAPs,
mirror feature points, FAPU names, counts, full intensity, the angle unit,
Mandarin weights) agree with each other and with the names and descriptions they
were once derived from; and the package source outside ``mpeg4fa/spec`` holds
none of the retired literals, so that they stay retired.
"""
from __future__ import annotations

import ast
import dataclasses
import functools
import io
import re
import tokenize
from pathlib import Path

import pytest

import mpeg4fa.spec as spec

PACKAGE = Path(spec.__file__).resolve().parents[1]
SPEC_DIR = spec._load.data_dir()
_SWAPS = (("_l_", "_r_"), ("_lm", "_rm"))


def _swapped(name: str) -> str:
    for a, b in _SWAPS:
        if a in name:
            return name.replace(a, b)
        if b in name:
            return name.replace(b, a)
    return name


# ---- counterpart FAPs ------------------------------------------------------------------------------

def test_partners_are_symmetric_and_distinct():
    partners = spec.FAP_PARTNERS
    assert partners.shape == (spec.N_FAPS, 2) and not partners.flags.writeable
    for i in range(spec.N_FAPS):
        for k in range(2):
            p = partners[i, k]
            if p >= 0:
                assert p != i and partners[p, k] == i, (i + 1, k)
    assert (partners[:2] == -1).all()  # FAP 1 and 2 have none


def test_lr_partner_agrees_with_left_right_names():
    for fap in spec.FAPS:
        other = spec.FAP_BY_NAME.get(_swapped(fap.name))
        expected = other.number if other is not None and other is not fap else None
        assert fap.lr_partner == expected, fap.name


def test_lr_partners_differ_only_by_side():
    mirrored = {"left": "right", "right": "left"}
    for fap in spec.FAPS:
        if fap.lr_partner is None:
            continue
        other = spec.FAPS[fap.lr_partner - 1]
        assert (other.fapu, other.group, other.quant_step, other.i_max, other.p_max, other.unidirectional) == (
            fap.fapu, fap.group, fap.quant_step, fap.i_max, fap.p_max, fap.unidirectional), fap.name
        assert other.direction in (fap.direction, mirrored.get(fap.direction)), fap.name
        assert other.io_partner is None or fap.io_partner is not None


def test_io_partner_pairs_inner_and_outer_lips():
    pairs = {(fap.number, fap.io_partner) for fap in spec.FAPS if fap.io_partner is not None}
    inner = {f.number for f in spec.FAPS if f.io_partner is not None and spec.FAP_BY_NAME.get(f.name + "_o")}
    assert inner == set(range(4, 14))
    for a, b in pairs:
        low, high = min(a, b), max(a, b)
        assert spec.FAPS[high - 1].name == spec.FAPS[low - 1].name + "_o"
        assert spec.FAPS[high - 1].direction == spec.FAPS[low - 1].direction
    assert len(pairs) == 20


def test_lr_partner_moves_the_mirror_point():
    for fap in spec.FAPS:
        if fap.lr_partner is not None:
            other = spec.FAPS[fap.lr_partner - 1]
            assert [spec.FEATURE_POINT_MIRROR.get(p) for p in fap.feature_point] == list(other.feature_point)


# ---- mirror feature points -------------------------------------------------------------------------

def test_mirror_is_an_involution_across_sides():
    by_label = {fp.label: fp for fp in spec.FEATURE_POINTS}
    mirror = spec.FEATURE_POINT_MIRROR
    assert len(mirror) == 64
    for label, twin in mirror.items():
        assert mirror[twin] == label and twin != label
        assert {by_label[label].side, by_label[twin].side} == {"left", "right"}
    for fp in spec.FEATURE_POINTS:
        assert (fp.mirror is None) == (fp.side is None) == (fp.label not in mirror)


def test_mirror_and_side_agree_with_the_descriptions():
    """Swapping left and right (or the defining points' twins) in a description gives the twin's."""
    text = {fp.label: fp.description.lower() for fp in spec.FEATURE_POINTS}
    label_of = {d: label for label, d in text.items()}
    side_word = re.compile(r"\b(left|right)\b")
    reference = re.compile(r"\b\d+\.\d+\b")
    for fp in spec.FEATURE_POINTS:
        d = text[fp.label]
        words = side_word.findall(d)
        if words:
            swapped = side_word.sub(lambda m: "right" if m.group(1) == "left" else "left", d)
            assert fp.side == words[-1], fp.label  # "Right corner of left eyebrow" lies on the left
        else:
            swapped = reference.sub(lambda m: spec.FEATURE_POINT_MIRROR.get(m.group(), m.group()), d)
        twin = label_of.get(swapped)
        assert fp.mirror == (twin if twin != fp.label else None), fp.label


# ---- FAPU names, angle unit, full intensity, counts, Mandarin weights --------------------------------

def test_fapu_names_have_one_order():
    from mpeg4fa.face.fapu import Fapu
    from mpeg4fa.fdp.model import FAPU_KEYS

    assert spec.FAPU_NAMES == ("IRISD0", "ES0", "ENS0", "MNS0", "MW0")
    assert FAPU_KEYS == spec.FAPU_NAMES
    assert tuple(f.name for f in dataclasses.fields(Fapu)) == spec.FAPU_NAMES
    for name in spec.FAPU_NAMES:
        record = spec.FAPU[name[:-1]]
        assert record.distance == name and record.definition.startswith(name + " = ")
    line = next(x for x in (SPEC_DIR / "FDP_STREAM.md").read_text().splitlines() if "FAPU keys are numbered" in x)
    assert ", ".join(spec.FAPU_NAMES) in line


def test_angle_unit_and_full_intensity():
    assert spec.ANGLE_UNIT == 1e-5 and spec.FAPU["AU"].radians == spec.ANGLE_UNIT
    assert spec.AU_PER_RADIAN == 100000 and isinstance(spec.AU_PER_RADIAN, int)
    assert spec.FULL_INTENSITY == 63
    fields = {(f.fap, f.field): f for f in spec.HIGH_LEVEL_FIELDS}
    for key in ((1, "blend"), (2, "intensity1"), (2, "intensity2")):
        assert fields[key].i_max == spec.FULL_INTENSITY


def test_counts_are_table_lengths_and_the_codec_uses_them():
    from mpeg4fa.fba import stream

    assert (spec.N_FAPS, spec.N_BAPS, spec.N_FAP_GROUPS, spec.N_BAP_GROUPS) == (68, 296, 10, 24)
    assert spec.N_FAPS == len(spec.FAPS) and spec.N_FAP_GROUPS == len(spec.FAP_GROUP_SLICES)
    assert spec.N_BAPS == len(spec.BAP_QUANT_STEP) and spec.N_BAP_GROUPS == len(spec.BAP_GROUPS)
    assert (stream.N_FAPS, stream.N_BAPS, stream.N_FAP_GROUPS, stream.N_BAP_GROUPS) == (
        spec.N_FAPS, spec.N_BAPS, spec.N_FAP_GROUPS, spec.N_BAP_GROUPS)


def test_mandarin_weights_come_from_the_table():
    from mpeg4fa.speech import graphemes, mandarin

    assert spec.MANDARIN_PART_WEIGHT == {"glide": 0.35, "main": 1.0, "ending": 0.6}
    assert spec.MANDARIN_INITIAL_WEIGHT == {"bpm": 0.7, "dtnl": 0.35, "f": 0.55}
    assert spec.MANDARIN_DEFAULT_INITIAL_WEIGHT == 0.5
    assert mandarin.FINAL_WEIGHT is spec.MANDARIN_PART_WEIGHT
    units = graphemes.syllable_units(mandarin.syllables("表")[0])  # b + iao: initial, glide, main, ending
    assert [u.weight for u in units] == [0.7, 0.35, 1.0, 0.6]


# ---- the retired literals stay retired -----------------------------------------------------------------

def _sources() -> list[Path]:
    """The package's modules but ``mpeg4fa/spec``, which loads the numbers (its docstrings may quote them)."""
    return sorted(p for p in PACKAGE.rglob("*.py") if "spec" not in p.relative_to(PACKAGE).parts[:1])


@functools.lru_cache(maxsize=1)
def _parsed(paths: tuple[Path, ...]) -> tuple[tuple[Path, ast.AST], ...]:
    return tuple((p, ast.parse(p.read_text(encoding="utf-8"), str(p))) for p in paths)


def _trees() -> tuple[tuple[Path, ast.AST], ...]:
    """Every module, ``mpeg4fa/spec`` included: it loads tables and has no business retyping them either."""
    return _parsed(tuple(sorted(PACKAGE.rglob("*.py"))))


def _where(path: Path, node: ast.AST | int) -> str:
    line = node if isinstance(node, int) else node.lineno
    return f"{path.relative_to(PACKAGE.parent)}:{line}"


def _code_lines(path: Path) -> list[tuple[int, list[tokenize.TokenInfo]]]:
    """Each logical line's tokens, without comments and strings (so prose may name the numbers)."""
    lines, current = [], []
    for tok in tokenize.generate_tokens(io.StringIO(path.read_text(encoding="utf-8")).readline):
        if tok.type in (tokenize.NEWLINE, tokenize.ENDMARKER):
            if current:
                lines.append((current[0].start[0], current))
            current = []
        elif tok.type not in (tokenize.COMMENT, tokenize.STRING, tokenize.NL, tokenize.INDENT, tokenize.DEDENT):
            current.append(tok)
    return lines


def test_sources_are_scanned():
    names = {p.relative_to(PACKAGE).as_posix() for p in _sources()}
    assert {"fba/stream.py", "speech/timeline.py", "fdp/model.py", "cli/model.py"} <= names
    assert not any(n.startswith("spec/") for n in names)


def test_no_retyped_full_intensity_counts_or_angle_unit():
    """63 (full blend/intensity), 68/296 (FAP/BAP counts), 1e-5 or 1e5 beside an angle: spec constants."""
    angle_words = {"pi", "radians", "degrees", "AU", "ANGLE", "angle"}
    found = []
    for path in _sources():
        for line, toks in _code_lines(path):
            words = {t.string for t in toks if t.type == tokenize.NAME}
            for k, tok in enumerate(toks):
                if tok.type != tokenize.NUMBER:
                    continue
                after_power = k > 0 and toks[k - 1].string == "**"  # 2**63: an integer width, not intensity
                if tok.string in ("63", "68", "296") and not after_power:
                    found.append(f"{_where(path, line)}: {tok.string}")
                elif re.fullmatch(r"[0-9.]+e[+-]?0*5|100000(\.0*)?", tok.string) and words & angle_words:
                    found.append(f"{_where(path, line)}: {tok.string} (the angle unit)")
    assert not found, "use mpeg4fa.spec (FULL_INTENSITY, N_FAPS, N_BAPS, ANGLE_UNIT, AU_PER_RADIAN): " + str(found)


def test_no_count_constants_or_length_checks():
    """No ``N_FAPS = 68``-style constant, no ``len(types) != 10`` (24 is left out: a common text length)."""
    found = []
    counts = {spec.N_FAPS, spec.N_BAPS, spec.N_FAP_GROUPS}
    for path, tree in _trees():
        for node in ast.walk(tree):
            if isinstance(node, (ast.Assign, ast.AnnAssign)) and isinstance(node.value, ast.Constant):
                targets = node.targets if isinstance(node, ast.Assign) else [node.target]
                if any(isinstance(t, ast.Name) and re.fullmatch(r"N_[A-Z_]+", t.id) for t in targets):
                    found.append(_where(path, node))
            if isinstance(node, ast.Compare) and isinstance(node.left, ast.Call) \
                    and getattr(node.left.func, "id", None) == "len":
                if any(isinstance(op, (ast.Eq, ast.NotEq)) and isinstance(c, ast.Constant) and c.value in counts
                       for op, c in zip(node.ops, node.comparators)):
                    found.append(_where(path, node))
    assert not found, "counts are the tables' lengths: import them from mpeg4fa.spec: " + str(found)


def test_no_fapu_name_lists():
    found = []
    for path, tree in _trees():
        for node in ast.walk(tree):
            if isinstance(node, (ast.Tuple, ast.List, ast.Set)):
                names = [e.value for e in node.elts if isinstance(e, ast.Constant) and e.value in spec.FAPU_NAMES]
                if len(names) >= 2:
                    found.append(_where(path, node))
    assert not found, "use mpeg4fa.spec.FAPU_NAMES (one order, from spec/fapu.csv): " + str(found)


def test_no_counterpart_or_mirror_rules_in_code():
    """Partners are the lr_partner/io_partner columns, mirrors the side/mirror columns: no name or text rules."""
    found = []
    for path, tree in _trees():
        for node in ast.walk(tree):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                if node.value in ("_l_", "_r_", "_lm", "_rm") or re.search(r"left\|right|right\|left", node.value):
                    found.append(_where(path, node))
    assert not found, "use FAP_PARTNERS / FEATURE_POINT_MIRROR (spec columns): " + str(found)


def test_no_mandarin_weight_tables_in_code():
    keys = {"glide", "main", "ending"} | {v.name for v in spec.CHINESE_VISEMES}
    found = []
    for path, tree in _trees():
        for node in ast.walk(tree):
            if isinstance(node, ast.Dict):
                pairs = [(k.value, v.value) for k, v in zip(node.keys, node.values)
                         if isinstance(k, ast.Constant) and isinstance(v, ast.Constant)]
                if sum(k in keys and isinstance(v, float) for k, v in pairs) >= 2:
                    found.append(_where(path, node))
    assert not found, "Mandarin weights live in spec/mandarin_weights.csv: " + str(found)


@pytest.mark.parametrize("snippet, flagged", [
    ("x = 63\n", True), ("y = 2**63 - 1\n", False), ("# 63 in a comment\nz = 1\n", False),
    ("a = np.pi / 1e-5\n", True), ("tol = 1e-5\n", False), ("n = len(t) != 10\n", False),
])
def test_literal_scan_is_precise(tmp_path, monkeypatch, snippet, flagged):
    """The scan flags the retyped numbers, not an integer width, a comment or an unrelated tolerance."""
    fake = tmp_path / "mod.py"
    fake.write_text(snippet)
    monkeypatch.setattr(f"{__name__}._sources", lambda: [fake])
    monkeypatch.setattr(f"{__name__}.PACKAGE", tmp_path)
    failed = False
    try:
        test_no_retyped_full_intensity_counts_or_angle_unit()
    except AssertionError:
        failed = True
    assert failed == flagged
