"""``mpeg4fa say``: tagged text -> speech, FAPs and an MP4 of the default head saying it."""
from __future__ import annotations

import argparse
import contextlib
import json
import sys
from pathlib import Path

import numpy as np

from ..speech.encoder import ENGINES, LEVELS, encode_text
from ..speech.errors import MarkupError
from .errors import UsageError
from .media import render_with_progress


def register(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser(
        "say", help="speak tagged text and render the face saying it (MP4 with audio)",
        description="Speak TEXT with espeak-ng (phonemes with sample-exact times), turn phonemes into "
                    "visemes (English: the 14 MPEG-4 visemes; Chinese: 15 visemes from pinyin) and tags "
                    "like (joy, 40, 0.5) into expressions with Hermite transitions, encode the FAPs as an "
                    "FBA stream, decode it again and render the default head with the speech. TEXT may be "
                    "'-' (read standard input) or @FILE (read a UTF-8 text file).",
        epilog='examples:\n  mpeg4fa say "(joy, 40, 0.5) Hello there! (sadness, 30, 1) Goodbye." -o hello.mp4\n'
               '  mpeg4fa say "(joy, 30, 0.5)你好，世界！" -o nihao.mp4 --keep',
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("text", help="the text with optional (expression, intensity 0-63, seconds) tags; - or @FILE")
    p.add_argument("-o", "--output", type=Path, required=True, help="OUT.mp4, or a folder for PNG frames")
    speech_options(p)
    p.add_argument("--fps", type=float, default=25.0, help="frame rate (default 25)")
    p.add_argument("--level", choices=LEVELS, default="low",
                   help="FAPs to send: high (FAP 1/2), low (3-68, the exact curves; default) or both")
    p.add_argument("--size", type=int, default=512, help="square image size (default 512)")
    p.add_argument("--aa", type=int, default=4, help="anti-aliasing samples (default 4; 0 = off)")
    p.add_argument("--keep", action="store_true", help="also write OUT.fba, OUT.wav and OUT.timings.json beside it")
    p.set_defaults(run=run_say)


def text_encoding_options(p: argparse.ArgumentParser) -> None:
    """The options of ``encode`` when INPUT is text (speech, FAP timeline, FDP of the speaker)."""
    first = len(p._actions)
    g = p.add_argument_group("text input: speech and FAPs")
    g.add_argument("--audio", type=Path, metavar="WAV", help="write the speech here (16-bit mono WAV)")
    g.add_argument("--timings", type=Path, metavar="JSON",
                   help='write the timed visemes used: [{"phoneme", "viseme", "start", "end"}, ...] in seconds')
    speech_options(g)
    g.add_argument("--level", choices=LEVELS, default="high",
                   help="FAPs to send: high (FAP 1 visemes + FAP 2 expressions; Chinese visemes and other "
                        "expressions as low-level FAPs; default), low (FAPs 3-68) or both")
    g = p.add_argument_group("text input: the speaker's face (FDP)")
    g.add_argument("--fdp-out", type=Path, metavar="FDP",
                   help="write an FDP describing the face (.fdp binary, or .json): the default head unless "
                        "--face-mesh or --front/--side say otherwise")
    g.add_argument("--face-mesh", type=Path, metavar="OBJ", help="the speaker's face mesh (Wavefront OBJ)")
    g.add_argument("--face-points", type=Path, metavar="JSON",
                   help="its feature points: JSON label -> vertex index or [x, y, z]")
    g.add_argument("--front", type=Path, metavar="IMAGE", help="a front photo of the speaker (sent as the texture)")
    g.add_argument("--front-points", type=Path, metavar="JSON", help="the front photo's feature points, label -> [x, y]")
    g.add_argument("--side", type=Path, metavar="IMAGE", help="a side photo of the speaker")
    g.add_argument("--side-points", type=Path, metavar="JSON", help="the side photo's feature points, label -> [x, y]")
    g.add_argument("--side-view", choices=("left", "right"), default="left",
                   help="which side of the face the side photo shows (default left)")
    # what these options default to, so a stream INPUT can tell which were given (argparse keeps
    # no public list of a parser's actions; _actions has been stable since Python 3.2)
    p.set_defaults(text_defaults={a.dest: a.default for a in p._actions[first:]})


def speech_options(g) -> None:
    """Engine, language, voice, rate and idle motion: shared by ``encode`` (text) and ``say``."""
    g.add_argument("--engine", choices=ENGINES, default="espeak",
                   help="espeak (phoneme times; default), pyttsx3 (word boundaries, visemes estimated in "
                        "between) or estimate (no audio: word times from a duration model)")
    g.add_argument("--lang", choices=("auto", "en", "zh"), default="auto", help="language (default: by script)")
    g.add_argument("--voice", help="English voice for latin text (default en-us)")
    g.add_argument("--rate", type=int, help="speech rate in words per minute (default 175)")
    g.add_argument("--idle", action="store_true", help="add blinks and small head motion")


def reject_text_options(args: argparse.Namespace) -> None:
    """A stream INPUT with text-only options is a mistake worth one clear line."""
    given = [name for name, default in args.text_defaults.items() if getattr(args, name) != default]
    if given:
        flags = ", ".join("--" + name.replace("_", "-") for name in given)
        raise UsageError(f"{flags} apply to text input, but {args.input} is a stream file",
                         hint="drop them, or pass the text itself")


def names_file(arg: str) -> bool:
    """Whether ``arg`` is the path of an existing file (a long sentence is not: its name is too long)."""
    try:
        return Path(arg).is_file()
    except (OSError, ValueError):
        return False


def read_text(arg: str) -> tuple[str, str]:
    """The text and its name for messages: literal, '-' (stdin) or @FILE."""
    if arg == "-":
        return sys.stdin.read(), "<stdin>"
    if arg.startswith("@") or names_file(arg):
        path = Path(arg[1:] if arg.startswith("@") else arg)
        try:
            return path.read_text(encoding="utf-8"), str(path)
        except UnicodeDecodeError as exc:
            raise MarkupError(f"the text file is not UTF-8 ({exc.reason} at byte {exc.start})", 1, 1,
                              hint="save it as UTF-8", source=str(path)) from None
    return arg, "<text>"


def run_encode_text(args: argparse.Namespace) -> int:
    """``mpeg4fa encode TEXT``: speech -> FAP stream (+ WAV, timings, FDP)."""
    from ..fba import encode
    from .codec import coding_options

    if args.engine == "estimate" and args.audio is not None:
        raise UsageError("the estimate engine makes no audio, so there is nothing for --audio",
                         hint="drop --audio, or use --engine espeak or pyttsx3")
    fdp = _speaker_fdp(args) if args.fdp_out is not None else None
    text, name = read_text(args.input)
    encoded = encode_text(text, engine=args.engine, lang=args.lang, voice=args.voice, rate=args.rate,
                          fps=args.fps or 25.0, level=args.level, idle=args.idle, name=name)
    data = encode(encoded.stream, coding_options(args, encoded.coding()))
    args.output.write_bytes(data)
    written = [f"{args.output} ({len(data)} bytes)"]
    if args.audio is not None:
        encoded.speech.write_wav(args.audio)
        written.append(f"{args.audio} ({encoded.speech.duration:.2f} s)")
    if args.timings is not None:
        _write_timings(encoded, args.timings)
        written.append(str(args.timings))
    if fdp is not None:
        from ..fdp import save_fdp
        save_fdp(fdp, args.fdp_out)
        written.append(f"{args.fdp_out} ({len(fdp.labels)} feature points)")
    frames = len(encoded.stream)
    seconds = frames / (args.fps or 25.0)
    print(f"{name}: {encoded.speech.engine} speech {encoded.speech.duration:.2f} s, {frames} frames, "
          f"{len(data) * 8 / max(frames, 1):.1f} bits/frame ({len(data) * 8 / seconds / 1000:.2f} kbit/s, "
          f"{args.level}-level)", file=sys.stderr)
    print("wrote " + ", ".join(written), file=sys.stderr)
    return 0


def _speaker_fdp(args: argparse.Namespace):
    """The FDP to send: from a mesh with feature points, from two photos, or the default head."""
    from .. import fdp as fdp_io

    def need(*names: str) -> None:
        missing = ["--" + n.replace("_", "-") for n in names if getattr(args, n) is None]
        if missing:
            raise UsageError(f"{', '.join(missing)} missing", hint="see mpeg4fa encode --help (the FDP options)")

    if args.face_mesh is not None and args.front is not None:
        raise UsageError("--face-mesh and --front both describe the face", hint="give one of them")
    if args.face_mesh is not None:
        need("face_points")
        mesh = fdp_io.read_obj(args.face_mesh)
        with _located(str(args.face_points)):
            return fdp_io.fdp_from_mesh(mesh, fdp_io.read_points_json(args.face_points), name=args.face_mesh.stem)
    if args.front is not None or args.side is not None:
        need("front", "front_points", "side", "side_points")
        with _located(f"{args.front_points} + {args.side_points}"):
            return fdp_io.fdp_from_photos(fdp_io.read_points_json(args.front_points),
                                          fdp_io.read_points_json(args.side_points), side_view=args.side_view,
                                          texture=fdp_io.texture_from_file(args.front), name=args.front.stem)
    from ..face import FaceModel
    return FaceModel.default().to_fdp()


@contextlib.contextmanager
def _located(path: str):
    """A value the FDP model rejects (a point outside the photo, a bad vertex index) named by its file."""
    from ..fdp import FdpError, FdpValueError
    try:
        yield
    except FdpValueError as exc:
        raise FdpError.no_place(path, exc.message, hint="check the feature point annotations") from None


def _write_timings(encoded, path: Path) -> None:
    timings = [t.as_dict() for t in encoded.utterance.timings]
    path.write_text(json.dumps(timings, ensure_ascii=False, indent=1) + "\n", encoding="utf-8")


def run_say(args: argparse.Namespace) -> int:
    from ..fba import decode, encode
    from ..face import FaceModel
    from ..render import Audio

    text, name = read_text(args.text)
    encoded = encode_text(text, engine=args.engine, lang=args.lang, voice=args.voice, rate=args.rate, fps=args.fps,
                          level=args.level, idle=args.idle, name=name)
    data = encode(encoded.stream, encoded.coding())
    stream = decode(data)  # the face plays what a receiver would decode
    speech = encoded.speech
    audio = Audio((speech.samples.astype(np.float32) / 32768.0)[:, None], speech.rate)
    if args.keep:
        base = args.output.with_suffix("")
        base.with_suffix(".fba").write_bytes(data)
        speech.write_wav(base.with_suffix(".wav"))
        _write_timings(encoded, base.with_suffix(".timings.json"))
    result = render_with_progress("say", stream, args.output, face=FaceModel.default(), audio=audio,
                                  width=args.size, height=args.size, samples=args.aa)
    print(f"{args.output}: {result.n_frames} frames at {result.fps:g} fps ({result.duration:.2f} s), "
          f"{len(data) * 8 / max(len(stream), 1):.0f} bits/frame of FAPs ({args.level}-level); "
          f"rendered in {result.seconds:.1f} s")
    return 0
