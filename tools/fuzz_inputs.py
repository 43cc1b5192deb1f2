"""What the fuzzer feeds the readers: seeds (real files and ones made here) and the mutations applied to them.

Why a file of its own: making inputs is one job, running and judging them
(``tools/fuzz.py``) another. Every mutator is ``(rng, data, pool) -> bytes``,
deterministic for a given ``random.Random`` state, so a case can be replayed.
"""
from __future__ import annotations

import functools
import io
import json
import math
import random
import re
import sys
import warnings
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from mpeg4fa.fba import EncodeOptions, FapStream, decode, demo_stream, encode  # noqa: E402
from mpeg4fa.fdp import (FaceDefMesh, FaceDefTable, FaceDefTransform, Fdp, FdpMesh, TextureImage,  # noqa: E402
                         fdp_to_bytes, fdp_to_json, sniff_fdp)
from mpeg4fa.fdp.model import LABELS  # noqa: E402
from mpeg4fa.formats import write_fap  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent))
import fuzz_seeds  # noqa: E402
from fuzz_text import draw_text, text_bytes  # noqa: E402

ORIGINAL_TARGETS = ("markup", "fdp-json", "fdp-xface", "fdp-binary", "fap", "fba")
READER_TARGETS = ("text", "stdin", "visemes", "points", "manifest", "conform", "bap", "wav", "image", "obj", "gltf")
"""Issue 26 item 9: every reader of item 4 and the text path (seeds: :mod:`fuzz_seeds`, texts: :mod:`fuzz_text`)."""
TARGETS = ORIGINAL_TARGETS + READER_TARGETS
"""Run order: the fast targets first, so the slow ones inherit the time the fast ones leave. A target's place
here seeds its cases (:meth:`Campaign.case_rng`), so new targets go at the end."""
MAX_INPUT = 2 << 20
"""Mutated inputs are cut to 2 MiB: big enough for a huge JSON array, small enough for 2 cores."""


# ---- seeds ------------------------------------------------------------------------------------------------


@dataclass
class Seed:
    name: str
    data: bytes


def _fap_bytes(stream: FapStream, crlf: bool = False) -> bytes:
    out = io.StringIO()
    write_fap(stream, out, name="seed.fap")
    text = out.getvalue()
    return (text.replace("\n", " \r\n") if crlf else text).encode("utf-8")


def _own_streams() -> list[tuple[str, FapStream, EncodeOptions | None]]:
    """Small streams covering what the real vectors do not: fap_quant != 1, skips, time codes, body, FAP 2."""
    rng = np.random.default_rng(12)
    short = demo_stream(seconds=0.6)
    body = demo_stream(seconds=0.3)
    body.object_mask[:] = 3
    body.bap_mask[:, :20] = True
    body.bap_values[:, :20] = rng.integers(-300, 300, size=(len(body), 20))
    sparse = demo_stream(seconds=0.8)
    sparse.fap_mask[::2, 2:] = False
    return [
        ("own/demo-default", short, None),
        ("own/demo-q2-intra4-startcodes", short, EncodeOptions(fap_quant=2, intra_period=4, start_codes=True)),
        ("own/demo-q31-timecodes", demo_stream(seconds=2.2), EncodeOptions(fap_quant=31, time_codes=True,
                                                                             intra_period=25)),
        ("own/demo-skips", short, EncodeOptions(skip_repeats=True, fps=12.5, optimize=True)),
        ("own/face+body", body, EncodeOptions(bap_quant=3)),
        ("own/sparse-interpolate", sparse, EncodeOptions(mask_types=(2,) * 10)),
    ]


def _own_fdps() -> list[tuple[str, Fdp]]:
    rng = np.random.default_rng(7)
    labels = LABELS[::3]
    points = {label: rng.normal(0, 50, 3) for label in labels}
    uv = {label: rng.random(2) for label in labels}
    mesh = FdpMesh(rng.normal(0, 50, (6, 3)), np.array([[0, 1, 2], [2, 3, 4], [3, 4, 5]]), rng.random((6, 2)),
                   name="skin")
    table = FaceDefTable(3, 1, (FaceDefMesh(np.array([0, 2]), np.array([-100, 0, 200]), rng.normal(0, 1, (2, 2, 3))),),
                         (FaceDefTransform("rotation"),))
    viseme_table = FaceDefTable(1, 4, (), (FaceDefTransform("scale"),))
    texture = TextureImage("front.png", "image/png", b"\x89PNG\r\n\x1a\n" + bytes(range(40)))
    fapu = {"IRISD0": 16.0, "ES0": 69.5, "ENS0": 51.0, "MNS0": 30.0, "MW0": 50.0}
    return [
        ("own/points", Fdp.from_points(points, name="points")),
        ("own/full", Fdp.from_points(points, uv, textures=(texture,), mesh=mesh, tables=(table, viseme_table),
                                     fapu=fapu, name="full")),
        ("own/empty", Fdp.from_points({})),
    ]


def _own_xface() -> bytes:
    """An Xface ``.fdp`` in the layout of Xface's files, written here."""
    rng = random.Random(3)
    lines = ['<?xml version="1.0" encoding="UTF-8" standalone="no" ?>', "<xfdp>", "  <head>",
             '    <file version="0.2"/>', '    <fapu ENS0="51.2" ES0="69" IRISD0="16" MNS0="30" MW0="50"/>',
             '    <translation x="0" y="-1.5" z="-600"/>',
             '    <rotation axis_angle="0.3" axis_x="-1" axis_y="0" axis_z="0"/>', "  </head>", "  <source>",
             '    <entity alias="Rest" category="Expression">', '      <mesh file="face.wrl" format="wrl"/>',
             "    </entity>", "  </source>"]
    for k, label in enumerate(LABELS[:12]):
        submesh = "face.wrl_0" if k % 4 else "face.wrl_1"
        lines.append(f'  <fdp affects="{submesh}" index="{k}" name="{label}">')
        lines.append("    <indices>" + " ".join(str(rng.randrange(20)) for _ in range(k % 5)) + " </indices>")
        for _ in range(k % 3):
            lines.append(f'    <influence fap="{rng.randrange(68)}" type="RaisedCosInfluenceSph" '
                         f'weight="{rng.uniform(-1, 1):.3f}"/>')
        lines.append("  </fdp>")
    lines.append("</xfdp>")
    return ("\n".join(lines) + "\n").encode("utf-8")


