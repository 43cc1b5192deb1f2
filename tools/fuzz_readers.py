"""What each fuzz case runs for the readers of issue 26 item 4 and the text path: the reader, then the next layers.

Why a file of its own: ``tools/fuzz.py`` is the harness (guards, classification, reproducers, workers);
these are the targets, each ``run_X(case)`` calling the library in-process the way the command that reads
that input does (``encode --visemes``, ``texture --points``, ``batch``, ``conform``, ``--face-mesh``, the
editor's upload, ``--speech``, ``--texture``, text on stdin). A case is only *ok* or *rejected*
(an ``MpegFaError``) when the whole way is safe: what a reader accepts goes on to the layers after it.
``case`` is :class:`fuzz.Case` (``data``, ``rng``, ``tmp``, ``stage(name, call)``, ``file(suffix)``).
"""
from __future__ import annotations

import functools
import io
import json
import sys
from pathlib import Path
from typing import Callable

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import fuzz_seeds  # noqa: E402
from fuzz_text import bytes_text  # noqa: E402

from mpeg4fa.fba import FapStream, FbaError, decode, encode  # noqa: E402
from mpeg4fa.speech.encoder import encode_text  # noqa: E402
from mpeg4fa.speech.markup import parse_markup  # noqa: E402

try:  # the one home of decoder output is moving to mpeg4fa.decoded (issue 12 item 1)
    from mpeg4fa.decoded import resolve  # type: ignore[import-not-found]
except ImportError:
    from mpeg4fa.face.frames import resolve

SPEECH_CHARS = 4000
"""Longest text also spoken by the estimate engine in a case (its work grows with the speech: volume, not damage)."""
LONG_SPEECH_CHARS = 20_000
"""A few cases speak up to this much (estimate engine): memory per character, still well under 10 s."""
ESPEAK_CHARS = 1500
"""Longest text spoken by espeak-ng in a case (~0.3 s of synthesis per 1000 characters)."""
ESPEAK_SHARE = 0.25
"""Share of the text cases (short enough) spoken by espeak-ng rather than the silent estimate engine."""
VALUE_FIELDS = ("fap_mask", "fap_values", "viseme", "expression", "bap_mask", "bap_values")


class Mismatch(Exception):
    """A round trip gave different values, or a layer refused what the layer before it made: a finding."""


# ---- shared next layers -------------------------------------------------------------------------------------


def same_values(a: FapStream, b: FapStream) -> None:
    """``b`` (decoded from ``encode(a)``) shows the same frames as ``a`` on the frame grid."""
    ga, gb = _on_grid(a), _on_grid(b)
    for name in VALUE_FIELDS:
        if ga[name].shape != gb[name].shape or not np.array_equal(ga[name], gb[name]):
            raise Mismatch(f"encode -> decode changed {name} (frames {len(a)} -> {len(b)})")


def _on_grid(s: FapStream) -> dict[str, np.ndarray]:
    idx = np.repeat(np.arange(len(s)), np.asarray(s.skip, dtype=np.int64) + 1)
    return {name: getattr(s, name)[idx] for name in VALUE_FIELDS}


def stream_layers(case, stream: FapStream, errors: tuple[type[BaseException], ...], exact: bool,
                  label: str = "") -> None:
    """resolve, then encode -> decode; ``exact``: the re-decoded values must equal (a decoded FBA stream)."""
    case.stage(label + "resolve", lambda: resolve(stream))
    if not len(stream):
        return
    try:
        data = case.stage(label + "encode", lambda: encode(stream))
    except errors as exc:
        case.notes.append(f"encode refused: {exc}")
        return
    try:
        again = case.stage(label + "redecode", lambda: decode(data))
    except FbaError as exc:
        raise Mismatch(f"decode refuses what encode wrote: {exc}") from exc
    if exact:
        same_values(stream, again)


