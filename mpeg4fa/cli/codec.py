"""Codec commands: info, decode, encode, validate, demo."""
from __future__ import annotations

import argparse
import dataclasses
import json
import os
import sys
from pathlib import Path

from ..fba import EncodeOptions, FbaError, decode, demo_stream, describe, encode
from ..formats import read_stream, write_fap
from ..formats.sniff import sniff
from ..spec import N_FAP_GROUPS
from . import speech


def register(commands: argparse._SubParsersAction) -> None:
    p = commands.add_parser("info", help="show what a .fba or .fap stream holds",
                            description="Header, frames, frame rate, duration, masks, bits per frame and "
                                        "bit rate of a binary FBA stream or a text .fap file.")
    p.add_argument("stream", type=Path, help="a .fba (binary) or .fap (text) file; the kind is read from the content")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of text")
    p.set_defaults(run=run_info)

    p = commands.add_parser("decode", help="decode a .fba stream to a .fap text file",
                            description="Decode a binary FBA stream and write its FAPs as a 2.1 .fap text file "
                                        "(skipped frames become gaps in the frame numbers).")
    p.add_argument("input", type=Path, help="the .fba stream")
    p.add_argument("-o", "--output", type=Path, required=True, help="the .fap file to write")
    p.set_defaults(run=run_decode)

    p = commands.add_parser(
        "encode", help="encode tagged text (speech -> FAPs), a .fap file or a .fba stream to .fba",
        description="Encode FAPs into a binary FBA stream. INPUT is a .fap or .fba file (a .fba is re-encoded "
                    "with the coding parameters it carries, the same bytes for a stream from a conforming "
                    "encoder, unless options override them), or text with expression tags such as "
                    "'(joy, 40, 0.5) Hello there': spoken by a TTS engine, turned into visemes and "
                    "expressions and encoded with the speech as --audio. Text may also come from a file "
                    "(INPUT names a file that is not a stream, or @FILE) or standard input (-).",
        epilog='examples:\n  mpeg4fa encode "(joy, 40, 0.5) Hello there!" -o talk.fba --audio talk.wav '
               '--timings talk.json\n  mpeg4fa encode script.txt -o talk.fba --audio talk.wav --fdp-out face.fdp\n'
               '  echo "你好，世界" | mpeg4fa encode - -o nihao.fba --audio nihao.wav --level both\n'
               '  mpeg4fa encode received.fap -o received.fba --optimize',
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input", help="a .fap or .fba file, tagged text, @FILE or - (text from standard input)")
    p.add_argument("-o", "--output", type=Path, required=True, help="the .fba stream to write")
    p.add_argument("--quant", type=_quant, metavar="0-31", help="fap_quant: 0 = exact, larger = coarser (default 1)")
    p.add_argument("--bap-quant", type=_quant, metavar="0-31", help="bap_quant for body data (default 1)")
    p.add_argument("--intra-period", type=int, metavar="K", help="an intra frame every K frames (0 = first only)")
    p.add_argument("--fps", type=float, help="frame rate to send (default: the input's)")
    p.add_argument("--mask-types", type=_mask_types, metavar="T,T,...",
                   help=f"{N_FAP_GROUPS} FAP group mask types: 0 none, 1 hold unsent, 2 interpolate unsent, 3 all")
    p.add_argument("--start-codes", action=argparse.BooleanOptionalAction, default=None,
                   help="send a plane start code before every intra plane")
    p.add_argument("--skip-repeats", action="store_true", help="send repeated frames as skip counts")
    p.add_argument("--time-codes", action="store_true", help="send a time code in every intra header")
    p.add_argument("--optimize", action="store_true",
                   help="smallest stream with the same decoded values (tight ranges, repeats skipped)")
    speech.text_encoding_options(p)
    p.set_defaults(run=run_encode)

    p = commands.add_parser("validate", help="check that a .fba stream decodes to its end code",
                            description="Exit status 0 when the stream is valid; 1 with one line naming the "
                                        "error and its bit offset when it is not.")
    p.add_argument("stream", type=Path)
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.set_defaults(run=run_validate)

    p = commands.add_parser("demo", help="encode a built-in synthetic FAP sequence and show what it holds",
                            description="Write a 4-second synthetic talking stream (FAP 1, FAP 2 and ten "
                                        "low-level FAPs), decode it back and print its summary.")
    p.add_argument("-o", "--output", type=Path, default=Path("demo.fba"), help="where to write it (demo.fba)")
    p.set_defaults(run=run_demo)


def _quant(text: str) -> int:
    q = int(text)
    if not 0 <= q <= 31:
        raise argparse.ArgumentTypeError("the quantiser is 0..31")
    return q


def _mask_types(text: str) -> list[int]:
    types = [int(t) for t in text.split(",")]
    if len(types) != N_FAP_GROUPS or any(t not in (0, 1, 2, 3) for t in types):
        raise argparse.ArgumentTypeError(f"give {N_FAP_GROUPS} comma-separated mask types, each 0..3")
    return types


def run_info(args: argparse.Namespace) -> int:
    stream, kind = read_stream(args.stream)
    info = {"file": str(args.stream), "format": kind,
            **describe(stream, os.path.getsize(args.stream) if kind == "fba" else None)}
    if args.json:
        json.dump(info, sys.stdout, indent=2)
        print()
    else:
        print(_as_text(info))
    return 0


def _as_text(info: dict) -> str:
    lines = []
    for key, value in info.items():
        if isinstance(value, dict):
            value = ", ".join(f"{k} {v}" for k, v in value.items())
        elif key in _NUMBER_LISTS:
            value = _ranges(value)
        elif isinstance(value, list):
            value = " ".join(map(str, value))
        lines.append(f"{key.replace('_', ' '):>18}: {value}")
    return "\n".join(lines)


_NUMBER_LISTS = ("intra_frames", "faps_sent", "visemes_used", "expressions_used")


def _ranges(numbers: list[int]) -> str:
    """[1,2,3,5] -> '1-3 5'."""
    out, start = [], None
    for i, n in enumerate(numbers):
        if start is None:
            start = n
        if i + 1 == len(numbers) or numbers[i + 1] != n + 1:
            out.append(str(start) if start == n else f"{start}-{n}")
            start = None
    return " ".join(out)


def run_decode(args: argparse.Namespace) -> int:
    stream = decode(args.input)
    write_fap(stream, args.output, name=args.output.name)
    print(f"{args.input} -> {args.output}: {len(stream)} frames at {stream.fps:g} fps", file=sys.stderr)
    return 0


def is_stream_file(arg: str) -> bool:
    """Whether an encode INPUT names a .fba/.fap stream (else it is text, or names a text file)."""
    path = Path(arg)
    return speech.names_file(arg) and (path.suffix.lower() in (".fap", ".fba") or sniff(path) == "fba")


def coding_options(args: argparse.Namespace, default: EncodeOptions | None) -> EncodeOptions | None:
    """``default`` with the coding flags given on the command line put over it (None: none given)."""
    chosen = {"fap_quant": args.quant, "bap_quant": args.bap_quant, "intra_period": args.intra_period,
              "fps": args.fps, "mask_types": args.mask_types, "start_codes": args.start_codes,
              "skip_repeats": args.skip_repeats or None, "time_codes": args.time_codes or None,
              "optimize": args.optimize or None}
    given = {k: v for k, v in chosen.items() if v is not None}
    if not given:
        return default
    return dataclasses.replace(default, **given) if default is not None else EncodeOptions(**given)


def run_encode(args: argparse.Namespace) -> int:
    if not is_stream_file(args.input):
        return speech.run_encode_text(args)
    speech.reject_text_options(args)
    stream, kind = read_stream(args.input)
    options = coding_options(args, EncodeOptions() if kind == "fap" else None)
    data = encode(stream, options)
    args.output.write_bytes(data)
    print(f"{args.input} -> {args.output}: {len(stream)} frames, {len(data)} bytes", file=sys.stderr)
    return 0


def run_validate(args: argparse.Namespace) -> int:
    try:
        stream = decode(args.stream)
    except FbaError as exc:
        result = {"valid": False, "error": exc.message, "bit_offset": exc.bit_offset, "frame": exc.frame,
                  "frames_decoded": len(exc.partial) if exc.partial is not None else 0}
        print(json.dumps(result) if args.json else f"{args.stream}: invalid: {exc}")
        return 1
    result = {"valid": True, "frames": len(stream), "fps": stream.fps}
    print(json.dumps(result) if args.json else f"{args.stream}: valid: {len(stream)} frames at {stream.fps:g} fps")
    return 0


def run_demo(args: argparse.Namespace) -> int:
    args.output.write_bytes(encode(demo_stream(), EncodeOptions(fap_quant=1)))
    print(f"wrote {args.output}\n")
    args.stream, args.json = args.output, False
    return run_info(args)
