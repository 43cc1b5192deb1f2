"""``mpeg4fa play`` and ``mpeg4fa snapshot``: watch and hear a decoded stream."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

from ..formats import read_stream
from ..render.camera import VIEWS
from ..render.video import AUDIO_WAV, writes_folder
from . import options
from .errors import UsageError
from .media import (audio_beside, check_frames_output, image_format, render_with_progress, save_image,
                    skin_texture)
from .model import deformer_option, face_options, posed_face
from .options import Commands
from .paths import refuse_overlaps



def register(commands: Commands) -> None:
    p = commands.add_parser(
        "play", help="render a .fba or .fap stream to MP4 (with its speech) or PNG frames",
        description="Decode a stream, animate the face (the generic head, or one calibrated to an FDP) and "
                    "render it headless: an MP4 (H.264 + AAC) when OUT ends in .mp4/.mov/.m4v, else a folder of "
                    "PNG frames. Frames appear at the stream's presentation times; the audio starts with "
                    "the first frame. A WAV with the stream's name beside it is used unless --audio or "
                    "--no-audio says otherwise.",
        epilog="examples:\n  mpeg4fa play talk.fba -o talk.mp4\n"
               "  mpeg4fa play talk.fap --fdp face.fdp --audio talk.wav -o frames/ --size 256\n"
               "  mpeg4fa play talk.fba --fdp face.fdp -o talk.mp4   # the skin wears the FDP's texture, if any\n"
               "  mpeg4fa play talk.fba --photo me.jpg -o talk.mp4   # your own face, found in the photo\n"
               "  mpeg4fa play talk.fba --show",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("stream", type=Path, help="a .fba (binary) or .fap (text) stream")
    p.add_argument("-o", "--output", type=Path, help="OUT.mp4 (or .mov/.m4v) or a folder for PNG frames")
    audio = p.add_mutually_exclusive_group()
    audio.add_argument("--audio", type=Path, help="speech to mux (WAV, or any file FFmpeg reads)")
    audio.add_argument("--no-audio", action="store_true", help="do not look for a WAV beside the stream")
    p.add_argument("--fit", choices=("pad", "trim"), default="pad",
                   help="when stream and audio lengths differ by more than a frame: pad the shorter (default: "
                        "the video holds its last frame, the audio gets silence) or trim the longer")
    p.add_argument("--fps", type=options.fps, help="output frame rate, 0 < fps < 256 (default: the stream's)")
    p.add_argument("--crf", type=options.crf, default=18, help="H.264 quality, 0 (lossless) to 51 (default 18)")
    p.add_argument("--show", action="store_true",
                   help="play in a window in real time (needs a display; late frames are dropped; no sound)")
    p.add_argument("--json", action="store_true", help="print a JSON summary when done")
    _render_options(p)
    p.set_defaults(run=run_play)

    p = commands.add_parser("snapshot", help="render one frame of a stream to a PNG",
                            description="Render the face as it is at one frame (or time) of a stream.",
                            epilog="example: mpeg4fa snapshot talk.fba --frame 40 -o f40.png")
    p.add_argument("stream", type=Path, help="a .fba (binary) or .fap (text) stream")
    at = p.add_mutually_exclusive_group()
    at.add_argument("--frame", type=options.frame, help="frame index (0 = first, -1 = last; default 0)")
    at.add_argument("--time", type=options.seconds, metavar="SECONDS",
                    help="presentation time in seconds from the first frame (>= 0)")
    p.add_argument("-o", "--output", type=Path, required=True, help="the PNG to write")
    _render_options(p)
    p.set_defaults(run=run_snapshot)


def _render_options(p: argparse.ArgumentParser) -> None:
    face_options(p)
    p.add_argument("--face-mesh", type=Path, metavar="OBJ",
                   help="play on this mesh instead of the generic head (Wavefront OBJ; all of it is skin), "
                        "rigged from its feature points")
    p.add_argument("--face-points", type=Path, metavar="JSON",
                   help="with --face-mesh: its feature points, JSON label -> vertex index or [x, y, z]")
    deformer_option(p)
    p.add_argument("--size", type=options.size, default=(512, 512), metavar="W[xH]",
                   help="image size, 16 to 8192 (default 512; even for MP4)")
    p.add_argument("--aa", type=options.samples, default=0, metavar="N",
                   help="anti-aliasing samples: 0 (off; default, fastest), 1, 2, 4, 8 or 16 (4 or 8 for final output; "
                        "the GL context may allow fewer: Mesa's CPU renderer 4)")
    p.add_argument("--view", default="front", choices=tuple(VIEWS), help="camera position (default front)")
    p.add_argument("--texture", type=Path, help="a UV texture image for the skin (e.g. from photos); wins over the "
                                                "FDP's own texture")
    p.add_argument("--photo", type=Path, metavar="IMAGE",
                   help="play on the face in this photo: its feature points found (the 'photo' extra), the head "
                        "calibrated to them and wearing the photo, as 'mpeg4fa fdp' makes it")
    p.add_argument("--no-fdp-texture", action="store_true",
                   help="do not paint the skin with the texture the --fdp file carries (its front photo)")


def _face(args: argparse.Namespace):
    """(face, texture from --photo or None): the face of the options, or the one found in --photo."""
    if args.photo is None:
        return posed_face(args), None
    from .fdp_photo import photo_face
    return photo_face(args)


def _renderer_options(args: argparse.Namespace, face, photo_texture=None) -> dict:
    chosen = {"width": args.size[0], "height": args.size[1], "samples": args.aa, "view": args.view}
    texture = photo_texture if photo_texture is not None else skin_texture(args, face)
    if texture is not None:
        chosen["texture"] = texture
    return chosen


def run_play(args: argparse.Namespace) -> int:
    from ..render import Renderer, play_live

    if args.output is None and not args.show:
        raise UsageError("say where the frames go", hint="-o OUT.mp4, -o FOLDER for PNG frames, or --show")
    audio = audio_beside(args) if args.output is not None else None
    if args.output is not None:
        inputs = {"stream": args.stream, "--audio": audio, "--fdp": args.fdp, "--texture": args.texture,
                  "--face-mesh": args.face_mesh, "--face-points": args.face_points, "--photo": args.photo}
        refuse_overlaps(inputs, {"-o": args.output})
        check_frames_output("play", args.output, args.size)
        if audio is not None and writes_folder(args.output):  # PNG frames, and the audio beside them
            refuse_overlaps(inputs, {f"-o {args.output}'s {AUDIO_WAV}": args.output / AUDIO_WAV})
    stream, _ = read_stream(args.stream)
    face, photo_texture = _face(args)
    render_options = _renderer_options(args, face, photo_texture)
    if args.show:
        from ..render.window import show
        with Renderer(face, **render_options) as renderer:
            show((f.image for f in play_live(iter(stream), renderer)), title=f"mpeg4fa: {args.stream.name}",
                 fps_hint=stream.fps)
        if args.output is None:
            return 0
    result = render_with_progress("play", stream, args.output, face=face, audio=audio, fps=args.fps, fit=args.fit,
                                  writer_options=None if writes_folder(args.output) else {"crf": args.crf},
                                  **render_options)
    summary = {"output": str(args.output), "frames": result.n_frames, "rendered": result.rendered,
               "fps": result.fps, "duration": round(result.duration, 6),
               "audio": str(audio) if audio else None, "audio_duration": result.audio_duration,
               "adjustments": result.adjustments, "seconds": round(result.seconds, 3),
               "speed_x_realtime": round(result.speed, 2)}
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(f"{args.output}: {result.n_frames} frames at {result.fps:g} fps ({result.duration:.2f} s)"
              f"{', with audio' if audio else ''}; rendered in {result.seconds:.1f} s ({result.speed:.1f}x real time)")
    return 0


def run_snapshot(args: argparse.Namespace) -> int:
    from PIL import Image

    from ..render import snapshot

    refuse_overlaps({"stream": args.stream, "--fdp": args.fdp, "--texture": args.texture, "--photo": args.photo,
                     "--face-mesh": args.face_mesh, "--face-points": args.face_points}, {"-o": args.output})
    image_format("snapshot", args.output)  # before the render: a name no image format has is refused at once
    stream, _ = read_stream(args.stream)
    face, photo_texture = _face(args)
    image = snapshot(stream, frame=args.frame, seconds=args.time, face=face,
                     **_renderer_options(args, face, photo_texture))
    save_image(Image.fromarray(image), args.output, "snapshot")
    print(f"{args.output}: {image.shape[1]}x{image.shape[0]}")
    return 0