def _made_stream(case, stream: FapStream, what: str) -> None:
    """A stream the library made itself (from text, events) must encode and decode: a refusal is a finding."""
    try:
        data = case.stage("encode", lambda: encode(stream))
        case.stage("redecode", lambda: decode(data))
    except FbaError as exc:
        raise Mismatch(f"the codec refuses what {what} made: {exc}") from exc


def _check_tags(markup) -> None:
    for tag in markup.tags:  # what the encoder relies on
        if not 0 <= tag.offset <= len(markup.text) or not 0 <= tag.intensity <= 63 or not tag.seconds >= 0:
            raise Mismatch(f"tag out of bounds: {tag}")


@functools.lru_cache(maxsize=1)
def _languages() -> tuple[str, ...]:
    """espeak-ng's language codes (the first of each voice's), for the cases that name one."""
    from mpeg4fa.speech.tts.espeak import list_voices

    return tuple(sorted({codes[0] for _, codes in list_voices() if codes}))


def speak(case, text: str, name: str, *, espeak_share: float = ESPEAK_SHARE) -> None:
    """``encode TEXT`` (``stream_text``: stream, WAV and timings written chunk by chunk) or the library's
    ``encode_text`` (what ``say`` keeps in memory), ``--lenient`` now and then; the estimate engine, or for
    a share of short texts espeak-ng in some voice; then the bits are decoded."""
    if len(text) > SPEECH_CHARS and not (len(text) <= LONG_SPEECH_CHARS and case.rng.random() < 0.05):
        return
    engine, lang = "estimate", "auto"
    if len(text) <= ESPEAK_CHARS and case.rng.random() < espeak_share:
        engine = "espeak"
        lang = case.rng.choice(_languages()) if case.rng.random() < 0.3 else "auto"
    options = {"lenient": True} if case.rng.random() < 0.2 else {}
    if case.rng.random() < 0.5:
        from mpeg4fa.speech.pipeline import stream_text

        out, audio, timings = io.BytesIO(), io.BytesIO(), io.StringIO()
        case.stage(f"stream_text({engine})", lambda: stream_text(text, out, audio=audio, timings=timings,
                                                                 engine=engine, lang=lang, name=name, **options))
        try:
            case.stage("redecode", lambda: decode(out.getvalue()))
        except FbaError as exc:
            raise Mismatch(f"the codec refuses what stream_text wrote: {exc}") from exc
        if timings.getvalue():
            case.stage("timings", lambda: json.loads(timings.getvalue()))
        return
    encoded = case.stage(f"encode_text({engine})", lambda: encode_text(text, engine=engine, lang=lang, name=name,
                                                                      **options))
    _made_stream(case, encoded.stream, "encode_text")


# ---- the text path ------------------------------------------------------------------------------------------


def run_text(case) -> None:
    """Typed text: ``parse_markup`` (any length, up to 1 MB lines), then the speech for texts of a script's size."""
    text = bytes_text(case.data)
    markup = case.stage("parse_markup", lambda: parse_markup(text, name="case.txt"))
    _check_tags(markup)
    speak(case, text, "case.txt")


def _read_stdin(data: bytes, errors: str):
    """``read_text`` of ``-`` with ``sys.stdin`` a UTF-8 pipe holding ``data`` (``errors``: the locale's handler)."""
    from mpeg4fa.cli.text_input import TextArgument, read_text

    saved = sys.stdin
    sys.stdin = io.TextIOWrapper(io.BytesIO(data), encoding="utf-8", errors=errors)
    try:
        return read_text(TextArgument("-", stdin=True))
    finally:
        sys.stdin = saved


