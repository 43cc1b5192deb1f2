"""Seeds for the readers issue 26 item 4 lists, all made here: WAV, .bap, viseme events, points, manifests,
a decoder's answers, OBJ and glTF/GLB meshes, images, text on standard input.

Why made and not copied: a case must be reproducible from (target, seed, index) on any checkout, so the
seeds come from the library's own writers (``write_pcm16``, ``write_bap``, the conformance adapter) or
from small writers here (WAV headers of every sample format, glTF/GLB, OBJ variants, PIL images), never
from files outside the repository. Each is small (a few kB) so a case costs milliseconds.
"""
from __future__ import annotations

import base64
import csv
import io
import json
import math
import random
import struct
import warnings
from pathlib import Path

import numpy as np

from mpeg4fa.fba import FapStream, decode, demo_stream, encode
from mpeg4fa.fdp import Fdp, fdp_to_bytes

FIXTURE_FILES = ("a.fba", "b.fap", "s.wav", "f.fdp", "t.png", "m.obj", "p.json")
"""Files a manifest seed names, written beside each manifest case (:func:`write_fixtures`)."""


# ---- audio ------------------------------------------------------------------------------------------------


def _tone(n: int, rate: int, channels: int = 1, seed: int = 0) -> np.ndarray:
    """A short voiced-sounding signal in [-1, 1]: two harmonics with a gliding pitch, and some noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / rate
    f0 = 140 + 40 * np.sin(2 * np.pi * 2 * t)
    phase = 2 * np.pi * np.cumsum(f0) / rate
    x = 0.5 * np.sin(phase) + 0.2 * np.sin(3 * phase) + 0.02 * rng.standard_normal(n)
    x *= np.minimum(1, np.minimum(t, t[-1] - t) * 20)
    return np.repeat(x[:, None], channels, axis=1) if channels > 1 else x


def wav_bytes(samples: np.ndarray, rate: int, bits: int, *, float_format: bool = False, extensible: bool = False,
              extra: bytes = b"") -> bytes:
    """A RIFF/WAVE file written here: integer PCM (8/16/24/32 bit), IEEE float (32/64) or WAVE_FORMAT_EXTENSIBLE,
    with ``extra`` chunks before the data (a LIST, an odd-sized chunk)."""
    x = np.asarray(samples, dtype=np.float64)
    channels = 1 if x.ndim == 1 else x.shape[1]
    flat = x.reshape(-1)
    if float_format:
        data = flat.astype("<f4" if bits == 32 else "<f8").tobytes()
    elif bits == 8:
        data = np.clip(np.rint(flat * 127 + 128), 0, 255).astype(np.uint8).tobytes()
    elif bits == 24:
        v = np.clip(np.rint(flat * (2**23 - 1)), -2**23, 2**23 - 1).astype("<i4")
        data = v.view(np.uint8).reshape(-1, 4)[:, :3].tobytes()
    else:
        kind = {16: "<i2", 32: "<i4"}[bits]
        top = 2 ** (bits - 1)
        data = np.clip(np.rint(flat * (top - 1)), -top, top - 1).astype(kind).tobytes()
    tag = 0xFFFE if extensible else (3 if float_format else 1)
    align = channels * bits // 8
    fmt = struct.pack("<HHIIHH", tag, channels, rate, rate * align, align, bits)
    if extensible:
        sub = (b"\x03" if float_format else b"\x01") + b"\x00\x00\x00\x00\x00\x10\x00\x80\x00\x00\xaa\x00\x38\x9b\x71"
        fmt += struct.pack("<HHI", 22, bits, (1 << channels) - 1) + sub
    body = b"WAVE" + _chunk(b"fmt ", fmt) + extra + _chunk(b"data", data)
    return b"RIFF" + struct.pack("<I", len(body)) + body


def _chunk(tag: bytes, payload: bytes) -> bytes:
    return tag + struct.pack("<I", len(payload)) + payload + (b"\x00" if len(payload) % 2 else b"")


def wav_seeds() -> list[tuple[str, bytes]]:
    rate = 8000
    mono, stereo = _tone(2400, rate), _tone(1600, 16000, 2, seed=1)
    listing = _chunk(b"LIST", b"INFOINAM" + struct.pack("<I", 5) + b"seed\x00\x00")
    return [
        ("own/pcm16-mono-8k.wav", wav_bytes(mono, rate, 16)),
        ("own/pcm16-stereo-16k.wav", wav_bytes(stereo, 16000, 16)),
        ("own/pcm8.wav", wav_bytes(mono, rate, 8)),
        ("own/pcm24.wav", wav_bytes(mono[:1200], rate, 24)),
        ("own/pcm32.wav", wav_bytes(mono[:1200], rate, 32)),
        ("own/float32.wav", wav_bytes(mono[:1200], rate, 32, float_format=True)),
        ("own/float64-stereo.wav", wav_bytes(stereo, 16000, 64, float_format=True)),
        ("own/extensible-pcm16.wav", wav_bytes(mono[:1200], rate, 16, extensible=True)),
        ("own/list-chunk-odd.wav", wav_bytes(mono[:801], 11025, 16, extra=listing + _chunk(b"odd ", b"abc"))),
        ("own/silence.wav", wav_bytes(np.zeros(800), rate, 16)),
    ]


# ---- .bap --------------------------------------------------------------------------------------------------


def bap_seeds() -> list[tuple[str, bytes]]:
    from mpeg4fa.formats.bap_text import write_bap

    rng = np.random.default_rng(5)
    out = []
    for name, n, width, version, gaps in (("own/186.bap", 6, None, "3.1", False),
                                          ("own/296-v32.bap", 4, 296, "3.2", False),
                                          ("own/gaps.bap", 8, None, "3.1", True)):
        s = FapStream.empty(n)
        s.source_fps = 15.0
        s.timestamps = np.arange(n) / 15.0
        s.object_mask[:] = 2
        cols = rng.choice(186 if width is None else 296, size=12, replace=False)
        s.bap_mask[:, cols] = True
        s.bap_values[:, cols] = rng.integers(-20000, 20000, size=(n, len(cols)))
        if gaps:
            s.object_mask[1::3] = 0
            s.bap_mask[1::3] = False
        text = io.StringIO()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            write_bap(s, text, name=name.split("/")[-1], version=version, width=width)
        out.append((name, text.getvalue().encode("utf-8")))
    out.append(("own/comments-crlf.bap", b"# a comment\r\n" + out[0][1].replace(b"\n", b" \r\n")))
    return out


# ---- viseme events (Azure, Polly) ----------------------------------------------------------------------------


def viseme_seeds() -> list[tuple[str, bytes]]:
    rng = random.Random(4)
    times = sorted(rng.uniform(0, 2.0) for _ in range(12))
    ids = [rng.randrange(22) for _ in times]
    azure = [{"AudioOffset": int(t * 1e7), "VisemeId": v} for t, v in zip(times, ids)]
    polly_v = ("sil", "p", "t", "S", "T", "f", "k", "i", "r", "s", "u", "@", "a", "e", "E", "o", "O")
    polly = [{"time": int(t * 1000), "type": "viseme", "value": rng.choice(polly_v)} for t in times]
    marks = [{"time": 0, "type": "sentence", "start": 0, "end": 11, "value": "Hello there"},
             {"time": 6, "type": "word", "start": 0, "end": 5, "value": "Hello"}] + polly
    return [
        ("own/azure.json", json.dumps(azure, indent=1).encode()),
        ("own/azure-wrapped.json", json.dumps({"visemes": azure[:6]}).encode()),
        ("own/azure-camel.json", json.dumps([{"audioOffset": e["AudioOffset"], "visemeId": e["VisemeId"],
                                              "animation": ""} for e in azure[:5]]).encode()),
        ("own/azure-js.json", json.dumps({"events": [{"privAudioOffset": e["AudioOffset"],
                                                      "privVisemeId": e["VisemeId"]} for e in azure[:4]]}).encode()),
        ("own/azure-snake.json", json.dumps([{"audio_offset": e["AudioOffset"], "viseme_id": e["VisemeId"]}
                                             for e in azure[:3]]).encode()),
        ("own/polly.jsonl", "\n".join(json.dumps(m) for m in marks).encode() + b"\n"),
        ("own/polly-array.json", json.dumps(polly[:8], indent=2).encode()),
    ]


# ---- feature points ----------------------------------------------------------------------------------------


def neutral_points() -> dict[str, tuple[float, float, float]]:
    """The neutral face's feature points (mm) from the package's data (its other rows left out)."""
    from importlib import resources

    from mpeg4fa.fdp.model import LABELS

    table = resources.files("mpeg4fa.face") / "data" / "neutral_face.csv"
    rows = csv.DictReader(io.StringIO(table.read_text(encoding="utf-8")))
    return {r["name"]: (float(r["x"]), float(r["y"]), float(r["z"])) for r in rows if r["name"] in LABELS}


def photo_points(view: str) -> dict[str, list[float]]:
    """Pixel points of the neutral face on a 512-pixel photo: ``front`` or ``left`` (the nose to the left)."""
    out = {}
    for label, (x, y, z) in neutral_points().items():
        if view == "front":
            out[label] = [round(256 + x * 0.8, 1), round(800 - y * 0.8, 1)]
        elif x >= -5:  # a left photo shows the face's left half
            out[label] = [round(300 - z * 0.8, 1), round(800 - y * 0.8, 1)]
    return out


def face_points() -> dict[str, int]:
    """Every feature point as the :func:`sphere` vertex nearest the neutral face's point (scaled to the sphere):
    a points file ``--face-mesh`` accepts, so the rigging behind it runs too."""
    vertices = sphere()[0]
    points = neutral_points()
    xyz = np.array(list(points.values()))
    xyz = (xyz - xyz.mean(axis=0)) / np.abs(xyz - xyz.mean(axis=0)).max() * 80.0
    return {label: int(np.argmin(((vertices - p) ** 2).sum(axis=1))) for label, p in zip(points, xyz)}


def points_seeds(mesh_vertices: int) -> list[tuple[str, bytes]]:
    labels = list(neutral_points())
    rng = random.Random(2)
    index = {label: rng.randrange(mesh_vertices) for label in labels[::2]}
    xyz = {label: list(p) for label, p in list(neutral_points().items())[::3]}
    return [
        ("own/face.points.json", json.dumps(face_points(), indent=1).encode()),
        ("own/front.points.json", json.dumps(photo_points("front"), indent=1).encode()),
        ("own/left.points.json", json.dumps(photo_points("left")).encode()),
        ("own/vertex.points.json", json.dumps(index, indent=2).encode()),
        ("own/xyz.points.json", json.dumps(xyz).encode()),
    ]


# ---- meshes ------------------------------------------------------------------------------------------------


def sphere(rings: int = 6, segments: int = 8, radius: float = 80.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A UV sphere: vertices (V, 3), triangles (T, 3), uvs (V, 2)."""
    verts, uvs = [], []
    for i in range(rings + 1):
        theta = math.pi * i / rings
        for j in range(segments + 1):
            phi = 2 * math.pi * j / segments
            verts.append((radius * math.sin(theta) * math.cos(phi), radius * math.cos(theta) * 1.3,
                          radius * math.sin(theta) * math.sin(phi)))
            uvs.append((j / segments, 1 - i / rings))
    tris = []
    for i in range(rings):
        for j in range(segments):
            a, b = i * (segments + 1) + j, (i + 1) * (segments + 1) + j
            tris += [(a, b, a + 1), (a + 1, b, b + 1)]
    return np.array(verts), np.array(tris), np.array(uvs)


