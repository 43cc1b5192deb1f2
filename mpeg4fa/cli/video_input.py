"""``mpeg4fa encode --video talk.mp4 -o talk.fba``: a face video -> the FBA stream of its motion (+ its sound as
WAV, + the FDP of its neutral face); a thin shell over :func:`mpeg4fa.tracking.track_video`."""
from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

from ..atomic import atomic_outputs
from .coding import coding_options
from .errors import UsageError
from .paths import refuse_overlaps


def video_options(p: argparse.ArgumentParser) -> list[argparse.Action]:
    """``--video`` and ``--neutral``: a face video to track instead of text to speak."""
    g = p.add_argument_group(
        "video input: a face's motion tracked into FAPs",
        "every frame tracked (MediaPipe Face Mesh), FAPs from the feature points' displacements from the neutral "
        "face over its FAPU: jaw, lips, lip corners, cheeks, brows, lids and blinks, gaze, head turns; the video's "
        "sound goes beside the stream as WAV (--audio, default the -o name with .wav)")
    return [
        g.add_argument("--video", type=Path, metavar="VIDEO",
                       help="a video of one face, seen from the front (MP4, MOV, MKV, WebM, AVI...)"),
        g.add_argument("--neutral", type=neutral_option, metavar="SECONDS|FRAME",
                       help="where the face is neutral: a frame number (e.g. 12) or a time with a decimal point or "
                            "s (e.g. 0.5 or 2s); default: the calmest stretch of the first 3 s, said in the output"),
    ]


def neutral_option(text: str) -> int | float:
    """``--neutral``: an int is a frame, a number with '.' or a trailing 's' is seconds."""
    word = text.strip().lower()
    try:
        if word.endswith("s"):
            value: int | float = float(word[:-1])
        elif "." in word or "e" in word:
            value = float(word)
        else:
            value = int(word)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is neither a frame number nor a time in seconds") from None
    if not value >= 0 or value != value or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r}: the neutral must be a frame or a time >= 0")
    return value


def encode_video(args: argparse.Namespace, given_text: bool) -> int:
    """Track the video, write the stream, the WAV and the FDP all or none, and say what was written."""
    from ..fba import EncodeOptions, encode
    from ..speech.encoder import TEXT_CODING
    from ..tracking import TrackingWarning, track_video
    from ..tracking.video import probe_video
    from .progress import ProgressBar

    clash = [flag for flag, given in (("INPUT", given_text), ("--speech", args.speech is not None),
                                      ("--visemes", args.visemes is not None), ("--timings", args.timings is not None),
                                      ("--face-mesh", args.face_mesh is not None), ("--front", args.front is not None),
                                      ("--side", args.side is not None)) if given]
    if clash:
        raise UsageError(f"--video encodes the face in the video, so {', '.join(clash)} has no place beside it",
                         hint="drop " + ", ".join(clash))
    info = probe_video(args.video)
    audio = args.audio if args.audio is not None else (args.output.with_suffix(".wav") if info.has_audio else None)
    refuse_overlaps({"--video": args.video}, {"-o": args.output, "--audio": audio, "--fdp-out": args.fdp_out})
    if not info.has_audio:
        if args.audio is not None:
            raise UsageError(f"--audio {args.audio}: {args.video} has no sound track to write", hint="drop --audio")
    bar = ProgressBar("tracking")
    try:
        tracked = track_video(args.video, fps=args.fps, neutral=args.neutral, progress=bar)
    finally:
        bar.close()
    summary, stream = tracked.summary, tracked.stream
    print(f"{args.video}: {summary.neutral.describe(summary.fps)}", file=sys.stderr)
    if not info.has_audio:
        print(f"{args.video}: no sound track, so no WAV is written", file=sys.stderr)
    if summary.lost:
        warnings.warn(f"{args.video}: the face was lost in {summary.lost} of {summary.frames} frames; they hold the "
                      f"last values", TrackingWarning)
    data = encode(stream, coding_options(args, EncodeOptions(**TEXT_CODING)))
    fdp = picture = None
    if args.fdp_out is not None:  # the neutral is a frame of the stream (at --fps); the picture, the video's frame
        picture, fdp = _neutral_fdp(args, summary.neutral.first / summary.fps)  # on screen then
    sound = None
    if audio is not None:
        from ..render.audio import read_audio
        sound = read_audio(args.video)
    written = [f"{args.output} ({len(data)} bytes)"]
    with atomic_outputs(args.output, audio, args.fdp_out) as (out, wav, fdp_out):
        out.write_bytes(data)
        if sound is not None:
            from ..render.video import write_wav
            write_wav(wav, sound)
            written.append(f"{audio} ({sound.duration:.2f} s)")
        if fdp is not None:
            from ..fdp import save_fdp
            save_fdp(fdp, fdp_out)
            written.append(f"{args.fdp_out} ({len(fdp.labels)} feature points, from the video's frame {picture}, "
                           f"{summary.neutral.first / summary.fps:.2f} s)")
    frames, seconds = len(stream), len(stream) / summary.fps
    print(f"{args.video}: {frames} frames at {summary.fps:g} fps ({seconds:.2f} s), "
          f"{len(data) * 8 / max(frames, 1):.1f} bits/frame ({len(data) * 8 / max(seconds, 1e-9) / 1000:.2f} kbit/s)",
          file=sys.stderr)
    print("wrote " + ", ".join(written), file=sys.stderr)
    return 0


def _neutral_fdp(args: argparse.Namespace, seconds: float):
    """(the video's frame shown ``seconds`` in, the FDP of it: :func:`mpeg4fa.tracking.photo.fdp_from_photo`, its
    picture as texture)."""
    from ..tracking.photo import fdp_from_photo
    from ..tracking.video import frame_showing
    from .fdp_photo import say_notes

    frame, rgb = frame_showing(args.video, seconds, args.fps)
    made = fdp_from_photo(rgb, where=f"{args.video}: frame {frame}", name=args.video.stem)
    say_notes(made, f"{args.video}: frame {frame}")
    return frame, made.fdp