def run_stdin(case) -> None:
    """Bytes in any encoding as ``encode -`` (stdin under a strict or a lenient UTF-8 locale) or ``encode FILE``
    (``@FILE``) read them: the bytes -> text step of ``cli/text_input.py``, then the text path."""
    from mpeg4fa.cli.text_input import classify, read_text

    pick = case.rng.random()
    if pick < 0.6:
        errors = "strict" if pick < 0.4 else "surrogateescape"
        text, name = case.stage(f"read_text(stdin, {errors})", lambda: _read_stdin(case.data, errors))
    else:
        path = case.file(".txt")
        arg = f"@{path}" if pick < 0.8 else str(path)
        text, name = case.stage("read_text(file)", lambda: read_text(classify(arg)))
    markup = case.stage("parse_markup", lambda: parse_markup(text, name=name))
    _check_tags(markup)
    speak(case, text, name, espeak_share=0.1)


# ---- files beside the text: events, points, manifests, a decoder's answer ----------------------------------------


def run_visemes(case) -> None:
    """``encode --visemes EVENTS.json [--format]``: read the events, then encode them as text is encoded."""
    from mpeg4fa.speech.viseme_events import encode_viseme_events, parse_viseme_events, read_viseme_events

    form = case.rng.choice(("auto", "auto", "auto", "azure", "polly"))
    if case.rng.random() < 0.2:
        text = case.data.decode("utf-8", "replace")
        kind, events = case.stage("parse_viseme_events", lambda: parse_viseme_events(text, "case.json", form))
    else:
        path = case.file(".json")
        kind, events = case.stage("read_viseme_events", lambda: read_viseme_events(path, form))
    encoded = case.stage("encode_viseme_events", lambda: encode_viseme_events(events, engine=kind, name="case.json"))
    _made_stream(case, encoded.stream, "encode_viseme_events")


@functools.lru_cache(maxsize=1)
def _seed_mesh():
    from mpeg4fa.fdp import mesh_from_obj

    return mesh_from_obj(fuzz_seeds.obj_seeds()[0][1], "seed.obj")


def run_points(case) -> None:
    """A points JSON as ``texture --points`` (the CLI's reader, then the photo view), ``encode --front-points``
    (``read_points_json`` -> ``fdp_from_photos``) and ``--face-points`` (-> ``fdp_from_mesh``, the rigging
    behind ``--face-mesh``) read it."""
    from mpeg4fa.fdp import fdp_from_bytes, fdp_to_bytes
    from mpeg4fa.fdp.build import fdp_from_mesh, fdp_from_photos, read_points_json

    path = case.file(".json")
    pick = case.rng.random()
    if pick < 0.25:
        from mpeg4fa.cli.texture import _points
        from mpeg4fa.render.texture import PhotoView

        points = case.stage("texture --points", lambda: _points(path))
        image = np.zeros((64, 48, 3), np.uint8)
        case.stage("PhotoView", lambda: PhotoView(image, points, case.rng.choice(("front", "left", "right"))))
        return
    points = case.stage("read_points_json", lambda: read_points_json(path))
    if pick < 0.55:
        other = fuzz_seeds.photo_points("left" if pick < 0.4 else "front")
        front, side = (points, other) if pick < 0.4 else (other, points)
        fdp = case.stage("fdp_from_photos", lambda: fdp_from_photos(front, side, side_view="left",
                                                                   front_size=(512, 512)))
    elif pick < 0.8:
        fdp = case.stage("fdp_from_mesh", lambda: fdp_from_mesh(_seed_mesh(), points))
    else:
        from mpeg4fa.face.assemble import mesh_face

        mesh = case.tmp / "face.obj"
        if not mesh.exists():
            mesh.write_bytes(fuzz_seeds.obj_seeds()[0][1])
        case.stage("mesh_face", lambda: mesh_face(mesh, path))
        return
    case.stage("fdp save-load", lambda: fdp_from_bytes(fdp_to_bytes(fdp)))


def run_manifest(case) -> None:
    """``mpeg4fa batch MANIFEST``: ``load_manifest`` of a JSON or CSV manifest naming files beside it."""
    from mpeg4fa.batch.manifest import load_manifest

    fuzz_seeds.write_fixtures(case.tmp)
    looks_json = case.data.lstrip()[:1] in (b"[", b"{")
    suffix = ".json" if looks_json != (case.rng.random() < 0.1) else ".csv"
    path = case.file(suffix)
    case.stage("load_manifest", lambda: load_manifest(path))