MARKUP_SEEDS = (
    "(joy, 40, 0.5) Hello there",
    "(surprise,63,1)你好",
    "(sadness, 30, 1) Goodbye. (anger, 0, 0.25) Fine!",
    "Hello (see below) \\(not a tag\\) (3, 4) world",
    "(joy, 9, 1)word(fear,10,.5)word\r\n(disgust, 63, 2.) end",
    "  (JOY , +12 , 0.75 )\n\tline two\n(joy,0,0)",
)


def collect_seeds(vectors: Path | None) -> dict[str, list[Seed]]:
    """Seeds per target: the real files when ``vectors`` is a folder, plus those made here."""
    seeds: dict[str, list[Seed]] = {t: [] for t in TARGETS}
    if vectors is not None and vectors.is_dir():
        for path in sorted(vectors.rglob("*")):
            if not path.is_file():
                continue
            rel, suffix, data = path.relative_to(vectors).as_posix(), path.suffix.lower(), b""
            if suffix in (".fba", ".fap", ".fdp", ".json", ".xml"):
                data = path.read_bytes()
            if suffix == ".fba":
                seeds["fba"].append(Seed(rel, data))
            elif suffix == ".fap":
                seeds["fap"].append(Seed(rel, data))
            elif data:
                kind = {"binary": "fdp-binary", "json": "fdp-json", "xface": "fdp-xface"}.get(sniff_fdp(data) or "")
                if kind:
                    seeds[kind].append(Seed(rel, data))
    for name, stream, options in _own_streams():
        data = encode(stream, options)
        seeds["fba"].append(Seed(name, data))
        with warnings.catch_warnings():  # write_fap says it drops the BAPs of the face+body seed
            warnings.simplefilter("ignore")
            fap = _fap_bytes(decode(data), crlf=name.endswith("default"))
        seeds["fap"].append(Seed(name + ".fap", fap))
    for name, fdp in _own_fdps():
        seeds["fdp-binary"].append(Seed(name + ".fdp", fdp_to_bytes(fdp)))
        seeds["fdp-binary"].append(Seed(name + "-f32.fdp", fdp_to_bytes(fdp, float32=True)))
        seeds["fdp-json"].append(Seed(name + ".json", fdp_to_json(fdp).encode("utf-8")))
    seeds["fdp-xface"].append(Seed("own/xface.fdp", _own_xface()))
    seeds["markup"] += [Seed(f"own/markup-{k}", s.encode("utf-8")) for k, s in enumerate(MARKUP_SEEDS)]
    for target, made in fuzz_seeds.all_seeds().items():  # the new readers: seeds made here only
        seeds[target] += [Seed(name, data) for name, data in made]
    seeds["text"] = [Seed("generated (tools/fuzz_text.py)", b"")]
    seeds["stdin"] = [Seed("generated (tools/fuzz_text.py) in some encoding", b"")]
    return seeds


# ---- mutations ----------------------------------------------------------------------------------------------

Mutator = Callable[[random.Random, bytes, list[bytes]], bytes]

INTERESTING_BYTES = (0x00, 0x01, 0x7F, 0x80, 0xFF, 0xFE, 0x20, 0x0A, 0x0D, 0x3C, 0x7B, 0x28, 0x29, 0x2C)
NUMBER_TOKENS = ("0", "-1", "1", "63", "64", "255", "256", "300", "-300", "8192", "-8193", "2147483647",
                 "-2147483648", "2147483648", "4294967296", "9" * 30, "-" + "9" * 30, "1" + "0" * 4300, "0" * 4301,
                 "nan", "NaN", "-nan", "inf", "-inf", "Infinity", "1e400", "-1e400", "1e-400", "1e308", "0.5",
                 "-0", "+5", "0x10", "1_000", "\u0663", "\uff11", "", "  ", ",", "1.5e", ".", "-", "1e9999999999")
_NUMBER = re.compile(rb"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?")
START_CODES = (b"\x00\x00\x01\xba", b"\x00\x00\x01\xb1", b"\x00\x00\x01\xbb", b"\x00\x00\x01\x03",
               b"\x00\x00\x01\x00", b"\x00\x00\x01\xb0", b"\x7f\x00\x00\x01\xbb")


def _pos(rng: random.Random, data: bytes, end: bool = False) -> int:
    return rng.randint(0, len(data)) if end or not data else rng.randrange(len(data))


def m_bitflip(rng, data, seeds):
    if not data:
        return data
    out = bytearray(data)
    for _ in range(rng.choice((1, 1, 1, 2, 4, 8))):
        i = rng.randrange(len(out) * 8)
        out[i >> 3] ^= 0x80 >> (i & 7)
    return bytes(out)


def m_byteset(rng, data, seeds):
    if not data:
        return bytes([rng.choice(INTERESTING_BYTES)])
    out = bytearray(data)
    for _ in range(rng.choice((1, 1, 2, 3))):
        out[rng.randrange(len(out))] = rng.choice(INTERESTING_BYTES) if rng.random() < 0.5 else rng.randrange(256)
    return bytes(out)


def m_insert(rng, data, seeds):
    i = _pos(rng, data, end=True)
    n = rng.choice((1, 1, 2, 4, 16, 256))
    chunk = bytes(rng.randrange(256) for _ in range(n)) if rng.random() < 0.7 else bytes([rng.randrange(256)]) * n
    return data[:i] + chunk + data[i:]


def m_delete(rng, data, seeds):
    if not data:
        return data
    i = _pos(rng, data)
    return data[:i] + data[i + rng.choice((1, 1, 2, 4, 16, 256)):]


def m_truncate(rng, data, seeds):
    return data[:_pos(rng, data, end=True)]


def m_duplicate(rng, data, seeds):
    if not data:
        return data
    i = _pos(rng, data)
    chunk = data[i:i + rng.choice((1, 4, 16, 64, 512, 4096))]
    times = rng.choice((1, 1, 2, 8, 64))
    j = _pos(rng, data, end=True)
    return data[:j] + chunk * times + data[j:]


def m_splice(rng, data, seeds):
    other = rng.choice(seeds)
    return data[:_pos(rng, data, end=True)] + other[_pos(rng, other, end=True):]


def m_int32(rng, data, seeds):
    """Overwrite 4 bytes with an extreme little- or big-endian integer (lengths, counts)."""
    if len(data) < 4:
        return data
    value = rng.choice((0, 1, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF, 0xFFFF, 0x10000, len(data), len(data) + 1))
    i = rng.randrange(len(data) - 3)
    return data[:i] + value.to_bytes(4, rng.choice(("little", "big"))) + data[i + 4:]