def obj_text(vertices: np.ndarray, triangles: np.ndarray, uvs: np.ndarray | None = None, *, groups: int = 1,
             normals: bool = False, quads: bool = False, negative: bool = False) -> str:
    """An OBJ written here: ``g`` groups, ``vt``/``vn``, quads (pairs of triangles joined), relative indices."""
    lines = ["# fuzz seed", "mtllib seed.mtl", "o head"]
    lines += [f"v {x:.4f} {y:.4f} {z:.4f}" for x, y, z in vertices]
    if uvs is not None:
        lines += [f"vt {u:.4f} {v:.4f}" for u, v in uvs]
    if normals:
        lines += [f"vn {x:.3f} {y:.3f} {z:.3f}" for x, y, z in vertices / np.linalg.norm(vertices, axis=1)[:, None]]
    n = len(vertices)
    per = max(1, len(triangles) // groups)
    step = 2 if quads else 1
    for k in range(0, len(triangles), step):
        if k % per == 0 and groups > 1:
            lines.append(f"g part{k // per}")
            lines.append("usemtl skin")
        corners = list(triangles[k]) + ([int(triangles[k + 1][2])] if quads and k + 1 < len(triangles) else [])
        words = []
        for c in corners:
            i = c - n if negative else c + 1
            if uvs is not None and normals:
                words.append(f"{i}/{i}/{i}")
            elif uvs is not None:
                words.append(f"{i}/{i}")
            elif normals:
                words.append(f"{i}//{i}")
            else:
                words.append(str(i))
        lines.append("f " + " ".join(words))
    return "\n".join(lines) + "\n"


def obj_seeds() -> list[tuple[str, bytes]]:
    v, t, uv = sphere()
    small_v, small_t, _ = sphere(3, 4, 50.0)
    return [
        ("own/sphere.obj", obj_text(v, t, uv).encode()),
        ("own/sphere-groups-normals.obj", obj_text(v, t, uv, groups=3, normals=True).encode()),
        ("own/small-quads.obj", obj_text(small_v, small_t, quads=True).encode()),
        ("own/small-negative.obj", obj_text(small_v, small_t, negative=True).encode()),
        ("own/small-crlf-tabs.obj", obj_text(small_v, small_t).replace(" ", "\t").replace("\n", "\r\n").encode()),
    ]


def obj_sidecars() -> list[tuple[str, bytes]]:
    """``NAME.parts.json`` and ``NAME.points.json`` for the first OBJ seed, as the editor saves them."""
    t = sphere()[1]
    half = len(t) // 2
    parts = {"parts": {"skin": list(range(half)), "eyes": list(range(half, len(t)))}}
    return [("sidecar/parts.json", json.dumps(parts).encode()),
            ("sidecar/points.json", json.dumps(face_points()).encode())]


def gltf_document(vertices: np.ndarray, triangles: np.ndarray, *, nodes: int = 1, uri: str | None = None,
                  index_type: int = 5123) -> tuple[dict, bytes]:
    """A glTF 2.0 document and its binary buffer, written here: POSITION + indices per mesh, one node each,
    the buffer embedded as a data URI unless ``uri`` names an external file (``""``: a GLB's own chunk)."""
    pos = np.asarray(vertices, "<f4").tobytes()
    idx = np.asarray(triangles, "<u2" if index_type == 5123 else "<u4").reshape(-1).tobytes()
    idx += b"\x00" * (-len(idx) % 4)
    blob = pos + idx
    doc: dict = {
        "asset": {"version": "2.0", "generator": "mpeg4fa fuzz seed"},
        "scene": 0, "scenes": [{"nodes": list(range(nodes))}],
        "nodes": [{"mesh": 0, "name": f"Part {k}", **({"translation": [k * 10.0, 0, 0]} if k else {}),
                   **({"matrix": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 5 * k, 0, 1]} if k == 2 else {})}
                  for k in range(nodes)],
        "meshes": [{"name": "Cube.001", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 4}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": len(vertices), "type": "VEC3",
             "min": np.asarray(vertices).min(axis=0).tolist(), "max": np.asarray(vertices).max(axis=0).tolist()},
            {"bufferView": 1, "componentType": index_type, "count": int(np.size(triangles)), "type": "SCALAR"},
        ],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": len(pos), "target": 34962},
                        {"buffer": 0, "byteOffset": len(pos), "byteLength": len(idx), "target": 34963}],
        "buffers": [{"byteLength": len(blob)}],
    }
    if uri is None:
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    elif uri:
        doc["buffers"][0]["uri"] = uri
    return doc, blob


