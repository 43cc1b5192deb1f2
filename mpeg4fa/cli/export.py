"""``mpeg4fa export``: a decoded stream as a file other tools play (a glTF binary head with its animation).

The formats are a small table (:data:`FORMATS`): output suffix -> writer. Each writer takes
the parsed arguments and does its work through a library call in :mod:`mpeg4fa.export`.
"""
from __future__ import annotations

import argparse
from pathlib import Path
from typing import Callable

from . import options
from .errors import UsageError
from .media import audio_beside, skin_texture
from .model import deformer_option, face_options, posed_face
from .options import Commands
from .paths import refuse_overlaps, same_file



def _write_glb(args: argparse.Namespace) -> str:
    """The head (calibrated to --fdp) as GLB, the stream baked as ARKit morph weights or per-frame vertices."""
    from ..export.gltf import export_glb
    from ..formats import read_stream
    from .progress import ProgressBar

    stream, _ = read_stream(args.stream)
    face = posed_face(args)
    audio = audio_beside(args)
    wav_out = args.output.with_suffix(".wav") if audio is not None else None
    if wav_out is not None and same_file(audio, wav_out):
        wav_out = None  # the speech is already beside the GLB under its name
    refuse_overlaps({"stream": args.stream, "--fdp": args.fdp, "--audio": audio, "--texture": args.texture},
                    {"-o": args.output, "-o's speech": wav_out})
    bar = ProgressBar("posing", unit="poses")
    try:
        result = export_glb(stream, face, args.output, animation=args.animation, audio=audio,
                            texture=skin_texture(args, face), progress=bar)
    finally:
        bar.close()
    extra = f"; speech: {result.audio}" if result.audio else ""
    if result.skin == "colours":
        extra += ("; the head's colours could not be baked into a texture (no OpenGL context, or no UV map), so "
                  "the brows are left out (the lips are in the vertex colours)")
    return (f"{args.output}: {result.n_parts} parts, {result.n_targets} morph targets, {result.n_frames} key frames "
            f"({result.duration:.2f} s, {args.animation} animation), {result.bytes / 1e6:.1f} MB{extra}")


def _write_weights(args: argparse.Namespace, kind: str) -> str:
    """Per-frame ARKit-52 or OVR-15 weights as JSON (schema: :mod:`mpeg4fa.export.weights`)."""
    from ..export import arkit_weights, oculus_weights, write_weights_json
    from ..formats import read_stream

    stream, _ = read_stream(args.stream)
    weights = (arkit_weights(stream, posed_face(args), fps=args.fps) if kind == "arkit"
               else oculus_weights(stream, fps=args.fps))
    write_weights_json(weights, args.output)
    return f"{args.output}: {len(weights.times)} frames of {len(weights.names)} {kind} weights"


def _write_azure(args: argparse.Namespace) -> str:
    """Azure-style viseme events as JSON (schema: :mod:`mpeg4fa.export.events`)."""
    from ..export import write_azure_json
    from ..formats import read_stream

    if args.fps is not None:
        raise UsageError("--fps samples per-frame weights; Azure events come at each change of viseme",
                         hint="drop --fps")
    stream, _ = read_stream(args.stream)
    return f"{args.output}: {write_azure_json(stream, args.output)} Azure viseme events"


FORMATS: dict[str, tuple[tuple[str, ...], Callable[[argparse.Namespace], str]]] = {
    "glb": ((".glb",), _write_glb),
    "arkit-json": ((), lambda args: _write_weights(args, "arkit")),
    "oculus-json": ((), lambda args: _write_weights(args, "oculus")),
    "azure-json": ((), _write_azure),
}
"""Format name -> (output suffixes it is chosen by, writer returning the line to print)."""


