"""Codec commands: info, decode, encode, validate, demo."""
from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

from ..atomic import atomic_output, atomic_outputs
from ..fba import EncodeOptions, FbaError, decode, demo_stream, describe, encode
from ..formats import (has_body, has_face, merge_face_body, read_bap, read_stream, split_face_body,
                       write_bap, write_fap)
from ..formats.sniff import sniff
from . import speech, text_input, tracing
from .coding import coding_flags, coding_options
from .errors import UsageError
from .options import Commands
from .paths import refuse_overlaps


def register(commands: Commands) -> None:
    p = commands.add_parser("info", help="show what a .fba, .fap or .bap stream holds",
                            description="Header, frames, frame rate, duration, masks, bits per frame and "
                                        "bit rate of a binary FBA stream or a text .fap or .bap file.")
    p.add_argument("stream", type=Path,
                   help="a .fba (binary), .fap or .bap (text) file; the kind is read from the content")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object instead of text (with --trace: one JSON object per element, "
                        "a line each, and at a fault a last {\"error\", \"bit_offset\", \"frame\"} line)")
    p.add_argument("--trace", action="store_true",
                   help="list every syntax element of a .fba stream (start codes, stuffing, header fields, "
                        "arithmetic-coded segments with their symbols and values) with its bit offset, width "
                        "and value, frame by frame; a damaged stream is listed up to the fault, then the "
                        "error (exit 1)")
    p.add_argument("--frames", type=tracing.frame_range, metavar="A:B",
                   help="with --trace: only frames A to B-1 (A:, :B or one frame A)")
    p.set_defaults(run=run_info)

    p = commands.add_parser(
        "decode", help="decode a .fba stream to .fap (face) and .bap (body) text files",
        description="Decode a binary FBA stream and write its FAPs as a 2.1 .fap text file and, when the stream "
                    "carries body animation, its BAPs as a 3.1 .bap text file (VREng's format) beside it: "
                    "-o OUT.fap also writes OUT.bap, or the file --bap names. -o OUT.bap (or --bap-only) writes "
                    "the body alone. Both files number frames alike (skipped frames become gaps), so "
                    "'encode OUT.fap --bap OUT.bap' joins them again. Both files are written or neither.",
        epilog="examples:\n  mpeg4fa decode yes.fba -o yes.fap            # yes.fap, and yes.bap for a face+body stream"
               "\n  mpeg4fa decode yes.fba -o yes.fap --bap body/yes.bap\n"
               "  mpeg4fa decode basicMotion.fba -o motion.bap  # body only",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input", type=Path, help="the .fba stream")
    p.add_argument("-o", "--output", type=Path, required=True,
                   help="the .fap file to write (a name ending in .bap: the .bap file, body only)")
    p.add_argument("--bap", type=Path, metavar="FILE",
                   help="where the BAPs of a face+body stream go (default: the -o name with .bap)")
    p.add_argument("--bap-only", action="store_true", help="write only the body, as a .bap file, to -o")
    p.set_defaults(run=run_decode)

    p = commands.add_parser(
        "encode", help="encode tagged text (speech -> FAPs), a .fap/.bap file or a .fba stream to .fba",
        description="Encode FAPs and BAPs into a binary FBA stream. INPUT is a .fap, .bap or .fba file (a .bap "
                    "alone gives a body-only stream; --bap joins a .bap body to a .fap face; a .fba is re-encoded "
                    "with the coding parameters it carries, the same bytes for a stream from a conforming "
                    "encoder, unless options override them), or text with expression tags such as "
                    "'(joy, 40, 0.5) Hello there': spoken by a TTS engine, turned into visemes and "
                    "expressions and encoded with the speech as --audio. Text may also come from a file "
                    "(INPUT names a file that is not a stream, or @FILE) or standard input (-); an INPUT that looks "
                    "like a file name (a path separator or an extension, no spaces) must name a readable file, "
                    "unless --text says it is text.",
        epilog='examples:\n  mpeg4fa encode "(joy, 40, 0.5) Hello there!" -o talk.fba --audio talk.wav '
               '--timings talk.json\n  mpeg4fa encode script.txt -o talk.fba --audio talk.wav --fdp-out face.fdp\n'
               '  echo "你好，世界" | mpeg4fa encode - -o nihao.fba --audio nihao.wav --level both\n'
               '  mpeg4fa encode received.fap -o received.fba --optimize\n'
               '  mpeg4fa encode yes.fap --bap yes.bap -o yes.fba   # face + body',
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("input", nargs="?", default=speech.NO_INPUT,
                   help="a .fap, .bap or .fba file, a text file, tagged text, @FILE or - (text from standard "
                        "input); left out with --speech REC.wav --transcript TEXT")
    p.add_argument("-o", "--output", type=Path, required=True, help="the .fba stream to write")
    p.add_argument("--bap", type=Path, metavar="FILE",
                   help="with a .fap INPUT: the .bap file of its body animation, frames matched by frame number")
    coding_flags(p)
    p.defer(speech.text_encoding_options)  # the speech layer only when encode runs (or --help)
    p.set_defaults(run=run_encode)

    p = commands.add_parser("validate", help="check that a .fba stream decodes to its end code",
                            description="Exit status 0 when the stream is valid; 1 with one line naming the "
                                        "error and its bit offset when it is not. With --semantic (a .fba or "
                                        ".fap), also what the values mean: one line per finding (frame, FAP, "
                                        "rule), then a summary; exit 1 only for error findings.")
    p.add_argument("stream", type=Path)
    p.add_argument("--json", action="store_true", help="print the result as JSON")
    p.add_argument("--semantic", action="store_true",
                   help="also check values, FAP 1/2 fields, masks, time and frame rate "
                        "(rules: mpeg4fa/conformance/semantic.py)")
    p.set_defaults(run=run_validate)

    p = commands.add_parser("demo", help="encode a built-in synthetic FAP sequence and show what it holds",
                            description="Write a 4-second synthetic talking stream (FAP 1, FAP 2 and ten "
                                        "low-level FAPs), decode it back and print its summary.")
    p.add_argument("-o", "--output", type=Path, default=Path("demo.fba"), help="where to write it (demo.fba)")
    p.set_defaults(run=run_demo)


def run_info(args: argparse.Namespace) -> int:
    if args.trace:
        return tracing.run_trace(args)
    if args.frames is not None:
        raise UsageError("--frames limits a trace", hint="add --trace")
    stream, kind = read_stream(args.stream)
    info = _info(args.stream, kind, stream, os.path.getsize(args.stream) if kind == "fba" else None)
    if args.json:
        json.dump(info, sys.stdout, indent=2)
        print()
    else:
        print(_as_text(info))
    return 0


def _info(path: str | os.PathLike, kind: str, stream, n_bytes: int | None) -> dict:
    """What ``info`` shows of a stream (``n_bytes``: the size of its bitstream, None for text)."""
    return {"file": str(path), "format": kind, **describe(stream, n_bytes)}


def _as_text(info: dict) -> str:
    lines = []
    for key, value in info.items():
        if isinstance(value, dict):
            value = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in value.items())
        elif key == "intra_frames":  # a count, then where: "1 (frame 0)", not a bare "0" that reads as none
            value = f"{len(value)} (frame{'s' * (len(value) != 1)} {_ranges(value)})" if value else "0"
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
    body_only = args.bap_only or args.output.suffix.lower() == ".bap"
    if body_only and args.bap is not None:
        raise UsageError("--bap names the body file beside a .fap; with a .bap -o (or --bap-only) -o is the body file",
                         hint="drop --bap")
    bap_path = args.output if body_only else (args.bap or args.output.with_suffix(".bap"))
    refuse_overlaps({"input": args.input}, {"-o": args.output, "--bap": None if body_only else bap_path})
    stream = decode(args.input)
    face, body = split_face_body(stream)
    if body_only or not has_face(stream):
        if not has_body(stream):
            raise UsageError(f"{args.input} carries no body animation (BAPs): there is nothing for a .bap file",
                             hint="write its FAPs with -o OUT.fap")
        if not body_only:
            raise UsageError(f"{args.input} is body animation only (BAPs, no FAPs): there is nothing for a .fap file",
                             hint=f"write it with -o {args.output.with_suffix('.bap')} (or --bap-only)")
        with atomic_output(args.output) as partial:
            write_bap(body, partial, name=args.output.name)
        written = f"{args.output} (body)"
    elif has_body(stream):
        if args.bap is None and (args.output.is_symlink() or (args.output.exists() and not args.output.is_file())):
            raise UsageError(f"-o {args.output} is a link or not a plain file: where its .bap would go is unclear",
                             hint="name the body file with --bap FILE")
        with atomic_outputs(args.output, bap_path) as (fap_partial, bap_partial):
            write_fap(face, fap_partial, name=args.output.name)
            write_bap(body, bap_partial, name=bap_path.name)
        written = f"{args.output} (face) and {bap_path} (body)"
    else:
        if args.bap is not None:
            raise UsageError(f"{args.input} carries no body animation (BAPs): there is nothing for --bap",
                             hint="drop --bap")
        with atomic_output(args.output) as partial:
            write_fap(face, partial, name=args.output.name)
        written = str(args.output)
    print(f"{args.input} -> {written}: {len(stream)} frames at {stream.fps:g} fps", file=sys.stderr)
    return 0


def is_stream_file(path: Path) -> bool:
    """Whether an encode INPUT file is a .fba/.fap/.bap stream (else it holds text to speak)."""
    return path.suffix.lower() in (".fap", ".bap", ".fba") or sniff(path) == "fba"


def run_encode(args: argparse.Namespace) -> int:
    source = text_input.classify(args.input, as_text=args.as_text)
    if source.path is None or source.argument.startswith("@") or not is_stream_file(source.path):
        if args.bap is not None:
            raise UsageError("--bap joins a .bap body file to a .fap INPUT, not to text",
                             hint="encode the text to .fba, decode it to .fap, then encode that with --bap")
        return speech.run_encode_text(args, source)
    speech.reject_text_options(args)
    refuse_overlaps({"input": source.path, "--bap": args.bap}, {"-o": args.output})
    stream, kind = read_stream(source.path)
    if args.bap is not None:
        if kind != "fap":
            raise UsageError(f"--bap joins a .bap body file to a .fap INPUT, and {args.input} is a .{kind} file",
                             hint="give the .fap file as INPUT" if kind == "bap" else "drop --bap")
        stream = merge_face_body(stream, read_bap(args.bap), body_label=str(args.bap))
    options = coding_options(args, EncodeOptions() if kind in ("fap", "bap") else None)
    data = encode(stream, options)
    with atomic_output(args.output) as partial:
        partial.write_bytes(data)
    print(f"{args.input} -> {args.output}: {len(stream)} frames, {len(data)} bytes", file=sys.stderr)
    return 0


def run_validate(args: argparse.Namespace) -> int:
    if args.semantic:
        return _run_validate_semantic(args)
    try:
        stream = decode(args.stream)
    except FbaError as exc:
        if not os.path.isfile(args.stream):  # no stream to judge: an error line, not "invalid" (and the name twice)
            raise
        result = {"valid": False, "error": exc.message, "bit_offset": exc.bit_offset, "frame": exc.frame,
                  "frames_decoded": len(exc.partial) if exc.partial is not None else 0}
        print(json.dumps(result) if args.json else f"{args.stream}: invalid: {exc}")
        return 1
    result = {"valid": True, "frames": len(stream), "fps": stream.fps}
    print(json.dumps(result) if args.json else f"{args.stream}: valid: {len(stream)} frames at {stream.fps:g} fps")
    return 0


def _run_validate_semantic(args: argparse.Namespace) -> int:
    """Syntax as without --semantic (a .fap through its reader), then the semantic findings."""
    from ..conformance.semantic import semantic_findings, summary

    try:
        stream, kind = read_stream(args.stream)
    except FbaError as exc:
        if not os.path.isfile(args.stream):
            raise
        result = {"valid": False, "error": exc.message, "bit_offset": exc.bit_offset, "frame": exc.frame,
                  "frames_decoded": len(exc.partial) if exc.partial is not None else 0}
        print(json.dumps(result) if args.json else f"{args.stream}: invalid: {exc}")
        return 1
    findings = semantic_findings(stream)
    counts = summary(findings)
    if args.json:
        print(json.dumps({"valid": True, "format": kind, "frames": len(stream), "fps": stream.fps,
                          "semantic": counts, "findings": [f.as_dict() for f in findings]}))
    else:
        for finding in findings:
            print(finding.line(str(args.stream)))
        said = ", ".join(f"{n} {severity}{'s' * (n != 1 and severity != 'info')}" for severity, n in counts.items())
        print(f"{args.stream}: valid syntax, {len(stream)} frames at {stream.fps:g} fps; semantic: {said}")
    return 1 if counts["error"] else 0


def run_demo(args: argparse.Namespace) -> int:
    data = encode(demo_stream(), EncodeOptions(fap_quant=1))
    with atomic_output(args.output) as partial:
        partial.write_bytes(data)
    print(f"wrote {args.output}\n")
    # what it holds, from the bytes written (the output may be a device: /dev/null reads back empty)
    print(_as_text(_info(args.output, "fba", decode(data), len(data))))
    return 0