def glb_bytes(doc: dict, blob: bytes) -> bytes:
    """A GLB container: the 12-byte header, the JSON chunk (space-padded) and the BIN chunk (zero-padded)."""
    text = json.dumps(doc, separators=(",", ":")).encode()
    text += b" " * (-len(text) % 4)
    blob += b"\x00" * (-len(blob) % 4)
    body = struct.pack("<I4s", len(text), b"JSON") + text + struct.pack("<I4s", len(blob), b"BIN\x00") + blob
    return struct.pack("<4sII", b"glTF", 2, 12 + len(body)) + body


def gltf_seeds() -> list[tuple[str, bytes]]:
    v, t, _ = sphere(4, 6, 60.0)
    doc, blob = gltf_document(v, t)
    doc3, _ = gltf_document(v, t, nodes=3, index_type=5125)
    glb_doc, glb_blob = gltf_document(v, t, uri="", nodes=2)
    ext_doc, _ = gltf_document(v, t, uri="buf.bin")
    return [
        ("own/embedded.gltf", json.dumps(doc, indent=1).encode()),
        ("own/three-nodes.gltf", json.dumps(doc3).encode()),
        ("own/two-nodes.glb", glb_bytes(glb_doc, glb_blob)),
        ("own/external-buffer.gltf", json.dumps(ext_doc).encode()),
    ]


