"""Decoded streams to pictures and sound: PNG sequences, MP4 files, snapshots and live frames.

The decode line ends here: FapStream -> resolved FAPs (face layer 1) -> poses
(layers 2-4) -> pixels (:class:`.Renderer`) -> a writer (:mod:`.video`), with the
speech muxed so that stream frame ``k`` appears at its presentation time
(:mod:`.timing`). A stream and its audio rarely end on the same sample: within
one frame nothing is said; beyond that the shorter one is padded (``fit="pad"``,
the default: the video holds its last frame, the audio gets silence) or the
longer one is cut (``fit="trim"``), and a :class:`.RenderWarning` says which.
"""
from __future__ import annotations

import math
import os
import time
import warnings
from dataclasses import dataclass, field
from typing import Callable, Iterable, Iterator

import numpy as np

from mpeg4fa.atomic import atomic_output
from mpeg4fa.decoded import FrameResolver, resolve
from mpeg4fa.face.model import FaceModel
from mpeg4fa.face.sent import played_face
from mpeg4fa.fba.stream import FapStream, Frame
from mpeg4fa.render.audio import Audio, fit_audio, read_audio
from mpeg4fa.fdp.model import Fdp
from mpeg4fa.render.errors import RenderError, RenderWarning
from mpeg4fa.render.fdp_texture import fdp_skin_texture
from mpeg4fa.render.realtime import LiveFrame, LiveStats, live
from mpeg4fa.render.renderer import Renderer
from mpeg4fa.render.timing import Schedule, schedule
from mpeg4fa.render.video import open_writer, writes_folder

Progress = Callable[[int, int], None]
FITS = ("pad", "trim")


@dataclass
class PlayResult:
    target: str
    n_frames: int          # frames written
    rendered: int          # distinct poses rendered (held frames are written again, not redrawn)
    fps: float
    duration: float        # seconds of video
    audio_duration: float | None
    adjustments: list[str] = field(default_factory=list)
    seconds: float = 0.0   # wall-clock time taken

    @property
    def speed(self) -> float:
        """Times real time (video seconds per wall-clock second)."""
        return self.duration / self.seconds if self.seconds else math.inf


def _as_audio(audio: Audio | str | os.PathLike | None) -> Audio | None:
    if audio is None or isinstance(audio, Audio):
        return audio
    return read_audio(audio)


def _reconcile(plan: Schedule, audio: Audio | None, fit: str) -> tuple[Schedule, Audio | None, list[str]]:
    """Make video and audio the same length, saying what was changed beyond one frame."""
    if fit not in FITS:
        raise RenderError(f"unknown fit {fit!r}", hint=f"one of {', '.join(FITS)}")
    if audio is None:
        return plan, None, []
    said = []
    frame = 1.0 / plan.fps
    gap = audio.duration - plan.duration
    if abs(gap) > frame:
        if fit == "pad" and gap > 0:
            n = int(math.ceil(audio.duration * plan.fps - 1e-6))
            said.append(f"audio is {audio.duration:.3f} s, the stream {plan.duration:.3f} s: "
                        f"video padded with {n - plan.n_frames} frames holding the last pose")
            plan = plan.extended(n)
        elif fit == "pad":
            said.append(f"audio is {audio.duration:.3f} s, the stream {plan.duration:.3f} s: "
                        f"audio padded with {-gap:.3f} s of silence")
        elif gap > 0:
            said.append(f"audio is {audio.duration:.3f} s, the stream {plan.duration:.3f} s: "
                        f"audio trimmed by {gap:.3f} s")
        else:
            n = max(int(math.ceil(audio.duration * plan.fps - 1e-6)), 1)
            said.append(f"audio is {audio.duration:.3f} s, the stream {plan.duration:.3f} s: "
                        f"video trimmed by {plan.n_frames - n} frames")
            plan = plan.extended(n)
    return plan, fit_audio(audio, plan.duration), said


def _face_and_options(face: FaceModel | None, fdp: Fdp | None, fdp_texture: bool, renderer: Renderer | None,
                      options: dict) -> tuple[FaceModel, dict]:
    """The face to pose (the renderer's, else the generic head calibrated to ``fdp``, unless one is given) and
    the renderer's options, with the FDP's own texture mapped onto the face when it carries one and no
    texture was given."""
    if face is None and renderer is not None:
        face = renderer.face  # posing another head than the one the renderer draws gives wrong pixels
    if renderer is not None and face is not renderer.face and face.mesh.n_vertices != renderer.face.mesh.n_vertices:
        raise RenderError(f"the face has {face.mesh.n_vertices} vertices, the renderer's {renderer.face.mesh.n_vertices}",
                          hint="pass the renderer's own face, or no face")
    if face is None:
        face = FaceModel.default() if fdp is None else played_face(fdp)
    if fdp is not None and fdp_texture and renderer is None and options.get("texture") is None:
        sent = fdp_skin_texture(face.mesh, fdp)
        if sent is not None:
            options = {**options, "texture": sent.image}
    return face, options


def _renderer_for(face: FaceModel, renderer: Renderer | None, options: dict) -> tuple[Renderer, bool]:
    if renderer is not None:
        if options:
            raise RenderError(f"pass either a renderer or its options ({', '.join(options)}), not both")
        return renderer, False
    return Renderer(face, **options), True


