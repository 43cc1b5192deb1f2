"""``mpeg4fa say``: tagged text -> speech, FAPs and an MP4 of the default head saying it."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

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
    p.add_argument("--lang", choices=("auto", "en", "zh"), default="auto", help="language (default: by script)")
    p.add_argument("--voice", help="English voice for latin text (default en-us)")
    p.add_argument("--rate", type=int, help="speech rate in words per minute (default 175)")
    p.add_argument("--fps", type=float, default=25.0, help="frame rate (default 25)")
    p.add_argument("--level", choices=("high", "low", "both"), default="low",
                   help="FAPs to send: high (FAP 1/2), low (3-68, the exact curves; default) or both")
    p.add_argument("--idle", action="store_true", help="add blinks and small head motion")
    p.add_argument("--size", type=int, default=512, help="square image size (default 512)")
    p.add_argument("--aa", type=int, default=4, help="anti-aliasing samples (default 4; 0 = off)")
    p.add_argument("--keep", action="store_true", help="also write OUT.fba, OUT.wav and OUT.timings.json beside it")
    p.set_defaults(run=run_say)


def read_text(arg: str) -> tuple[str, str]:
    """The text and its name for messages: literal, '-' (stdin) or @FILE."""
    if arg == "-":
        return sys.stdin.read(), "<stdin>"
    if arg.startswith("@"):
        path = Path(arg[1:])
        return path.read_text(encoding="utf-8"), str(path)
    return arg, "<text>"


def run_say(args: argparse.Namespace) -> int:
    from ..fba import decode, encode
    from ..face import FaceModel
    from ..render import Audio
    from ..speech.encoder import encode_text

    text, name = read_text(args.text)
    encoded = encode_text(text, lang=args.lang, voice=args.voice, rate=args.rate, fps=args.fps, level=args.level,
                          idle=args.idle, name=name)
    data = encode(encoded.stream)
    stream = decode(data)  # the face plays what a receiver would decode
    speech = encoded.speech
    audio = Audio((speech.samples.astype(np.float32) / 32768.0)[:, None], speech.rate)
    if args.keep:
        base = args.output.with_suffix("")
        base.with_suffix(".fba").write_bytes(data)
        speech.write_wav(base.with_suffix(".wav"))
        timings = [t.as_dict() for t in encoded.utterance.timings]
        base.with_suffix(".timings.json").write_text(json.dumps(timings, ensure_ascii=False, indent=1))
    result = render_with_progress("say", stream, args.output, face=FaceModel.default(), audio=audio,
                                  width=args.size, height=args.size, samples=args.aa)
    print(f"{args.output}: {result.n_frames} frames at {result.fps:g} fps ({result.duration:.2f} s), "
          f"{len(data) * 8 / max(len(stream), 1):.0f} bits/frame of FAPs ({args.level}-level); "
          f"rendered in {result.seconds:.1f} s")
    return 0