def gltf_buffer() -> bytes:
    """The ``buf.bin`` the external-buffer seed names (uploaded or written beside the case)."""
    v, t, _ = sphere(4, 6, 60.0)
    return gltf_document(v, t, uri="buf.bin")[1]


# ---- images ------------------------------------------------------------------------------------------------


def image_seeds() -> list[tuple[str, bytes]]:
    from PIL import Image

    rng = np.random.default_rng(9)
    rgb = rng.integers(0, 256, size=(12, 16, 3), dtype=np.uint8)
    base = Image.fromarray(rgb)
    out = []

    def save(name: str, img, fmt: str, **kw) -> None:
        buf = io.BytesIO()
        img.save(buf, fmt, **kw)
        out.append((name, buf.getvalue()))

    save("own/rgb.png", base, "PNG")
    save("own/rgba.png", base.convert("RGBA"), "PNG")
    save("own/gray.png", base.convert("L"), "PNG")
    save("own/palette.png", base.convert("P"), "PNG")
    save("own/gray16.png", Image.fromarray((rgb[:, :, 0].astype(np.uint16) * 257)), "PNG")
    save("own/interlaced.png", base, "PNG", optimize=False)
    save("own/baseline.jpg", base, "JPEG", quality=80)
    save("own/progressive.jpg", base, "JPEG", quality=60, progressive=True)
    save("own/cmyk.jpg", base.convert("CMYK"), "JPEG")
    save("own/image.gif", base.convert("P"), "GIF")
    save("own/image.bmp", base, "BMP")
    save("own/image.tiff", base, "TIFF")
    save("own/image.webp", base, "WEBP", quality=50)
    return out