def register(commands: Commands) -> None:
    p = commands.add_parser(
        "export", help="export a .fba or .fap stream for other players (glTF binary head with its animation)",
        description="Decode a stream and write it for other tools. glb: the head (calibrated to --fdp) with its "
                    "parts, materials and texture, and the stream baked as a glTF animation. "
                    "--animation morph (default) drives the 52 ARKit-named morph targets the generic head "
                    "carries with the weights the arkit deformer derives from each frame's FAPs, so the GLB "
                    "shows the head as '--deformer arkit' would, not exactly as the default feature-point "
                    "deformer does (no feature-point correction of the skin; the head turns rigidly with "
                    "its neck; a head without ARKit units, e.g. a --face-mesh, cannot do this). "
                    "--animation vertex bakes every frame's vertex positions as one morph target per frame "
                    "(exact for any head and deformer; larger files). glTF has no audio: the stream's speech "
                    "(--audio, or the WAV beside the stream) is copied next to OUT with OUT's name and .wav. "
                    "arkit-json / oculus-json (give --format): per-frame weights of the 52 ARKit blend shapes "
                    "(as the arkit deformer drives them; needs the generic head) or of the 15 Oculus/OVR visemes; "
                    "azure-json: Azure-style viseme events (AudioOffset in 100 ns ticks, VisemeId 0-21) at each "
                    "change of the viseme shown, the form 'mpeg4fa encode --visemes' reads back (JSON schemas: "
                    "mpeg4fa/export/weights.py and events.py).",
        epilog="examples:\n  mpeg4fa export talk.fba -o talk.glb\n"
               "  mpeg4fa export talk.fap --fdp face.fdp --animation vertex --audio talk.wav -o talk.glb\n"
               "  mpeg4fa export talk.fba --format arkit-json -o talk.arkit.json",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("stream", type=Path, help="a .fba (binary) or .fap (text) stream")
    p.add_argument("-o", "--output", type=Path, required=True, help="the file to write (format from its suffix)")
    p.add_argument("--format", choices=tuple(FORMATS), help="output format (default: from the -o suffix)")
    p.add_argument("--animation", choices=("morph", "vertex"), default="morph",
                   help="glb: ARKit morph-target weights (default; as the arkit deformer shows the face) or "
                        "per-frame vertex positions (the chosen --deformer, exact, bigger)")
    p.add_argument("--fps", type=options.fps, metavar="FPS",
                   help="arkit-json, oculus-json: the weights at this rate, each tick showing the frame a player "
                        "would (default: one entry per stream frame)")
    audio = p.add_mutually_exclusive_group()
    audio.add_argument("--audio", type=Path, help="speech to copy next to the output (WAV)")
    audio.add_argument("--no-audio", action="store_true", help="do not look for a WAV beside the stream")
    face_options(p)
    deformer_option(p)
    p.add_argument("--texture", type=Path, help="a UV texture image for the skin, embedded as PNG; wins over the "
                                                "FDP's own texture")
    p.add_argument("--no-fdp-texture", action="store_true",
                   help="do not embed the texture the --fdp file carries (its front photo)")
    p.set_defaults(run=run_export)


def _format_of(args: argparse.Namespace) -> str:
    suffix = args.output.suffix.lower()
    by_suffix = next((name for name, (suffixes, _) in FORMATS.items() if suffix in suffixes), None)
    if args.format is not None:
        if by_suffix not in (None, args.format):  # JSON in a file named .glb would fool every glTF reader
            raise UsageError(f"-o {args.output} names a {by_suffix} file, but --format {args.format} writes another",
                             hint=f"name the output for {args.format} (e.g. .json), or drop --format")
        return args.format
    if by_suffix is not None:
        return by_suffix
    known = ", ".join(s for suffixes, _ in FORMATS.values() for s in suffixes)
    raise UsageError(f"-o {args.output}: no export format for suffix {suffix or '(none)'!r}",
                     hint=f"name the output with one of {known}, or give --format")


def run_export(args: argparse.Namespace) -> int:
    refuse_overlaps({"stream": args.stream, "--fdp": args.fdp, "--audio": args.audio}, {"-o": args.output})
    if args.animation == "morph" and args.deformer not in ("fap", "arkit"):
        raise UsageError(f"--deformer {args.deformer} goes with --animation vertex",
                         hint="morph animation shows the ARKit units as the arkit deformer drives them")
    name = _format_of(args)
    if args.fps is not None and name == "glb":
        raise UsageError("--fps goes with arkit-json and oculus-json", hint="a GLB keys the stream's own frames")
    _, writer = FORMATS[name]
    print(writer(args))
    return 0