@functools.lru_cache(maxsize=1)
def _expected() -> dict:
    return fuzz_seeds.decoder_answer()[1]


def run_conform(case) -> None:
    """``mpeg4fa conform --decoder CMD``: the runner reads an external decoder's answer (``OUT.json`` or
    ``OUT.csv``) and its stderr (``bit N``), then judges the answer against the vector's expected file."""
    from mpeg4fa.conformance.compare import compare_decoded, compare_rejected
    from mpeg4fa.conformance.protocol import REJECTED, DecoderResult, bit_from_text, read_output

    out, csv_out = case.tmp / "out.json", case.tmp / "out.csv"
    out.unlink(missing_ok=True)
    csv_out.unlink(missing_ok=True)
    pick = case.rng.random()
    looks_json = case.data.lstrip()[:1] in (b"[", b"{")
    looks_text = not looks_json and b"," not in case.data[:200]
    if pick < (0.9 if looks_text else 0.05):  # the decoder's stderr on a rejection
        text = case.data.decode("utf-8", "replace")
        bit = case.stage("bit_from_text", lambda: bit_from_text(text))
        result = DecoderResult(REJECTED, None, bit)
        case.stage("compare_rejected", lambda: compare_rejected({"bit_offset": 1234}, result))
        return
    (out if looks_json != (pick > 0.9) else csv_out).write_bytes(case.data)
    output = case.stage("read_output", lambda: read_output(out))
    if output is not None:
        case.stage("compare_decoded", lambda: compare_decoded(_expected(), output))


def run_bap(case) -> None:
    """A ``.bap`` as ``read_bap``, ``iter_bap``, ``read_stream`` (``info``/``encode``) and a text stream read
    it; what is read goes on to resolve and encode -> decode."""
    from mpeg4fa.formats import read_stream
    from mpeg4fa.formats.bap_text import iter_bap, read_bap
    from mpeg4fa.formats.errors import FormatError
    from mpeg4fa.errors import MpegFaError

    pick = case.rng.random()
    if pick < 0.15:
        text = io.TextIOWrapper(io.BytesIO(case.data), encoding="utf-8", newline=None)
        stream = case.stage("read_bap(stream)", lambda: read_bap(text, name="case.bap"))
    elif pick < 0.25:
        path = case.file(".bap")
        case.stage("iter_bap", lambda: sum(1 for _ in iter_bap(path)))
        return
    elif pick < 0.4:
        path = case.file(".bap")
        stream, _ = case.stage("read_stream", lambda: read_stream(path))
    else:
        path = case.file(".bap")
        stream = case.stage("read_bap", lambda: read_bap(path))
    stream_layers(case, stream, (MpegFaError, FormatError, FbaError), exact=False)


# ---- media: recordings and images ------------------------------------------------------------------------------


def run_wav(case) -> None:
    """``--speech REC.wav``: ``read_recording`` (any PCM or float WAV, PyAV for the rest), then what the
    aligners do first: the speech-energy check and the resampling to 16 kHz."""
    from mpeg4fa.speech.align.recording import check_speech, read_recording, resample

    path = case.file(".wav")
    rec = case.stage("read_recording", lambda: read_recording(path))
    if rec.duration > 60:
        case.notes.append(f"{rec.duration:.0f} s recording: not aligned")
        return
    case.stage("check_speech", lambda: check_speech(rec))
    case.stage("resample", lambda: resample(rec.floats(), rec.rate, 16000))