# ---- a decoder's answer (conformance protocol) ---------------------------------------------------------------


def decoder_answer() -> tuple[dict, dict]:
    """The protocol JSON of a decoded demo stream with feature points, and the expected file it is judged by."""
    from mpeg4fa.conformance.adapter import stream_output

    stream = decode(encode(demo_stream(seconds=0.24)))
    output = stream_output(stream)
    doc = output.to_json()
    labels = list(neutral_points())[:4]
    base = np.array([neutral_points()[label] for label in labels])
    positions = base[None] + np.arange(len(output))[:, None, None] * 0.1
    doc["feature_points"] = {"labels": labels, "positions": np.round(positions, 3).tolist()}
    expected = {**json.loads(json.dumps(doc)), "frames": len(output),
                "tolerance": {"shown": 1e-6, "feature_points": 1e-3}}
    expected["feature_points"]["axes"] = [[1, 1, 0]] * len(labels)
    return doc, expected


def conform_seeds() -> list[tuple[str, bytes]]:
    doc, _ = decoder_answer()
    plain = {k: doc[k] for k in ("timestamps", "shown")}
    rows = ["t," + ",".join(f"FAP{i}" for i in range(1, 69))]
    rows += [",".join(repr(float(x)) for x in (t, *row)) for t, row in zip(doc["timestamps"], doc["shown"])]
    return [
        ("own/answer.json", json.dumps(doc).encode()),
        ("own/answer-shown-only.json", json.dumps(plain, indent=1).encode()),
        ("own/answer.csv", ("\n".join(rows) + "\n").encode()),
        ("own/stderr.txt", b"decoder: bad fap_quant at bit 1234 in frame 3\n"),
    ]