def play(stream: FapStream, target: str | os.PathLike, *, face: FaceModel | None = None, fdp: Fdp | None = None,
         fdp_texture: bool = True, audio: Audio | str | os.PathLike | None = None, fps: float | None = None, fit: str = "pad",
         renderer: Renderer | None = None, progress: Progress | None = None, writer_options: dict | None = None,
         **render_options) -> PlayResult:
    """Render every frame of ``stream`` to ``target`` (.mp4/.mov/.m4v file, else a PNG folder).

    ``render_options`` go to :class:`.Renderer` (width, height, samples, view, texture...).
    ``fdp``: the sender's FDP; without ``face`` the generic head is calibrated to it (or, when it
    carries a mesh and FaceDefTables, FDP case 4, that mesh is played, moved by its tables:
    :mod:`mpeg4fa.face.sent`), and when it carries a texture (FDP case 3) the skin wears it (:mod:`.fdp_texture`) unless ``texture`` is
    given or ``fdp_texture`` is False.
    Warnings (:class:`.RenderWarning`) say how stream and audio lengths were matched.
    """
    started = time.perf_counter()
    face, render_options = _face_and_options(face, fdp, fdp_texture, renderer, render_options)
    plan, audio_fit, said = _reconcile(schedule(stream, fps), _as_audio(audio), fit)
    for message in said:
        warnings.warn(message, RenderWarning, stacklevel=2)
    values = resolve(stream)
    rend, owned = _renderer_for(face, renderer, render_options)
    image = np.empty((rend.height, rend.width, 3), np.uint8)
    rendered, shown = 0, -1
    try:  # under a temporary name until the last frame is in: a failed play leaves nothing behind
        with atomic_output(target, directory=writes_folder(target)) as partial, \
                open_writer(partial, rend.width, rend.height, plan.fps, audio_fit, **(writer_options or {})) as out:
            for j, k in enumerate(plan.source):
                if k != shown:
                    rend.render(face.pose_values(values[k]), out=image)
                    rendered, shown = rendered + 1, k
                out.write(image)
                if progress is not None:
                    progress(j + 1, plan.n_frames)
    finally:
        if owned:
            rend.release()
    return PlayResult(target=str(target), n_frames=plan.n_frames, rendered=rendered, fps=plan.fps,
                      duration=plan.duration, audio_duration=audio_fit.duration if audio_fit else None,
                      adjustments=said, seconds=time.perf_counter() - started)


def frame_at(stream: FapStream, *, frame: int | None = None, seconds: float | None = None) -> int:
    """The stream frame shown at ``frame`` (an index) or ``seconds`` (presentation time)."""
    n = len(stream)
    if frame is not None and seconds is not None:
        raise RenderError("give a frame index or a time, not both")
    if seconds is not None:
        times = schedule(stream).times
        if not 0 <= seconds <= times[-1] + 1.0 / stream.fps:
            raise RenderError(f"time {seconds} s is outside the stream", hint=f"0 to {times[-1]:.3f} s")
        return int(np.searchsorted(times, seconds + 1e-9, side="right") - 1)
    k = 0 if frame is None else int(frame)
    if k < 0:
        k += n
    if not 0 <= k < n:
        raise RenderError(f"frame {frame} is outside the stream",
                          hint=f"the stream has {n} frames: 0 to {n - 1}, negative counts from the end")
    return k


def snapshot(stream: FapStream, *, frame: int | None = None, seconds: float | None = None,
             face: FaceModel | None = None, fdp: Fdp | None = None, fdp_texture: bool = True,
             renderer: Renderer | None = None, **render_options) -> np.ndarray:
    """One frame of a stream as an (H, W, 3) image (held and interpolated FAPs resolved as in playback).

    ``fdp`` and ``fdp_texture`` as in :func:`play`.
    """
    face, render_options = _face_and_options(face, fdp, fdp_texture, renderer, render_options)
    k = frame_at(stream, frame=frame, seconds=seconds)
    values = resolve(stream)[k]
    rend, owned = _renderer_for(face, renderer, render_options)
    try:
        return rend.render(face.pose_values(values))
    finally:
        if owned:
            rend.release()


def play_live(frames: Iterable[Frame], renderer: Renderer, *, face: FaceModel | None = None,
              stall_timeout: float = 2.0, stats: LiveStats | None = None, **pacing) -> Iterator[LiveFrame]:
    """Decode -> deform -> render at wall-clock pace: late frames are dropped, a stalled source raises.

    ``frames`` is any iterator of decoded frames, e.g. :func:`mpeg4fa.fba.iter_decode` on a
    socket's file object: ``sock.makefile("rb")`` with its default buffering works (the bit reader
    takes what has arrived, ``read1``). For the lowest latency decode a live source with
    ``backend="python"``: the compiled path decodes a P plane only once a worst-case margin of bits
    has arrived after it (about 100 bytes, seconds at the rates of streams made from text). Every
    frame is resolved in the source thread, because unsent FAPs hold their values across frames,
    even across frames that are dropped for lateness.
    """
    face = face or renderer.face
    resolver = FrameResolver()

    def resolved():
        for frame in frames:
            yield frame, resolver.push(frame)

    def draw(item):
        return renderer.render(face.pose_values(item[1]))

    return live(resolved(), draw, timestamp=lambda item: item[0].timestamp, stall_timeout=stall_timeout,
                stats=stats, **pacing)