def run_image(case) -> None:
    """``--texture`` / ``--front`` / a photo: ``read_image`` (PIL, any format), and for an FDP's texture
    ``texture_from_file`` + ``image_size`` (whose size must agree with the decoded image)."""
    from mpeg4fa.fdp.build import image_size, texture_from_file
    from mpeg4fa.render.images import read_image

    suffix = case.rng.choice((".png", ".jpg", ".img"))
    path = case.file(suffix)
    if case.rng.random() < 0.3:
        texture = case.stage("texture_from_file", lambda: texture_from_file(path))
        size = case.stage("image_size", lambda: image_size(texture.data))
        pixels = case.stage("read_image", lambda: read_image(path, "texture image"))
        if size is not None and tuple(size) != (pixels.shape[1], pixels.shape[0]):
            raise Mismatch(f"image_size says {size}, the decoded image is {pixels.shape[1]}x{pixels.shape[0]}")
        return
    case.stage("read_image", lambda: read_image(path, case.rng.choice(("texture image", "photo"))))


# ---- meshes ----------------------------------------------------------------------------------------------------


def run_obj(case) -> None:
    """An OBJ as ``--face-mesh`` (``read_obj`` -> the rigging), the editor (``read_mesh``, an upload with its
    ``NAME.parts.json`` and ``NAME.points.json``) read it; a case whose bytes are JSON is a damaged sidecar."""
    from mpeg4fa.fdp import read_obj
    from mpeg4fa.web.files import read_mesh, read_upload

    sidecars = {name: data for name, data in fuzz_seeds.obj_sidecars()}
    model = fuzz_seeds.obj_seeds()[0][1]
    if case.data.lstrip()[:1] == b"{":
        kind = "parts" if b'"parts"' in case.data[:64] else "points"
        case.stage(f"read_upload(.{kind}.json)", lambda: read_upload([("m.obj", model), (f"m.{kind}.json", case.data)]))
        return
    pick = case.rng.random()
    if pick < 0.35:
        path = case.file(".obj")
        case.stage("read_obj", lambda: read_obj(path))
    elif pick < 0.6:
        case.stage("read_mesh", lambda: read_mesh(case.data, "case.obj"))
    elif pick < 0.8:
        files = [("case.obj", case.data)] + [(f"case.{n.split('/')[-1]}", d) for n, d in sidecars.items()
                                             if case.rng.random() < 0.5]
        case.stage("read_upload", lambda: read_upload(files))
    else:
        from mpeg4fa.face.assemble import mesh_face

        path = case.file(".obj")
        points = case.tmp / "face.points.json"
        if not points.exists():
            points.write_bytes(sidecars["sidecar/points.json"])
        face = case.stage("mesh_face", lambda: mesh_face(path, points))
        frame = np.zeros(68)
        frame[[2, 3, 4, 18, 30]] = 400.0  # open the jaw, lips and eyelids a little
        case.stage("deform", lambda: face.deform(frame))


def run_gltf(case) -> None:
    """A glTF/GLB as the editor reads it: ``read_mesh`` of the bytes (a .gltf must embed its buffers), an upload
    with ``buf.bin``, and ``read_model`` of a file with its buffer beside it (``mpeg4fa edit FILE.gltf``)."""
    from mpeg4fa.web.files import read_mesh, read_model, read_upload

    ext = "glb" if case.data[:4] == b"glTF" else "gltf"
    pick = case.rng.random()
    if pick < 0.5 or ext == "glb" and pick < 0.8:
        case.stage("read_mesh", lambda: read_mesh(case.data, f"case.{ext}"))
    elif pick < 0.8:
        files = [(f"case.{ext}", case.data), ("buf.bin", fuzz_seeds.gltf_buffer())]
        case.stage("read_upload", lambda: read_upload(files))
    else:
        buffer = case.tmp / "buf.bin"
        if not buffer.exists():
            buffer.write_bytes(fuzz_seeds.gltf_buffer())
        path = case.file(f".{ext}")
        case.stage("read_model", lambda: read_model(path))


RUNNERS: dict[str, Callable] = {
    "text": run_text, "stdin": run_stdin, "visemes": run_visemes, "points": run_points, "manifest": run_manifest,
    "conform": run_conform, "bap": run_bap, "wav": run_wav, "image": run_image, "obj": run_obj, "gltf": run_gltf,
}