# ---- batch manifests -------------------------------------------------------------------------------------------


def manifest_seeds() -> list[tuple[str, bytes]]:
    jobs = [{"stream": "a.fba", "audio": "s.wav", "output": "one.mp4", "size": [320, 240], "aa": 4},
            {"stream": "b.fap", "fdp": "f.fdp", "view": "front", "fps": 25, "crf": 20, "texture": "t.png"},
            {"stream": "a.fba", "output": "three.mov", "options": {"size": "256x256", "deformer": "blocks"}},
            {"stream": "a.fba", "output": "mesh.mp4", "face_mesh": "m.obj", "face_points": "p.json",
             "fdp_texture": False}]
    rows = ["stream,audio,fdp,output,size,aa,view,fps", "a.fba,s.wav,,one.mp4,320x240,4,front,25",
            "b.fap,,f.fdp,two.mp4,256,,,", "a.fba,,,,,,,"]
    return [
        ("own/list.json", json.dumps(jobs, indent=2).encode()),
        ("own/defaults.json", json.dumps({"defaults": {"size": [160, 120], "aa": 0}, "jobs": jobs[:2]},
                                         indent=1).encode()),
        ("own/jobs.csv", ("\n".join(rows) + "\n").encode()),
    ]


def write_fixtures(folder: Path) -> None:
    """The small files the manifest seeds name, in ``folder`` (once: they are never mutated)."""
    if (folder / FIXTURE_FILES[-1]).exists():
        return
    from mpeg4fa.formats import write_fap

    stream = demo_stream(seconds=0.2)
    (folder / "a.fba").write_bytes(encode(stream))
    text = io.StringIO()
    write_fap(decode(encode(stream)), text, name="b.fap")
    (folder / "b.fap").write_text(text.getvalue(), encoding="utf-8")
    (folder / "s.wav").write_bytes(wav_seeds()[0][1])
    (folder / "f.fdp").write_bytes(fdp_to_bytes(Fdp.from_points(neutral_points())))
    (folder / "t.png").write_bytes(image_seeds()[0][1])
    (folder / "m.obj").write_bytes(obj_seeds()[0][1])
    (folder / "p.json").write_text(json.dumps(face_points()), encoding="utf-8")


def all_seeds() -> dict[str, list[tuple[str, bytes]]]:
    """Seeds per new target (the text targets draw generated texts instead, :mod:`fuzz_text`)."""
    obj = obj_seeds()
    return {
        "wav": wav_seeds(), "bap": bap_seeds(), "visemes": viseme_seeds(),
        "points": points_seeds(len(sphere()[0])), "manifest": manifest_seeds(), "conform": conform_seeds(),
        "obj": obj + obj_sidecars(), "gltf": gltf_seeds(), "image": image_seeds(),
    }
