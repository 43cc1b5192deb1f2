"""``mpeg4fa say`` and ``mpeg4fa encode TEXT``: tagged text -> speech, FAPs, and the face saying it; with
``--speech REC.wav --transcript TEXT``, the same for a recording (its transcript aligned to it)."""
from __future__ import annotations

import argparse
import contextlib
import sys
from pathlib import Path

from ..atomic import atomic_outputs
from . import options, text_input
from .coding import coding_options
from .errors import UsageError, located
from .media import check_frames_output, rendering
from .options import Commands
from .paths import refuse_overlaps


def register(commands: Commands) -> None:
    from ..speech.encoder import LEVELS

    p = commands.add_parser(
        "say", help="speak tagged text and render the face saying it (MP4 with audio)",
        description="Speak TEXT with espeak-ng (phonemes with sample-exact times), turn phonemes into "
                    "visemes (English: the 14 MPEG-4 visemes; Chinese: 15 visemes from pinyin; any other "
                    "espeak-ng language, --lang CODE: the 14 MPEG-4 visemes from IPA features) and tags "
                    "like (joy, 40, 0.5) into expressions with Hermite transitions, encode the FAPs as an "
                    "FBA stream, decode it again and render the default head with the speech. TEXT may be "
                    "a text file, '-' (read standard input) or @FILE (read a UTF-8 text file); a TEXT that "
                    "looks like a file name (a path separator or an extension, no spaces) must name a "
                    "readable file, unless --text says it is text. With --speech REC.wav --transcript TEXT the face says a "
                    "recording instead: the transcript is phonemised, aligned to the recording (pocketsphinx for "
                    "English, DTW against espeak-ng's rendering for other languages) and the video plays the "
                    "recording's audio. With --speech REC.wav alone the speech is recognised from the audio "
                    "(--recognizer: English words, phones in any language, or either), in any language; silence, "
                    "noise and music keep the mouth "
                    "at rest.",
        epilog='examples:\n  mpeg4fa say "(joy, 40, 0.5) Hello there! (sadness, 30, 1) Goodbye." -o hello.mp4\n'
               '  mpeg4fa say "(joy, 30, 0.5)你好，世界！" -o nihao.mp4 --keep\n'
               '  mpeg4fa say "Buenos días, ¿cómo estás?" --lang es -o hola.mp4\n'
               '  mpeg4fa say script.txt -o script.mp4\n'
               '  mpeg4fa say --photo me.jpg "Hello, it is me." -o me.mp4\n'
               '  mpeg4fa say --speech me.wav --transcript "(joy, 30, 0.5) Hello there!" -o me.mp4\n'
               '  mpeg4fa say --speech clip.wav -o clip.mp4 --expression joy=30',
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("text", nargs="?", help="the text with optional (expression, intensity 0-63, seconds) tags; a text "
                                           "file, - or @FILE (or --speech REC.wav --transcript TEXT)")
    p.add_argument("-o", "--output", type=Path, required=True, help="OUT.mp4, or a folder for PNG frames")
    text_flag(p)
    recording_options(p)
    speech_options(p)
    p.add_argument("--fps", type=options.fps, default=25.0, help="frame rate, 0 < fps < 256 (default 25)")
    p.add_argument("--level", choices=LEVELS, default="low",
                   help="FAPs in the stream it renders: low (FAPs 3-68, the timeline's exact curves with idle "
                        "motion; default here: say renders the stream itself, so its ~4x bit rate costs nothing), "
                        "high (FAP 1 visemes and FAP 2 expressions, each decoder animating them its own way: "
                        "encode's default, for streams sent elsewhere) or both")
    p.add_argument("--size", type=options.size, default=(512, 512), metavar="W[xH]",
                   help="image size, 16 to 8192 (default 512; even for MP4)")
    p.add_argument("--aa", type=options.samples, default=4, metavar="N",
                   help="anti-aliasing samples: 0 (off), 1, 2, 4 (default), 8 or 16")
    p.add_argument("--photo", type=Path, metavar="IMAGE",
                   help="say it with the face in this photo: its feature points found (the 'photo' extra), the head "
                        "calibrated to them and wearing the photo, as 'mpeg4fa fdp' makes it")
    p.add_argument("--keep", action="store_true",
                   help="also write OUT.fba, OUT.wav and OUT.timings.json beside it")
    p.set_defaults(run=run_say)

    p = commands.add_parser(
        "voices", help="list espeak-ng's voices and language codes (what --lang and --voice take)",
        description="List the installed espeak-ng voices: the language code (give it to --lang or --voice), "
                    "the voice's name and every code it answers to (voices whose dictionary is not installed are left "
                    "out, and named on stderr). English (en, en-*) and Mandarin (zh) "
                    "map phonemes through their own tables; every other language through IPA features "
                    "(spec/ipa_*.csv).")
    p.add_argument("--json", action="store_true",
                   help='print a JSON list: [{"language", "name", "identifier", "languages", "dictionary", "visemes"}, '
                        '...] of the voices that can speak here')
    p.set_defaults(run=run_voices)


def run_voices(args: argparse.Namespace) -> int:
    """``mpeg4fa voices``: :func:`mpeg4fa.speech.tts.espeak.voices`, as a table or JSON."""
    import json

    from ..speech.tts.espeak import voices

    rows = []
    mute = [v for v in voices() if not v.speaks]  # espeak-ng lists them, but their dictionary is not installed
    for v in voices(speaking=True):
        entry = v.as_dict()
        entry["visemes"] = _viseme_route(v.language)
        rows.append(entry)
    left_out = (f"left out: {', '.join(v.language for v in mute)} (espeak-ng has no dictionary for "
                f"{'them' if len(mute) > 1 else 'it'} in this installation)") if mute else ""
    if args.json:
        print(json.dumps(rows, ensure_ascii=False, indent=1))
        if left_out:
            print(left_out, file=sys.stderr)
        return 0
    width = max((len(r["language"]) for r in rows), default=4)
    for r in rows:
        others = [c for c in r["languages"] if c != r["language"]]
        also = f"  (also {', '.join(others)})" if others else ""
        print(f"{r['language']:<{width}}  {r['name']}{also}  [{r['visemes']}]")
    print(f"{len(rows)} voices; --lang takes any code above, or auto, en, zh" + (f"; {left_out}" if left_out else ""),
          file=sys.stderr)
    return 0


def _viseme_route(code: str) -> str:
    """How ``--lang CODE`` maps phonemes to visemes."""
    if code == "en" or code.startswith("en-"):
        return "English table"
    return "IPA features"


def text_flag(p: argparse.ArgumentParser) -> None:
    """``--text``: the positional argument is the text itself, even when it looks like a file name."""
    p.add_argument("--text", dest="as_text", action="store_true",
                   help="take the argument as the text to speak, even if it looks like a file name")


def text_encoding_options(p: argparse.ArgumentParser) -> None:
    """The options of ``encode`` when INPUT is text (speech, FAP timeline, FDP of the speaker), or when a
    recording and its transcript stand in for it (INPUT is then left out: :data:`NO_INPUT`)."""
    from ..speech.encoder import LEVELS

    text_flag(p)
    from .video_input import video_options
    added = recording_options(p) + viseme_event_options(p) + video_options(p)
    g = p.add_argument_group("text input: speech and FAPs")
    added += [g.add_argument("--audio", type=Path, metavar="WAV", help="write the speech here (16-bit mono WAV)"),
             g.add_argument("--timings", type=Path, metavar="JSON",
                            help='write the timed visemes used: [{"phoneme", "viseme", "start", "end"}, ...] in '
                                 'seconds')]
    added += speech_options(g)
    added.append(g.add_argument(
        "--level", choices=LEVELS, default="high",
        help="FAPs to send: high (FAP 1 visemes + FAP 2 expressions; Chinese visemes and other expressions as "
             "low-level FAPs; default: ~4x fewer bits than low, for a stream sent to other decoders), low (FAPs "
             "3-68, the timeline's exact curves with idle motion: say's default, as it renders them itself) or both"))
    g = p.add_argument_group("text input: the speaker's face (FDP)")
    added += [
        g.add_argument("--fdp-out", type=Path, metavar="FDP",
                       help="write an FDP describing the face (.fdp binary, or .json): the default head unless "
                            "--face-mesh or --front/--side say otherwise"),
        g.add_argument("--face-mesh", type=Path, metavar="OBJ", help="the speaker's face mesh (Wavefront OBJ)"),
        g.add_argument("--face-points", type=Path, metavar="JSON",
                       help="its feature points: JSON label -> vertex index or [x, y, z]"),
        g.add_argument("--front", type=Path, metavar="IMAGE",
                       help="a front photo of the speaker (sent as the texture)"),
        g.add_argument("--front-points", type=Path, metavar="JSON",
                       help="the front photo's feature points, label -> [x, y] (optional: without them the face is "
                            "found in the photo; given points win over found ones)"),
        g.add_argument("--side", type=Path, metavar="IMAGE",
                       help="a side photo of the speaker (with --side-points: a profile; without: turned 20-60 "
                            "degrees, its face found)"),
        g.add_argument("--side-points", type=Path, metavar="JSON",
                       help="the side photo's feature points, label -> [x, y]"),
        g.add_argument("--side-view", choices=("left", "right"), default="left",
                       help="which side of the face the side photo shows (default left)"),
    ]
    # what these options default to, so that a stream INPUT can tell which of them were given
    p.set_defaults(text_defaults={action.dest: action.default for action in added})


NO_INPUT = ""
"""What ``encode``'s INPUT holds when it is left out (with ``--speech``, the transcript is the text)."""


def viseme_event_options(p: argparse.ArgumentParser) -> list[argparse.Action]:
    """``--visemes EVENTS.json`` and ``--format``: a cloud TTS's viseme events to encode instead of text."""
    from ..speech.viseme_events import FORMATS

    g = p.add_argument_group("viseme events: a cloud TTS's visemes as the stream",
                             "Azure Speech VisemeReceived events or Amazon Polly viseme speech marks, encoded with "
                             "the same transitions as text (no audio: the stream goes with the TTS's own)")
    return [
        g.add_argument("--visemes", type=Path, metavar="EVENTS.json",
                       help='Azure events [{"AudioOffset": ticks, "VisemeId": 0-21}, ...] or Polly speech marks '
                            '(JSON lines {"time": ms, "type": "viseme", "value": "p"})'),
        g.add_argument("--format", dest="events_format", choices=FORMATS, default="auto",
                       help="with --visemes: which of the two the file holds (default auto: by its keys)"),
    ]


def _encode_visemes(args: argparse.Namespace) -> int:
    """``mpeg4fa encode --visemes EVENTS.json``: Azure/Polly viseme events -> FAP stream (+ timings, FDP)."""
    from ..fba import EncodeOptions
    from ..speech.encoder import TEXT_CODING
    from ..speech.viseme_events import read_viseme_events, stream_viseme_events

    clash = [flag for flag, given in (("INPUT", args.input != NO_INPUT), ("--speech", args.speech is not None),
                                      ("--audio", args.audio is not None)) if given]
    if clash:
        raise UsageError(f"--visemes encodes the events alone, so {', '.join(clash)} has no place beside it",
                         hint="drop " + ", ".join(clash) + " (the TTS's audio goes with the stream as it is)")
    inputs = {"--visemes": args.visemes, "--face-mesh": args.face_mesh, "--face-points": args.face_points,
              "--front": args.front, "--front-points": args.front_points, "--side": args.side,
              "--side-points": args.side_points}
    refuse_overlaps(inputs, {"-o": args.output, "--timings": args.timings, "--fdp-out": args.fdp_out})
    fdp = _speaker_fdp(args) if args.fdp_out is not None else None
    kind, events = read_viseme_events(args.visemes, args.events_format)
    fps = args.fps if args.fps is not None else 25.0
    print(f"{args.visemes}: {len(events)} {kind} viseme events", file=sys.stderr)
    options = coding_options(args, EncodeOptions(**TEXT_CODING))
    with atomic_outputs(args.output, args.timings, args.fdp_out) as (out, timings, fdp_out):
        with contextlib.ExitStack() as files:  # coded block by block as it is written (memory of a block)
            spoken = stream_viseme_events(
                events, files.enter_context(open(out, "wb")),
                timings=files.enter_context(open(timings, "w", encoding="utf-8")) if timings is not None else None,
                engine=kind, fps=fps, level=args.level, idle=args.idle, options=options, name=str(args.visemes))
        if fdp is not None:
            from ..fdp import save_fdp
            save_fdp(fdp, fdp_out)
    written = [f"{args.output} ({spoken.bytes} bytes)"] + ([str(args.timings)] if args.timings is not None else [])
    if fdp is not None:
        written.append(f"{args.fdp_out} ({len(fdp.labels)} feature points)")
    frames = spoken.frames
    print(f"{args.visemes}: {spoken.engine} speech {spoken.seconds:.2f} s, {frames} frames, "
          f"{spoken.bytes * 8 / max(frames, 1):.1f} bits/frame "
          f"({spoken.bytes * 8 / max(frames / fps, 1e-9) / 1000:.2f} kbit/s, {args.level}-level)", file=sys.stderr)
    print("wrote " + ", ".join(written), file=sys.stderr)
    return 0


def recording_options(p: argparse.ArgumentParser) -> list[argparse.Action]:
    """``--speech``, ``--transcript``, ``--aligner``, ``--no-fit-check``, and without a transcript
    ``--recognizer``, ``--expression``, ``--pcm-rate``: a recording to animate instead of text to speak."""
    from ..speech.align import METHODS
    from ..speech.listen import ENGLISH_DEFAULT, RECOGNIZERS
    from ..speech.listen.stream import RAW_FORMAT, RAW_RATE

    g = p.add_argument_group("recorded speech: lip sync to a recording",
                             "with --transcript, the transcript is phonemised by espeak-ng and aligned to the "
                             "recording (--lang, --voice and --rate then describe espeak-ng's reference rendering); "
                             "without one, the speech is recognised from the audio alone (--recognizer), silence, "
                             "breath, noise and music leaving the mouth at rest")
    return [
        g.add_argument("--speech", type=Path, metavar="REC.wav",
                       help="a recording (WAV any rate and channel count, or MP3/FLAC/Ogg/M4A); '-' reads raw PCM "
                            f"from standard input: {RAW_FORMAT}, at --pcm-rate Hz (default {RAW_RATE})"),
        g.add_argument("--transcript", metavar="TEXT|FILE",
                       help="what the recording says, with optional expression tags; a text file, - or @FILE "
                            "(optional: without it the speech is recognised)"),
        g.add_argument("--aligner", choices=METHODS, default="auto",
                       help="auto (default: pocketsphinx for English, else dtw), pocketsphinx (English) or dtw "
                            "(any language: warping against espeak-ng's rendering)"),
        g.add_argument("--no-fit-check", dest="fit_check", action="store_false",
                       help="align even when pocketsphinx finds the transcript's words are not what the "
                            "recording says (its acoustic fit below the limit)"),
        g.add_argument("--recognizer", choices=RECOGNIZERS, default="auto",
                       help="without --transcript: words (English words heard by pocketsphinx, then aligned as a "
                            "transcript; written into --timings: best on recordings of people), phonetic (phones "
                            "heard, any language, mapped by their IPA features: best on synthetic voices), either "
                            "(English: both listen, and the words are taken where they explain the audio nearly as "
                            "well as the phones do, else the phones; slower) or auto (default: "
                            f"{ENGLISH_DEFAULT} for English, phonetic for other languages)"),
        g.add_argument("--expression", metavar="NAME=INTENSITY", type=_expression,
                       help="without --transcript: one expression for the whole clip, e.g. joy=30 (intensity 0-63; "
                            "with a transcript, tags in it say when)"),
        g.add_argument("--pcm-rate", type=int, default=RAW_RATE, metavar="HZ",
                       help=f"sample rate of raw PCM read with --speech - (default {RAW_RATE}; --rate is the speech "
                            "rate of a transcript's reference)"),
    ]


def _expression(text: str) -> tuple[str, int]:
    """``NAME=INTENSITY`` -> (name, intensity), checked against the expressions of the standard."""
    from ..spec import EXPRESSIONS

    names = [e.name for e in EXPRESSIONS]
    name, eq, value = text.partition("=")
    if not eq or name.strip() not in names:
        raise argparse.ArgumentTypeError(f"{text!r}: give NAME=INTENSITY, NAME one of {', '.join(names)}")
    try:
        intensity = int(value)
    except ValueError:
        intensity = -1
    from mpeg4fa.spec import FULL_INTENSITY

    if not 0 <= intensity <= FULL_INTENSITY:
        raise argparse.ArgumentTypeError(f"{text!r}: the intensity is a whole number from 0 to {FULL_INTENSITY}")
    return name.strip(), intensity


def _recording_args(args: argparse.Namespace, given_text: bool, what: str) -> bool:
    """Whether a recording is to be animated; UsageError for options that clash with one (or lack it)."""
    listen_flags = [flag for flag, given in (("--recognizer", args.recognizer != "auto"),
                                             ("--expression", args.expression is not None),
                                             ("--pcm-rate", args.pcm_rate != 16000)) if given]
    if args.speech is None:
        if args.transcript is not None or args.aligner != "auto" or not args.fit_check or listen_flags:
            flag = ("--transcript" if args.transcript is not None else
                    "--aligner" if args.aligner != "auto" else "--no-fit-check" if not args.fit_check else
                    listen_flags[0])
            raise UsageError(f"{flag} goes with --speech REC.wav", hint="add --speech, or drop " + flag)
        return False
    if given_text:
        raise UsageError(f"--speech animates the recording, so {what} has no place beside it",
                         hint="give the text as --transcript and drop " + what)
    if args.engine != "espeak":
        raise UsageError(f"--engine {args.engine} with --speech: the transcript is phonemised by espeak",
                         hint="drop --engine")
    if args.transcript is not None:
        clash = [f for f in listen_flags if f != "--pcm-rate"]
        if clash:
            raise UsageError(f"{clash[0]} is for a recording without a transcript",
                             hint="drop it (with a transcript, its tags give the expressions)")
    else:
        clash = [flag for flag, given in (("--aligner", args.aligner != "auto"), ("--no-fit-check", not args.fit_check),
                                          ("--voice", args.voice is not None), ("--rate", args.rate is not None))
                 if given]
        if clash:
            raise UsageError(f"{clash[0]} goes with --transcript (espeak-ng's reference for the alignment)",
                             hint=f"add --transcript, or drop {clash[0]}")
        from ..speech.listen.core import check_language

        check_language(args.recognizer, args.lang)  # before anything is read: exit 1, one line
    if args.pcm_rate != 16000 and str(args.speech) != "-":
        raise UsageError("--pcm-rate is the rate of raw PCM from standard input (--speech -)",
                         hint="drop --pcm-rate: a WAV file says its own rate")
    return True


def _listen_source(args: argparse.Namespace):
    """The recording to hear: raw PCM from standard input, or the file."""
    from ..speech.listen.stream import raw_source, wav_source

    if str(args.speech) == "-":
        return raw_source(sys.stdin.buffer, args.pcm_rate)
    return wav_source(args.speech)


def _heard_line(name: str, heard) -> str:
    """What was heard, in one line (the words, or that it is silent)."""
    if heard.silent:
        return f"{name}: no speech heard (silent, or only noise or music): the mouth stays closed"
    said = f"{name}: {heard.voiced:.1f} s of speech heard by the {heard.recognizer} recogniser"
    if heard.recognizer == "words":
        count = heard.words if isinstance(heard.words, int) else len(heard.words)
        said += f": {count} words recognised (no transcript), written into --timings when given"
    return said


def _aligned(args: argparse.Namespace, inputs: dict, outputs: dict):
    """The transcript read (text, file, - or @FILE) and aligned to the recording: (Alignment, transcript name).
    No output may overwrite ``inputs``, the recording or the transcript file."""
    from ..speech.align import align_recording
    from ..speech.markup import parse_markup

    source = text_input.classify(args.transcript, as_text=args.as_text)
    from_stdin = str(args.speech) == "-"
    if from_stdin and source.stdin:
        raise UsageError("--speech - and --transcript - both read standard input",
                         hint="give the transcript as text or as a file")
    refuse_overlaps({**inputs, **({} if from_stdin else {"--speech": args.speech}), "--transcript": source.path},
                    outputs)
    text, name = text_input.read_text(source)
    transcript = parse_markup(text, name=name, lenient=args.lenient) if args.lenient else text
    recording = _stdin_recording(args) if from_stdin else args.speech
    return align_recording(recording, transcript, lang=args.lang, voice=args.voice, rate=args.rate,
                           method=args.aligner, name=name, fit_check=args.fit_check), name


def _speech_name(args: argparse.Namespace) -> str:
    """The recording as messages name it: its file, or ``<stdin>`` for ``--speech -``."""
    return "<stdin>" if str(args.speech) == "-" else str(args.speech)


def _stdin_recording(args: argparse.Namespace):
    """Raw PCM from standard input (``--speech -``, at ``--pcm-rate``) as one recording: an alignment hears the
    whole of it at once, as it does a file (at most the speech encoder's 30 min: bounded memory)."""
    from ..speech.listen.stream import recording_of

    return recording_of(_listen_source(args))


def speech_options(g) -> list[argparse.Action]:
    """Engine, language, voice, rate and idle motion: shared by ``encode`` (text) and ``say``; the actions added."""
    from ..speech.encoder import ENGINES

    return [
        g.add_argument("--engine", choices=ENGINES, default="espeak",
                       help="espeak (phoneme times; default), pyttsx3 (word boundaries, visemes estimated in "
                            "between) or estimate (no audio: word times from a duration model)"),
        g.add_argument("--lang", default="auto", metavar="auto|en|zh|CODE",
                       help="language: auto (default: by script: Latin English, Han Mandarin, Cyrillic ru, "
                            "Arabic ar, Devanagari hi, kana ja), en, zh, or any espeak-ng language code (es, fr, "
                            "de, yue...: 'mpeg4fa voices' lists them; visemes from IPA features)"),
        g.add_argument("--voice", help="under auto, the English voice for Latin text (default en-us); with "
                                       "--lang CODE, the voice for all of it (default: CODE)"),
        g.add_argument("--rate", type=options.speech_rate, help="speech rate in words per minute, 80 to 450 "
                                                                "(default 175)"),
        g.add_argument("--idle", action="store_true", help="add blinks and small head motion"),
        g.add_argument("--lenient", action="store_true",
                       help="speak a malformed tag, like (joy 40 0.5), as text with one warning, instead of "
                            "stopping at it with its line and column"),
    ]


def reject_text_options(args: argparse.Namespace) -> None:
    """A stream INPUT with text-only options is a mistake worth one clear line."""
    given = [name for name, default in args.text_defaults.items() if getattr(args, name) != default]
    if given:
        flags = ", ".join("--" + name.replace("_", "-") for name in given)
        raise UsageError(f"{flags} apply to text input, but {args.input} is a stream file",
                         hint="drop them, or pass the text itself")


def run_encode_text(args: argparse.Namespace, source: text_input.TextArgument) -> int:
    """``mpeg4fa encode TEXT``: speech -> FAP stream (+ WAV, timings, FDP), all written or none."""
    if args.video is not None:
        from .video_input import encode_video
        return encode_video(args, args.input != NO_INPUT)
    if args.visemes is not None:
        return _encode_visemes(args)
    if args.events_format != "auto":
        raise UsageError("--format says what a --visemes file holds", hint="add --visemes EVENTS.json, or drop --format")
    if _recording_args(args, args.input != NO_INPUT, f"INPUT ({args.input})"):
        return _encode_recording(args)
    if args.input == NO_INPUT:
        raise UsageError("INPUT missing: give the text to speak (or a .fap/.fba stream)",
                         hint='or --speech REC.wav --transcript "TEXT" to animate a recording, '
                              'or --visemes EVENTS.json for a cloud TTS\'s visemes')
    if args.engine == "estimate" and args.audio is not None:
        raise UsageError("the estimate engine makes no audio, so there is nothing for --audio",
                         hint="drop --audio, or use --engine espeak or pyttsx3")
    refuse_overlaps({"input": source.path, "--face-mesh": args.face_mesh, "--face-points": args.face_points,
                     "--front": args.front, "--front-points": args.front_points, "--side": args.side,
                     "--side-points": args.side_points},
                    {"-o": args.output, "--audio": args.audio, "--timings": args.timings, "--fdp-out": args.fdp_out})
    fdp = _speaker_fdp(args) if args.fdp_out is not None else None
    text, name = text_input.read_text(source)
    fps = args.fps if args.fps is not None else 25.0
    return _stream_encoded(args, text, name, fps, fdp)


def _stream_encoded(args: argparse.Namespace, text: str, name: str, fps: float, fdp) -> int:
    """Speak the text chunk by chunk, writing the stream, the WAV and the timings as they come
    (:func:`mpeg4fa.speech.pipeline.stream_text`: memory of a chunk, whatever the text's length), with a
    progress bar; all files appear once it is done, or none."""
    from ..fba import EncodeOptions
    from ..speech.encoder import TEXT_CODING
    from ..speech.pipeline import stream_text
    from .progress import ProgressBar

    options = coding_options(args, EncodeOptions(**TEXT_CODING))
    bar = ProgressBar("speaking", unit="characters")
    try:
        with atomic_outputs(args.output, args.audio, args.timings, args.fdp_out) as (out, audio, timings, fdp_out):
            with contextlib.ExitStack() as files:
                spoken = stream_text(
                    text, files.enter_context(open(out, "wb")),
                    audio=files.enter_context(open(audio, "wb")) if audio is not None else None,
                    timings=files.enter_context(open(timings, "w", encoding="utf-8")) if timings is not None else None,
                    engine=args.engine, lang=args.lang, voice=args.voice, rate=args.rate, fps=fps, level=args.level,
                    idle=args.idle, name=name, options=options, progress=bar, lenient=args.lenient)
            if fdp is not None:
                from ..fdp import save_fdp
                save_fdp(fdp, fdp_out)
    finally:
        bar.close()
    written = [f"{args.output} ({spoken.bytes} bytes)"]
    if args.audio is not None:
        written.append(f"{args.audio} ({spoken.seconds:.2f} s)")
    if args.timings is not None:
        written.append(str(args.timings))
    if fdp is not None:
        written.append(f"{args.fdp_out} ({len(fdp.labels)} feature points)")
    frames = spoken.frames
    print(f"{name}: {spoken.engine} speech {spoken.seconds:.2f} s, {frames} frames, "
          f"{spoken.bytes * 8 / max(frames, 1):.1f} bits/frame "
          f"({spoken.bytes * 8 / max(frames / fps, 1e-9) / 1000:.2f} kbit/s, {args.level}-level), "
          f"made in {spoken.wall:.2f} s for {spoken.seconds:.2f} s of speech", file=sys.stderr)
    print("wrote " + ", ".join(written), file=sys.stderr)
    return 0


def _encode_recording(args: argparse.Namespace) -> int:
    """``mpeg4fa encode --speech REC.wav --transcript TEXT``: the aligned transcript -> FAP stream (+ files)."""
    from ..speech.encoder import encode_utterance

    inputs = {"--face-mesh": args.face_mesh, "--face-points": args.face_points, "--front": args.front,
              "--front-points": args.front_points, "--side": args.side, "--side-points": args.side_points}
    outputs = {"-o": args.output, "--audio": args.audio, "--timings": args.timings, "--fdp-out": args.fdp_out}
    refuse_overlaps({**inputs, **({"--speech": args.speech} if str(args.speech) != "-" else {})}, outputs)
    fdp = _speaker_fdp(args) if args.fdp_out is not None else None
    if args.transcript is None:
        return _encode_listened(args, fdp)
    aligned, name = _aligned(args, inputs, outputs)
    fps = args.fps if args.fps is not None else 25.0
    encoded = encode_utterance(aligned.utterance, fps=fps, level=args.level, idle=args.idle)
    shown = _speech_name(args)
    print(f"{shown}: {name} aligned by {aligned.method} in {aligned.seconds:.2f} s for "
          f"{encoded.speech.duration:.2f} s of audio", file=sys.stderr)
    return _write_encoded(args, encoded, shown, fps, fdp)


def _encode_listened(args: argparse.Namespace, fdp) -> int:
    """``mpeg4fa encode --speech REC.wav`` (no transcript): the speech recognised and encoded block by block
    (:func:`mpeg4fa.speech.listen.stream.stream_listened`: memory of a block, any length), with a progress bar;
    all files appear once it is done, or none."""
    from ..fba import EncodeOptions
    from ..speech.encoder import TEXT_CODING
    from ..speech.listen.stream import stream_listened
    from .progress import ProgressBar

    fps = args.fps if args.fps is not None else 25.0
    source = _listen_source(args)
    bar = ProgressBar("listening", unit="s of audio")
    try:
        with atomic_outputs(args.output, args.audio, args.timings, args.fdp_out) as (out, audio, timings, fdp_out):
            with contextlib.ExitStack() as files:
                heard = stream_listened(
                    source, files.enter_context(open(out, "wb")),
                    audio=files.enter_context(open(audio, "wb")) if audio is not None else None,
                    timings=files.enter_context(open(timings, "w", encoding="utf-8")) if timings is not None else None,
                    recognizer=args.recognizer, lang=args.lang, expression=args.expression, fps=fps,
                    level=args.level, idle=args.idle, options=coding_options(args, EncodeOptions(**TEXT_CODING)),
                    progress=bar if source.seconds is not None else None)  # a pipe's length is unknown
            if fdp is not None:
                from ..fdp import save_fdp
                save_fdp(fdp, fdp_out)
    finally:
        bar.close()
    print(_heard_line(source.name, heard), file=sys.stderr)
    for note in heard.notes:
        print(f"{source.name}: {note}", file=sys.stderr)
    written = [f"{args.output} ({heard.bytes} bytes)"]
    if args.audio is not None:
        written.append(f"{args.audio} ({heard.seconds:.2f} s)")
    if args.timings is not None:
        written.append(str(args.timings))
    if fdp is not None:
        written.append(f"{args.fdp_out} ({len(fdp.labels)} feature points)")
    frames = heard.frames
    print(f"{source.name}: recording {heard.seconds:.2f} s, {frames} frames, "
          f"{heard.bytes * 8 / max(frames, 1):.1f} bits/frame "
          f"({heard.bytes * 8 / max(frames / fps, 1e-9) / 1000:.2f} kbit/s, {args.level}-level), "
          f"heard in {heard.wall:.2f} s ({heard.speed:.1f}x real time)", file=sys.stderr)
    print("wrote " + ", ".join(written), file=sys.stderr)
    return 0


def _write_encoded(args: argparse.Namespace, encoded, name: str, fps: float, fdp) -> int:
    """Write the stream and the files asked for, all or none, and say what was written."""
    from ..fba import encode
    from ..say import write_timings

    data = encode(encoded.stream, coding_options(args, encoded.coding()))
    written = [f"{args.output} ({len(data)} bytes)"]
    with atomic_outputs(args.output, args.audio, args.timings, args.fdp_out) as (out, audio, timings, fdp_out):
        out.write_bytes(data)
        if audio is not None:
            encoded.speech.write_wav(audio)
            written.append(f"{args.audio} ({encoded.speech.duration:.2f} s)")
        if timings is not None:
            write_timings(encoded, timings)
            written.append(str(args.timings))
        if fdp is not None:
            from ..fdp import save_fdp
            save_fdp(fdp, fdp_out)
            written.append(f"{args.fdp_out} ({len(fdp.labels)} feature points)")
    frames = len(encoded.stream)
    seconds = frames / fps
    print(f"{name}: {encoded.speech.engine} speech {encoded.speech.duration:.2f} s, {frames} frames, "
          f"{len(data) * 8 / max(frames, 1):.1f} bits/frame ({len(data) * 8 / max(seconds, 1e-9) / 1000:.2f} kbit/s, "
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
        with located(str(args.face_points)):
            return fdp_io.fdp_from_mesh(mesh, fdp_io.read_points_json(args.face_points), name=args.face_mesh.stem)
    if args.front is not None or args.side is not None:
        if args.side_points is None:  # the face is found in the photo(s); given front points win
            need("front")
            return _photo_fdp(args)
        need("front", "front_points", "side", "side_points")
        with located(f"{args.front_points} + {args.side_points}"):
            return fdp_io.fdp_from_photos(fdp_io.read_points_json(args.front_points),
                                          fdp_io.read_points_json(args.side_points), side_view=args.side_view,
                                          texture=fdp_io.texture_from_file(args.front), name=args.front.stem)
    from ..face import FaceModel
    return FaceModel.default().to_fdp()


def _photo_fdp(args: argparse.Namespace):
    """The FDP of the face found in --front (and --side, turned 20-60 degrees): :func:`mpeg4fa.tracking.fdp_from_photo`."""
    from ..tracking.photo import fdp_from_photo
    from .fdp_photo import photo_points_file, say_notes

    given = photo_points_file(args.front_points) if args.front_points is not None else None
    with located(str(args.front_points or args.front)):
        made = fdp_from_photo(args.front, side=args.side, points=given)
    say_notes(made, str(args.front))
    return made.fdp


def _photo_face(args: argparse.Namespace):
    """(face, texture) of ``say --photo``, or (None, None): the generic head."""
    if args.photo is None:
        return None, None
    from .fdp_photo import photo_face
    return photo_face(args)


def run_say(args: argparse.Namespace) -> int:
    """``mpeg4fa say``: :func:`mpeg4fa.say.say` with a progress bar, after checking what it would write."""
    from ..say import kept_paths, say

    if _recording_args(args, args.text is not None, f"TEXT ({args.text})"):
        return _say_recording(args)
    if args.text is None:
        raise UsageError("TEXT missing: give the text to say", hint='or --speech REC.wav --transcript "TEXT"')
    source = text_input.classify(args.text, as_text=args.as_text)
    kept = kept_paths(args.output) if args.keep else {}
    refuse_overlaps({"text file": source.path, "--photo": args.photo}, {"-o": args.output, **{f"--keep ({what})": path
                                                                        for what, path in kept.items()}})
    check_frames_output("say", args.output, args.size)
    text, name = text_input.read_text(source)
    width, height = args.size
    face, texture = _photo_face(args)
    with rendering("say", args.output) as progress:
        said = say(text, args.output, engine=args.engine, lang=args.lang, voice=args.voice, rate=args.rate,
                   fps=args.fps, level=args.level, idle=args.idle, width=width, height=height, samples=args.aa,
                   keep=args.keep, name=name, progress=progress, lenient=args.lenient, face=face, texture=texture)
    result = said.result
    print(f"{args.output}: {result.n_frames} frames at {result.fps:g} fps ({result.duration:.2f} s), "
          f"{len(said.data) * 8 / max(len(said.stream), 1):.0f} bits/frame of FAPs ({_level_said(args.level)}); "
          f"rendered in {result.seconds:.1f} s" + (f"; kept {', '.join(map(str, said.kept.values()))}"
                                                   if said.kept else ""))
    return 0


def _level_said(level: str) -> str:
    """The level in say's last line, with why when it is say's own default (encode's is high)."""
    if level == "low":
        return "low-level: the exact curves, say's default; --level high sends ~4x fewer bits, as encode does"
    return f"{level}-level"


def _say_recording(args: argparse.Namespace) -> int:
    """``mpeg4fa say --speech REC.wav --transcript TEXT``: the face saying the recording, with its audio
    (:func:`mpeg4fa.say.say_encoded` on the aligned transcript)."""
    from ..say import kept_paths, say_encoded
    from ..speech.encoder import encode_utterance

    kept = kept_paths(args.output) if args.keep else {}
    outputs = {"-o": args.output, **{f"--keep ({what})": path for what, path in kept.items()}}
    refuse_overlaps({**({"--speech": args.speech} if str(args.speech) != "-" else {}), "--photo": args.photo}, outputs)
    check_frames_output("say", args.output, args.size)
    if args.transcript is None:
        from ..speech.listen.stream import listened_whole

        source = _listen_source(args)
        heard = listened_whole(source, recognizer=args.recognizer, lang=args.lang, expression=args.expression)
        encoded = encode_utterance(heard.utterance, fps=args.fps, level=args.level, idle=args.idle)
        print(_heard_line(source.name, heard), file=sys.stderr)
        for note in heard.notes:
            print(f"{source.name}: {note}", file=sys.stderr)
        how = f"{heard.recognizer} recogniser, no transcript"
    else:
        aligned, name = _aligned(args, {}, outputs)
        encoded = encode_utterance(aligned.utterance, fps=args.fps, level=args.level, idle=args.idle)
        how = f"{name} aligned by {aligned.method}"
    width, height = args.size
    face, texture = _photo_face(args)
    with rendering("say", args.output) as progress:
        said = say_encoded(encoded, args.output, width=width, height=height, samples=args.aa, keep=args.keep,
                           progress=progress, face=face, texture=texture)
    result, data, stream, kept = said.result, said.data, said.stream, said.kept
    print(f"{args.output}: {result.n_frames} frames at {result.fps:g} fps ({result.duration:.2f} s) of "
          f"{_speech_name(args)} "
          f"({how}), {len(data) * 8 / max(len(stream), 1):.0f} bits/frame of FAPs "
          f"({_level_said(args.level)}); rendered in {result.seconds:.1f} s"
          + (f"; kept {', '.join(map(str, kept.values()))}" if kept else ""))
    return 0