def m_start_code(rng, data, seeds):
    """Insert or overwrite an FBA start code (object, plane, end, legacy) at a random byte."""
    code, i = rng.choice(START_CODES), _pos(rng, data, end=True)
    return data[:i] + code + data[i + (len(code) if rng.random() < 0.5 else 0):]


def m_number(rng, data, seeds):
    """Replace a number token of a text format by an extreme one (huge, negative, nan, 1e400, 4301 zeros, empty)."""
    found = list(_NUMBER.finditer(data, 0, min(len(data), 1 << 16)))
    if not found:
        return data
    out = data
    for m in sorted(rng.sample(found, min(len(found), rng.choice((1, 1, 2, 5)))), key=lambda m: -m.start()):
        pick = rng.random()
        if pick < 0.5:
            token = rng.choice(NUMBER_TOKENS)
        elif pick < 0.8:  # a plausible value: the structure survives and the next layers run
            token = str(rng.randint(-70, 70))
        else:
            token = str(rng.randint(-10**6, 10**6))
        out = out[:m.start()] + token.encode("utf-8") + out[m.end():]
    return out


def _lines(data: bytes) -> list[bytes]:
    return data.splitlines(keepends=True) or [b""]


def m_lines(rng, data, seeds):
    """Duplicate, delete, swap or repeat whole lines."""
    lines = _lines(data)
    i, j = rng.randrange(len(lines)), rng.randrange(len(lines))
    op = rng.randrange(4)
    if op == 0:
        lines.insert(j, lines[i])
    elif op == 1:
        del lines[i]
    elif op == 2:
        lines[i], lines[j] = lines[j], lines[i]
    else:  # repeated, up to what a case may hold
        lines[i:i + 1] = [lines[i]] * min(rng.choice((2, 10, 1000)), MAX_INPUT // max(len(lines[i]), 1) + 1)
    return b"".join(lines)


def m_encoding(rng, data, seeds):
    """Encoding damage: invalid UTF-8, NUL bytes, BOMs, UTF-16, Latin-1, lone surrogates."""
    op = rng.randrange(8)
    i = _pos(rng, data, end=True)
    if op == 0:
        return data[:i] + rng.choice((b"\xff", b"\xc3", b"\xe4\xbd", b"\xed\xa0\x80", b"\xf8\x88\x80\x80\x80",
                                      b"\xc0\xaf")) + data[i:]
    if op == 1:
        return data[:i] + b"\x00" * rng.choice((1, 1, 4)) + data[i:]
    if op == 2:
        return rng.choice((b"\xef\xbb\xbf", b"\xff\xfe", b"\xfe\xff", b"\xef\xbb\xbf\xef\xbb\xbf")) + data
    if op == 3:
        return data[:i] + b"\xef\xbb\xbf" + data[i:]
    text = data.decode("utf-8", "replace")
    if op == 4:
        return text.encode(rng.choice(("utf-16", "utf-16-le", "utf-16-be", "utf-32")))
    if op == 5:
        return text.encode("latin-1", "replace")
    if op == 6:
        odd = rng.choice(("é", "你", "\u0301", "\u200b", "\u2028", "\U0001F600", "\u202e"))
        return data[:i] + odd.encode() + data[i:]
    return data.replace(b"\n", rng.choice((b"\r", b"\r\n", b"\x0b", b"\x85", b"\xe2\x80\xa8")))


BILLION_LAUGHS = (b'<?xml version="1.0"?>\n<!DOCTYPE xfdp [\n <!ENTITY a "aaaaaaaaaa">\n'
                  + b"".join(b' <!ENTITY %s "%s">\n' % (bytes([98 + k]), (b"&" + bytes([97 + k]) + b";") * 10)
                             for k in range(9))
                  + b"]>\n")
XML_DECLS = (b'<?xml version="1.0" encoding="x-unknown-9"?>', b'<?xml version="1.0" encoding="UTF-16"?>',
             b'<?xml version="1.0" encoding="ISO-8859-1"?>', b'<?xml version="1.0" encoding="utf-32"?>',
             b'<?xml version="1.0" encoding="ebcdic-cp-us"?>', b'<?xml version="1.1"?>', b'<?xml version="9"?>',
             b'<?xml version="1.0" encoding=""?>', b'<?xml version="1.0" encoding="' + b"A" * 300 + b'"?>')


def m_xml(rng, data, seeds):
    """XML damage: encoding declarations, entity bombs, external entities, deep nesting, tag and attribute edits."""
    op = rng.randrange(9)
    body = re.sub(rb"\A\s*<\?xml[^>]*\?>", b"", data)
    if op == 0:
        return rng.choice(XML_DECLS) + b"\n" + body
    if op == 1:
        return BILLION_LAUGHS + body.replace(b"<xfdp>", b"<xfdp>&j;", 1)
    if op == 2:
        return (b'<?xml version="1.0"?>\n<!DOCTYPE xfdp SYSTEM "file:///etc/passwd">\n'
                + body.replace(b"<xfdp>", b'<xfdp>&ext;', 1))
    if op == 3:
        depth = rng.choice((100, 10000, 200000))
        i = body.find(b"</xfdp>")
        i = i if i >= 0 else len(body)
        return body[:i] + b"<n>" * depth + b"</n>" * depth + body[i:]
    if op == 4:  # many elements
        one = re.search(rb"<fdp .*?</fdp>", body, re.S)
        if one:
            return body[:one.end()] + one.group(0) * rng.choice((2, 100, 5000)) + body[one.end():]
        return body
    if op == 5:  # drop or rename an attribute
        attrs = list(re.finditer(rb'\s(\w+)="[^"]*"', body))
        if attrs:
            m = rng.choice(attrs)
            new = rng.choice((b"", b' %s="%s"' % (m.group(1), b"x" * rng.choice((0, 1, 70000))),
                              b' other="1"', m.group(0) + m.group(0)))
            return body[:m.start()] + new + body[m.end():]
        return body
    if op == 6:  # rename a tag
        tags = list(re.finditer(rb"<(/?)(\w+)", body))
        if tags:
            m = rng.choice(tags)
            tag = rng.choice((b"xfdp", b"fdp", b"head", b"indices", b"q", b"x:y"))
            return body[:m.start(2)] + tag + body[m.end(2):]
        return body
    if op == 7:
        i = _pos(rng, body, end=True)
        return body[:i] + rng.choice((b"<![CDATA[1 2 3]]>", b"<?pi x?>", b"<!-- c -->", b"&amp;", b"&#0;",
                                      b"&#x110000;", b"&unknown;", b"]]>", b"<", b"\x00")) + body[i:]
    return b'<?xml version="1.0" encoding="UTF-16"?>\n' + body.decode("utf-8", "replace").encode("utf-16")


def m_json(rng, data, seeds):
    """JSON damage: deep nesting, huge arrays, duplicate keys, NaN/Infinity, long numbers, wrong types."""
    op = rng.randrange(8)
    i = _pos(rng, data, end=True)
    if op == 0:
        depth = rng.choice((50, 1000, 100000))
        return data[:i] + b"[" * depth + b"]" * depth + data[i:]
    if op == 1:
        n = rng.choice((1000, 100000))
        big = b"[" + b",".join([b"1.5"] * n) + b"]"
        keys = list(re.finditer(rb'"(\w+)":\s*', data))
        if keys:
            m = rng.choice(keys)
            return data[:m.end()] + big + b"," + data[m.end():]
        return big
    if op == 2:
        value = rng.choice((b"NaN", b"Infinity", b"-Infinity", b"1e400", b"9" * 5000, b"-0", b"\"\\ud800\"",
                            b"\"\\u0000\"", b"null", b"true", b"{}", b"[]", b"\"\""))
        return data[:i] + value + data[i:]
    if op == 3:  # duplicate a key/value pair
        pairs = list(re.finditer(rb'"\w+":\s*("[^"]*"|[-0-9.eE]+|null|true|false)', data))
        if pairs:
            m = rng.choice(pairs)
            return data[:m.end()] + b", " + m.group(0) + data[m.end():]
        return data
    if op == 4:  # replace a value by another type
        values = list(re.finditer(rb'(?<=: )("[^"]*"|[-0-9.eE]+|null|true|false|\[)', data))
        if values:
            m = rng.choice(values)
            new = rng.choice((b'"x"', b"null", b"true", b"{}", b"[[]]", b"-1", b"1e400", b"1.5", b"[1,2]"))
            end = m.end() if m.group(0) != b"[" else m.start()
            return data[:m.start()] + new + (b"," if m.group(0) == b"[" else b"") + data[end:]
        return data
    if op == 5:  # rename a key
        keys = list(re.finditer(rb'"(\w+)":', data))
        if keys:
            m = rng.choice(keys)
            return data[:m.start(1)] + rng.choice((b"version", b"format", b"mesh", b"x", b"", b"fap")) + data[m.end(1):]
        return data
    if op == 6:
        return data[:i] + rng.choice((b"}", b"]", b",", b":", b'"', b"\\", b"/*c*/")) + data[i:]
    return b'{"a": ' * 2 + data + b"}" * 2


_JSON_VALUES = (0, -1, 1, 63, 64, 68, 69, 2**31, -2**31 - 1, 2**64, 10**400, 1.5, -0.0, 1e308, float("nan"),
                float("inf"), "", "x", "2.1", "11.6", "image/png", None, True, False, [], {}, [[]], [0, 0, 0],
                [1e308, 1e308, 1e308], [[0, 1, 2]], {"x": 1})


def _json_nodes(node, path=()):
    yield path, node
    if isinstance(node, dict):
        for key, value in node.items():
            yield from _json_nodes(value, path + (key,))
    elif isinstance(node, list):
        for i, value in enumerate(node[:64]):
            yield from _json_nodes(value, path + (i,))


def m_json_tree(rng, data, seeds):
    """Valid JSON, wrong content: replace, delete, duplicate or grow one node of the parsed document."""
    try:
        doc = json.loads(data)
    except (ValueError, RecursionError):
        return data
    nodes = list(_json_nodes(doc))
    path, node = rng.choice(nodes)
    if not path:
        return json.dumps(rng.choice(_JSON_VALUES)).encode()
    parent = doc
    for key in path[:-1]:
        parent = parent[key]
    key, op = path[-1], rng.randrange(5)
    if op == 0:
        parent[key] = rng.choice(_JSON_VALUES)
    elif op == 1:
        del parent[key]
    elif op == 2 and isinstance(parent, list):
        parent.insert(key, node)
    elif op == 3 and isinstance(node, list) and node:
        parent[key] = node * rng.choice((2, 3, 50))
    elif op == 4 and isinstance(node, (int, float)) and not isinstance(node, bool) and abs(node) < 1e300:
        parent[key] = rng.choice((node + 1, node - 1, -node, node * 1000, int(node)))
    else:
        parent[key] = {"x": node} if rng.random() < 0.5 else [node]
    try:
        return json.dumps(doc).encode("utf-8")
    except (ValueError, OverflowError):
        return data


def m_fdp_chunk(rng, data, seeds):
    """Damage a binary FDP chunk's payload or length, then fix its CRC so the reader looks inside."""
    chunks, pos = [], 10
    while pos + 12 <= len(data):
        length = int.from_bytes(data[pos:pos + 4], "little")
        if pos + 12 + length > len(data):
            break
        chunks.append((pos, length))
        pos += 12 + length
    if not chunks:
        return data
    start, length = rng.choice(chunks)
    tag = data[start + 4:start + 8]
    payload = data[start + 8:start + 8 + length]
    op = rng.randrange(4)
    if op == 0 and payload:
        payload = rng.choice((m_bitflip, m_byteset, m_int32))(rng, payload, seeds)
    elif op == 1:
        payload = rng.choice((m_truncate, m_insert, m_delete, m_duplicate))(rng, payload, seeds)
    elif op == 2 and len(payload) >= 2:
        i = rng.randrange(len(payload) - 1)
        width = rng.choice((1, 2, 4))
        payload = payload[:i] + bytes([0xFF] * width) + payload[i + width:]
    else:
        tag = rng.choice((b"NAME", b"FPTS", b"TXCO", b"FAPU", b"MESH", b"FDTB", b"TXIM", b"IEND", b"zzzz", b"ZZZZ"))
    crc = zlib.crc32(tag + payload).to_bytes(4, "little")
    rebuilt = len(payload).to_bytes(4, "little") + tag + payload + crc
    if rng.random() < 0.3:
        rebuilt *= 2  # a chunk twice
    return data[:start] + rebuilt + data[start + 12 + length:]


# ---- mutations for the readers of issue 26 item 4 -------------------------------------------------------------

_U32 = (0, 1, 2, 3, 7, 8, 12, 255, 256, 0xFFFF, 0x10000, 0x7FFFFFFF, 0x80000000, 0xFFFFFFFF)


def _riff_chunks(data: bytes) -> list[tuple[int, bytes, int]]:
    """``(offset, tag, size)`` of each chunk of a RIFF file, as far as its sizes lead."""
    chunks, pos = [], 12
    while pos + 8 <= len(data):
        size = int.from_bytes(data[pos + 4:pos + 8], "little")
        chunks.append((pos, data[pos:pos + 4], size))
        pos += 8 + size + (size & 1)
    return chunks


def m_wav(rng, data, seeds):
    """WAV header damage: fmt fields (format tag, channels, rate, bits, block align), chunk and RIFF sizes,
    chunk order, the magic words, an unknown chunk claiming gigabytes, the extensible sub-format."""
    chunks = _riff_chunks(data)
    op = rng.randrange(8)
    fmt = next((c for c in chunks if c[1] == b"fmt "), None)
    if op == 0 and fmt is not None and fmt[2] >= 16:
        field, width = rng.choice(((0, 2), (2, 2), (4, 4), (8, 4), (12, 2), (14, 2)))
        choices = {0: (0, 1, 2, 3, 6, 7, 0x11, 0x55, 0xFFFE, 0xFFFF), 2: (0, 1, 2, 3, 8, 255, 0xFFFF),
                   4: (0, 1, 8000, 44100, 0x7FFFFFFF, 0xFFFFFFFF), 8: (0, 1, 0xFFFFFFFF),
                   12: (0, 1, 3, 0xFFFF), 14: (0, 1, 4, 7, 8, 12, 16, 20, 24, 32, 48, 64, 0xFFFF)}[field]
        at = fmt[0] + 8 + field
        return data[:at] + rng.choice(choices).to_bytes(width, "little") + data[at + width:]
    if op == 1 and chunks:
        at = rng.choice(chunks)[0] + 4
        value = rng.choice(_U32 + (len(data), len(data) + 1))
        return data[:at] + value.to_bytes(4, "little") + data[at + 4:]
    if op == 2 and len(data) >= 8:
        return data[:4] + rng.choice(_U32 + (len(data) - 8, len(data))).to_bytes(4, "little") + data[8:]
    if op == 3 and len(chunks) >= 2:  # swap, drop or duplicate whole chunks
        parts = [data[o:o + 8 + n + (n & 1)] for o, _, n in chunks]
        kind = rng.randrange(3)
        if kind == 0:
            parts.reverse()
        elif kind == 1:
            del parts[rng.randrange(len(parts))]
        else:
            parts.insert(0, rng.choice(parts))
        return data[:12] + b"".join(parts)
    if op == 4:
        tag = rng.choice((b"junk", b"LIST", b"fact", b"cue ", b"data", b"fmt ", b"\x00\x00\x00\x00"))
        size = rng.choice((0, 3, 0x7FFFFFF0, 0xFFFFFFFF))
        return data[:12] + tag + size.to_bytes(4, "little") + b"x" * rng.choice((0, 3, 16)) + data[12:]
    if op == 5:
        return data[:rng.choice((0, 4, 11, 12, 20, 36, 43, 44, 46))]
    if op == 6:
        magic = rng.choice(((0, b"RIFX"), (0, b"RF64"), (0, b"riff"), (8, b"AVI "), (8, b"WAVf"), (0, b"\x00" * 4)))
        return data[:magic[0]] + magic[1] + data[magic[0] + 4:]
    if fmt is not None and fmt[2] >= 18:  # the extension: cbSize, valid bits, channel mask, sub-format GUID
        at = fmt[0] + 8 + rng.choice((16, 18, 20, 24))
        return data[:at] + rng.choice((b"\xff\xff", b"\x00\x00", b"\x03\x00", b"\x55\x00")) + data[at + 2:]
    return m_int32(rng, data, seeds)


_PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def _png_chunks(data: bytes) -> list[tuple[int, bytes, int]]:
    chunks, pos = [], 8
    while pos + 12 <= len(data):
        size = int.from_bytes(data[pos:pos + 4], "big")
        chunks.append((pos, data[pos + 4:pos + 8], size))
        if size > len(data):
            break
        pos += 12 + size
    return chunks


def _png_chunk(tag: bytes, payload: bytes) -> bytes:
    return len(payload).to_bytes(4, "big") + tag + payload + zlib.crc32(tag + payload).to_bytes(4, "big")


@functools.lru_cache(maxsize=None)
def _zeros_deflated(n: int) -> bytes:
    return zlib.compress(b"\x00" * n, 9)


def m_image(rng, data, seeds):
    """Image damage that gets past the checksums: PNG chunks rebuilt with their CRC (IHDR sizes up to a
    decompression bomb, bit depths, colour types, a zlib bomb in IDAT, zTXt, iCCP), JPEG frame sizes and
    segment lengths; other formats get byte damage."""
    if data.startswith(_PNG_MAGIC):
        chunks = _png_chunks(data)
        op = rng.randrange(6)
        ihdr = next((c for c in chunks if c[1] == b"IHDR" and c[2] == 13), None)
        if op <= 1 and ihdr is not None:
            payload = bytearray(data[ihdr[0] + 8:ihdr[0] + 21])
            if op == 0:
                w, h = rng.choice(((0, 12), (16, 0), (65535, 65535), (30000, 30000), (10000, 9000), (1, 2**31 - 1),
                                   (2**31 - 1, 2**31 - 1), (100000, 1), (16, 13), (17, 12)))
                payload[0:8] = w.to_bytes(4, "big") + h.to_bytes(4, "big")
            else:
                at = rng.choice((8, 9, 10, 11, 12))
                payload[at] = rng.choice((0, 1, 2, 3, 4, 5, 6, 7, 8, 16, 33, 255))
            return data[:ihdr[0]] + _png_chunk(b"IHDR", bytes(payload)) + data[ihdr[0] + 25:]
        if op == 2:  # an IDAT (or a text chunk) that inflates to far more than the image holds
            bomb = _zeros_deflated(rng.choice((1 << 20, 64 << 20)))
            tag = rng.choice((b"IDAT", b"zTXt", b"iCCP", b"iTXt"))
            payload = (b"k\x00\x00" + bomb) if tag != b"IDAT" else bomb
            at = next((c[0] for c in chunks if c[1] == b"IDAT"), 33)
            return data[:at] + _png_chunk(tag, payload) + data[at:]
        if op == 3 and chunks:  # damage a payload, fix the CRC
            pos, tag, size = rng.choice(chunks)
            payload = data[pos + 8:pos + 8 + size]
            payload = rng.choice((m_bitflip, m_byteset, m_truncate, m_insert))(rng, payload, seeds)
            return data[:pos] + _png_chunk(tag, payload) + data[pos + 12 + size:]
        if op == 4 and chunks:  # drop or repeat a chunk
            pos, tag, size = rng.choice(chunks)
            one = data[pos:pos + 12 + size]
            return data[:pos] + (one * rng.choice((0, 2, 500))) + data[pos + 12 + size:]
        return data[:8] + _png_chunk(rng.choice((b"acTL", b"fcTL", b"PLTE", b"tRNS", b"sBIT", b"eXIf")),
                                     bytes(rng.randrange(256) for _ in range(rng.choice((0, 1, 8, 26))))) + data[8:]
    if data.startswith(b"\xff\xd8"):
        sof = [m.start() for m in re.finditer(rb"\xff[\xc0-\xc3\xc5-\xc7\xc9-\xcb\xcd-\xcf]", data)]
        op = rng.randrange(4)
        if op == 0 and sof:
            at = rng.choice(sof) + 5
            size = rng.choice((0, 1, 65535, 65500, 12, 16))
            return data[:at] + size.to_bytes(2, "big") + data[at + 2:]
        if op == 1 and sof:  # component count, precision
            at = rng.choice(sof) + rng.choice((4, 9))
            return data[:at] + bytes([rng.choice((0, 1, 2, 3, 4, 5, 12, 16, 255))]) + data[at + 1:]
        if op == 2:  # a segment length
            marks = [m.start() for m in re.finditer(rb"\xff[\xc0-\xfe]", data[:4096])]
            if marks:
                at = rng.choice(marks) + 2
                return data[:at] + rng.choice((0, 1, 2, 0xFFFF)).to_bytes(2, "big") + data[at + 2:]
        exif = b"Exif\x00\x00MM\x00*\x00\x00\x00\x08\x00\x01\x01\x12\x00\x03\x00\x00\x00\x01" + \
            bytes([0, rng.choice((0, 1, 6, 8, 9, 255)), 0, 0])
        return data[:2] + b"\xff\xe1" + (len(exif) + 2).to_bytes(2, "big") + exif + data[2:]
    return rng.choice(BINARY)(rng, data, seeds)


_GLTF_VALUES = (0, 1, -1, 3, 5120, 5121, 5123, 5125, 5126, 9999, 2**31, 2**32 + 3, 10**12, 1e308, "VEC3", "MAT4",
                "SCALAR", "", None, [], {}, [0], [0, 0], "data:,", "data:application/octet-stream;base64,!!!",
                "data:application/octet-stream;base64,AAAA", "../../../../etc/passwd", "buf.bin", "http://x/y.bin")
_GLTF_PLACES = (("accessors", "count"), ("accessors", "byteOffset"), ("accessors", "componentType"),
                ("accessors", "type"), ("accessors", "bufferView"), ("bufferViews", "byteOffset"),
                ("bufferViews", "byteLength"), ("bufferViews", "byteStride"), ("bufferViews", "buffer"),
                ("buffers", "byteLength"), ("buffers", "uri"), ("nodes", "mesh"), ("nodes", "children"),
                ("nodes", "matrix"), ("nodes", "scale"), ("meshes", "primitives"), ("scenes", "nodes"))


def m_gltf(rng, data, seeds):
    """glTF content damage on the parsed document: accessor counts and offsets, component types, buffer sizes
    and URIs, node cycles (a node its own child), transforms of 1e308, required extensions."""
    try:
        doc = json.loads(data)
    except (ValueError, RecursionError):
        return data
    if not isinstance(doc, dict):
        return data
    op = rng.randrange(4)
    if op == 0:
        key, field = rng.choice(_GLTF_PLACES)
        items = doc.get(key)
        entries = [item for item in items if isinstance(item, dict)] if isinstance(items, list) else []
        if entries:
            rng.choice(entries)[field] = rng.choice(_GLTF_VALUES)
    elif op == 1 and isinstance(doc.get("nodes"), list) and doc["nodes"]:  # cycles and deep chains
        nodes = doc["nodes"]
        depth = rng.choice((1, 2, 1000))
        for k in range(len(nodes)):
            if isinstance(nodes[k], dict):
                nodes[k]["children"] = [rng.randrange(len(nodes) + depth)]
        nodes += [{"children": [len(nodes) + k + 1]} for k in range(depth)]
    elif op == 2:
        doc["extensionsRequired"] = [rng.choice(("KHR_draco_mesh_compression", "EXT_meshopt_compression", "X"))]
        doc["extensionsUsed"] = doc["extensionsRequired"]
    else:
        meshes = doc.get("meshes") if isinstance(doc.get("meshes"), list) else []
        prims = [p for m in meshes if isinstance(m, dict) and isinstance(m.get("primitives"), list)
                 for p in m["primitives"] if isinstance(p, dict)]
        if prims:
            prim = rng.choice(prims)
            prim[rng.choice(("mode", "indices", "attributes", "targets"))] = rng.choice(
                (0, 1, 3, 6, 7, -1, 99, None, {"POSITION": 5}, [{"POSITION": 0}], {}))
    try:
        return json.dumps(doc).encode("utf-8")
    except (ValueError, OverflowError, RecursionError):
        return data


def m_glb(rng, data, seeds):
    """GLB container damage: header and chunk lengths, chunk types, version, and the JSON chunk rewritten by
    the glTF mutators with the lengths fixed (so the reader gets to the content)."""
    if len(data) < 20 or not data.startswith(b"glTF"):
        return m_int32(rng, data, seeds)
    json_len = int.from_bytes(data[12:16], "little")
    op = rng.randrange(5)
    if op == 0:
        at = rng.choice((4, 8, 12, 20 + json_len))
        return data[:at] + rng.choice(_U32 + (len(data), json_len + 1)).to_bytes(4, "little") + data[at + 4:]
    if op == 1:
        at = rng.choice((16, 24 + json_len))
        return data[:at] + rng.choice((b"BIN\x00", b"JSON", b"\x00\x00\x00\x00", b"XXXX")) + data[at + 4:]
    text, rest = data[20:20 + json_len], data[20 + json_len:]
    text = rng.choice((m_gltf, m_gltf, m_json, m_json_tree))(rng, text, seeds)
    text += b" " * (-len(text) % 4)
    body = len(text).to_bytes(4, "little") + b"JSON" + text + rest
    return b"glTF" + data[4:8] + (12 + len(body)).to_bytes(4, "little") + body


_OBJ_TOKENS = ("0", "-1", "-99999", "99999", "2147483648", "-2147483649", "1" + "0" * 30, "1/2/3/4", "//", "/",
               "1//", "a", "nan", "inf", "-inf", "1e308", "-1e308", "1e400", "", "1.5", "0x10", "#", "\\")
_OBJ_LINES = ("f 1 2", "f 1 1 1", "f", "v", "v 1", "v 1 2 3 4 5 6 7", "vt 1", "vn", "l 1 2 3", "p 1",
              "s off", "g", "o", "g " + "x" * 5000, "usemtl", "mtllib ../../../../etc/passwd", "mtllib /dev/zero",
              "curv 0 1 1 2", "vp 0.5", "cstype bspline", "f " + " ".join(str(k) for k in range(1, 2000)),
              "v nan nan nan", "v 1e308 1e308 1e308", "v -1e308 0 1e308", "f -1 -2 -3", "f 1/1/1 2/2 3//3",
              "\\", "f 1 2 \\\n 3", "v 0 0 0 \\")


def m_obj(rng, data, seeds):
    """OBJ damage: a face or vertex token replaced (0, out of range, huge, nan, malformed), odd statements
    added (polygons of 2000 corners, mtllib naming system files, lines, points, curves, line continuations)."""
    lines = _lines(data)
    if rng.random() < 0.5:
        picks = [k for k, line in enumerate(lines[:20000]) if line[:2] in (b"f ", b"v ", b"vt", b"vn")]
        if picks:
            k = rng.choice(picks)
            words = lines[k].rstrip(b"\r\n").split(b" ")
            if len(words) > 1:
                words[rng.randrange(1, len(words))] = rng.choice(_OBJ_TOKENS).encode()
                lines[k] = b" ".join(words) + b"\n"
            return b"".join(lines)
    extra = rng.choice(_OBJ_LINES).encode() + b"\n"
    lines.insert(rng.randint(0, len(lines)), extra * rng.choice((1, 1, 2, 1000)))
    return b"".join(lines)


def m_frame_values(rng, data, seeds):
    """A .fap/.bap value on a frame line (not a mask entry, not the header) set to an extreme or plausible number:
    mask lines hold most of the numbers, so number damage alone seldom reaches the values."""
    lines = _lines(data)
    heads = [k for k, line in enumerate(lines) if line.strip() and not line.lstrip().startswith(b"#")]
    frames = [k for k in heads[1:] if len(lines[k].split()) > 1 and not set(lines[k].split()) <= {b"0", b"1"}]
    if not frames:
        return data
    k = rng.choice(frames)
    words = lines[k].split()
    at = rng.randrange(len(words))
    words[at] = (rng.choice(NUMBER_TOKENS) if rng.random() < 0.4 else str(rng.randint(-40000, 40000))).encode()
    lines[k] = b" ".join(words) + b"\n"
    return b"".join(lines)


_EVENT_TIMES = (0, -1, 1, 21_600_000, 21_600_001, 216_000_000_000, 216_000_000_001, 10**15, 2**63, 10**30, 1.5,
                1e308, -1e308, "5", None, True, [], 3_600_000, 36_000_000_000)
_EVENT_VISEMES = (-1, 0, 9, 10, 11, 21, 22, 100, 2**40, 1.5, "p", "sil", "", "21", None, True, [], "\u0000", "x" * 100)


def m_events(rng, data, seeds):
    """Viseme-event damage: a time far away (6 h and over, in ticks or ms), negative, a string; a viseme ID
    out of range or of the wrong type; events out of order; tens of thousands of events."""
    try:
        doc = json.loads(data)
        lines = None
    except (ValueError, RecursionError):
        try:
            lines, doc = data.decode("utf-8").splitlines(), None
            doc = [json.loads(line) for line in lines if line.strip()]
        except (ValueError, RecursionError, UnicodeDecodeError):
            return data
    events = doc if isinstance(doc, list) else next((v for v in doc.values() if isinstance(v, list)), None) \
        if isinstance(doc, dict) else None
    if not events or not all(isinstance(e, dict) for e in events):
        return data
    op = rng.randrange(4)
    event = rng.choice(events)
    time_keys = [k for k in event if "ffset" in k or k == "time"]
    id_keys = [k for k in event if "iseme" in k or k == "value"]
    if op == 0 and time_keys:
        event[rng.choice(time_keys)] = rng.choice(_EVENT_TIMES)
    elif op == 1 and id_keys:
        event[rng.choice(id_keys)] = rng.choice(_EVENT_VISEMES)
    elif op == 2:
        rng.shuffle(events)
    else:
        n = rng.choice((1000, 20000, 40000))
        events.extend(dict(events[k % len(events)]) for k in range(n))
        for k, e in enumerate(events):
            for key in time_keys:
                if key in e:
                    e[key] = k * (10_000 if "ffset" in key else 1)
    try:
        if lines is not None:
            return "\n".join(json.dumps(e) for e in doc).encode("utf-8")
        return json.dumps(doc).encode("utf-8")
    except (ValueError, OverflowError, RecursionError):
        return data


_CSV_CELLS = ("", '"', '""', '"a,b"', '"x\ny"', "a.fba", "../a.fba", "/dev/zero", "/dev/null", ".", "/", "~",
              "a.fba\x00", "nonexistent.fba", "x" * 5000, "320x240", "0x0", "100000x100000", "-2x2", "3", "17",
              "1e308", "nan", "front", "sideways", "true", "maybe", "one.mp4", "../escape.mp4", "/tmp/abs.mp4",
              "one.mp4", "ONE.MP4", "out.avi")


def m_csv(rng, data, seeds):
    """Manifest cell damage: a cell replaced by a quote, a path (system files, folders, ``..``), a size or
    option value out of range, a duplicated output name; a column added or dropped."""
    lines = _lines(data)
    k = rng.randrange(len(lines))
    cells = lines[k].rstrip(b"\r\n").split(b",")
    op = rng.randrange(3)
    if op == 0:
        cells[rng.randrange(len(cells))] = rng.choice(_CSV_CELLS).encode()
    elif op == 1:
        cells.insert(rng.randint(0, len(cells)), rng.choice(_CSV_CELLS).encode())
    elif len(cells) > 1:
        del cells[rng.randrange(len(cells))]
    lines[k] = b",".join(cells) + b"\n"
    return b"".join(lines)


_MANIFEST_VALUES = ("/dev/zero", "/dev/null", ".", "/", "../a.fba", "a.fba", "s.wav", "m.obj", "nonexistent.fba",
                    "one.mp4", "../x.mp4", "x" * 5000, [320, 240], [0, 0], [10**9, 10**9], [1.5, 2], 3, 17, -1,
                    1e308, "nan", True, None, {}, [])
_MANIFEST_KEYS = ("stream", "audio", "fdp", "output", "size", "aa", "view", "fps", "fit", "crf", "deformer", "blocks",
                  "method", "skull", "texture", "fdp_texture", "face_mesh", "face_points", "options", "x")


def m_manifest(rng, data, seeds):
    """A job's key set to a value of the manifest's vocabulary: paths (system files, folders), sizes, odd types."""
    try:
        doc = json.loads(data)
    except (ValueError, RecursionError):
        return data
    jobs = doc.get("jobs") if isinstance(doc, dict) else doc
    if not isinstance(jobs, list) or not jobs or not isinstance(jobs[0], dict):
        return data
    job = rng.choice([j for j in jobs if isinstance(j, dict)] or [{}])
    job[rng.choice(_MANIFEST_KEYS)] = rng.choice(_MANIFEST_VALUES)
    if rng.random() < 0.1:
        jobs.extend(dict(jobs[0]) for _ in range(rng.choice((100, 5000))))
    try:
        return json.dumps(doc).encode("utf-8")
    except (ValueError, OverflowError, RecursionError):
        return data


_CODECS = ("utf-8", "utf-8", "utf-8-sig", "utf-16", "utf-16-le", "utf-16-be", "utf-32", "latin-1", "cp1252",
           "cp1251", "koi8-r", "shift_jis", "euc-jp", "gb18030", "big5", "euc-kr", "iso-8859-7", "cp437", "mac-roman")


def stdin_bytes(rng: random.Random) -> tuple[bytes, str]:
    """Bytes as a pipe brings them: a generated text in one of many encodings (some not UTF-8), pieces in
    several, raw random bytes, or UTF-8 with encoding damage."""
    text, recipe = draw_text(rng)
    op = rng.random()
    if op < 0.45:
        codec = rng.choice(_CODECS)
        return text.encode(codec, rng.choice(("replace", "ignore", "surrogatepass" if "utf" in codec else "replace"))
                           ), f"{recipe} in {codec}"
    if op < 0.6:
        pieces = [draw_text(rng)[0][:2000].encode(rng.choice(_CODECS), "replace") for _ in range(rng.choice((2, 3)))]
        return b"".join(pieces), f"{recipe}: pieces in several encodings"
    if op < 0.7:
        return bytes(rng.randrange(256) for _ in range(rng.choice((1, 16, 300, 4000)))), "random bytes"
    data = text_bytes(text)
    for _ in range(rng.choice((1, 2, 3))):
        data = rng.choice((m_encoding, m_encoding, m_bitflip, m_truncate, m_insert))(rng, data, [])
    return data[:MAX_INPUT], f"{recipe} in UTF-8 + encoding damage"


BINARY = (m_bitflip, m_byteset, m_insert, m_delete, m_truncate, m_duplicate, m_splice, m_int32)
TEXT = (m_number, m_number, m_number, m_lines, m_lines, m_encoding, m_bitflip, m_byteset, m_insert, m_delete,
        m_truncate, m_duplicate, m_splice)
MUTATORS: dict[str, tuple[Mutator, ...]] = {
    "fba": BINARY + (m_start_code, m_start_code, m_bitflip, m_truncate),
    "fap": TEXT,
    "fdp-binary": BINARY + (m_fdp_chunk,) * 6,
    "fdp-json": TEXT + (m_json,) * 6 + (m_json_tree,) * 8,
    "fdp-xface": TEXT + (m_xml,) * 6,
    "markup": TEXT + (m_encoding,),
    "visemes": TEXT + (m_json,) * 4 + (m_json_tree,) * 6 + (m_events,) * 8,
    "points": TEXT + (m_json,) * 6 + (m_json_tree,) * 8,
    "manifest": TEXT + (m_json,) * 4 + (m_json_tree,) * 6 + (m_manifest,) * 6 + (m_csv,) * 4,
    "conform": TEXT + (m_json,) * 6 + (m_json_tree,) * 8,
    "bap": TEXT + (m_frame_values,) * 8,
    "wav": BINARY + (m_wav,) * 10,
    "image": BINARY + (m_image,) * 10,
    "obj": TEXT + (m_obj,) * 8 + (m_json, m_json_tree),
    "gltf": TEXT + (m_json,) * 3 + (m_json_tree,) * 4 + (m_gltf,) * 6 + (m_glb,) * 6,
}
def _text_case(text: str, recipe: str) -> tuple[bytes, str]:
    """A generated text as a case's bytes, cut (at a character) to what a case may hold."""
    data = text_bytes(text)
    return (data if len(data) <= MAX_INPUT else text_bytes(text[:MAX_INPUT // 4])), recipe


GENERATED: dict[str, Callable[[random.Random], tuple[bytes, str]]] = {
    "text": lambda rng: _text_case(*draw_text(rng)),
    "stdin": stdin_bytes,
}
"""Targets whose cases are drawn, not mutated from seeds: what a user types or pipes is not damaged files."""


def mutate(rng: random.Random, target: str, seed: bytes, pool: list[bytes]) -> tuple[bytes, list[str]]:
    """1-4 mutations of ``seed`` (mostly 1); returns the bytes and the mutations' names."""
    data, names = seed, []
    for _ in range(rng.choice((1, 1, 1, 2, 2, 3, 4))):
        mutator = rng.choice(MUTATORS[target])
        try:
            data = mutator(rng, data, pool)[:MAX_INPUT]
            names.append(mutator.__name__[2:])
        except (ArithmeticError, ValueError, RecursionError, MemoryError, LookupError, TypeError):
            # cannot apply to this input (a document of another shape than the mutator knows): leave it as it is
            names.append(mutator.__name__[2:] + " (not applicable)")
    return data, names


def _pick_seed(rng: random.Random, seeds: list[Seed]) -> Seed:
    """Small seeds more often: a case of a 64 KB stream costs a hundred of a 300-byte one."""
    weights = [1.0 / math.sqrt(max(len(s.data), 64)) for s in seeds]
    return rng.choices(seeds, weights)[0]


def draw(rng: random.Random, target: str, seeds: list[Seed]) -> tuple[bytes, str]:
    """One case's input and where it came from (the seed and the mutations, for the reproducer's notes)."""
    if target in GENERATED:
        return GENERATED[target](rng)
    seed = _pick_seed(rng, seeds)
    base = seed.data
    if len(base) > 16384 and rng.random() < 0.7:  # most cases of a long stream look at its start
        base = base[:rng.randint(1024, 16384)]
    data, names = mutate(rng, target, base, [s.data for s in seeds])
    return data, f"{seed.name} + {', '.join(names)}"
