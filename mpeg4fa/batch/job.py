"""One batch job: when it is already done, and rendering it inside a worker process.

*Complete* means the output exists and its record beside it (``.NAME.batch.json``) holds the
same key, a hash of the bytes of every input, the options and the package version, and the
output's size: a changed stream, audio, FDP, texture, mesh or option renders again; an output
replaced by hand renders again. The MP4 appears whole or not at all (:func:`mpeg4fa.render.play`
writes it under a temporary name) and the record is written after it, so an interrupted job is
never taken for a finished one.

In a worker, every job of a process runs on one thread kept for GL (a GL context is current on
one thread only, and a worker may run tasks on several), where the process's EGL context
(:mod:`mpeg4fa.render.context`) is made once. Faces and renderers are cached per process by
what they are built from, so the jobs that share a face and image options reuse one
:class:`~mpeg4fa.render.Renderer` and its framebuffer, and the face is rigged or calibrated once.
"""
from __future__ import annotations

import contextlib
import datetime
import glob
import hashlib
import json
import os
import threading
import time
import warnings
from collections import OrderedDict
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path
from typing import Any

from mpeg4fa import __version__
from mpeg4fa.atomic import PARTIAL_MARK, atomic_output
from mpeg4fa.batch.errors import BatchError
from mpeg4fa.batch.manifest import PATH_OPTIONS, Job
from mpeg4fa.errors import MpegFaError, MpegFaWarning

RECORD_SUFFIX = ".batch.json"
FACES_KEPT = 4       # rigged/calibrated faces a worker keeps
RENDERERS_KEPT = 2   # renderers (framebuffers and GPU buffers) a worker keeps


def digest(path: str | os.PathLike) -> str:
    """SHA-256 of a file's bytes (read in 1 MiB pieces)."""
    h = hashlib.sha256()
    with open(path, "rb") as handle:
        for chunk in iter(lambda: handle.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def job_key(job: Job, seen: dict | None = None) -> tuple[str, dict[str, str]]:
    """``(key, digests)``: the key changes when any input's bytes, an option or the package version does.

    ``seen`` (a dict kept across calls) hashes a file many jobs share once: it is keyed by path,
    size and modification time.
    """
    seen = {} if seen is None else seen
    digests = {}
    for name, path in job.inputs().items():
        info = os.stat(path)
        known = (str(path), info.st_size, info.st_mtime_ns)
        if known not in seen:
            seen[known] = digest(path)
        digests[name] = seen[known]
    options = {k: v for k, v in job.options.items() if k not in PATH_OPTIONS}
    text = json.dumps({"version": __version__, "inputs": digests, "options": options}, sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest(), digests


def record_path(target: Path) -> Path:
    """The hidden record beside an output: ``.NAME.batch.json``."""
    return target.with_name(f".{target.name}{RECORD_SUFFIX}")


def completed(target: Path, key: str) -> dict | None:
    """The output's record when it is complete for ``key`` (see the module's docstring), else None."""
    try:
        record = json.loads(record_path(target).read_text(encoding="utf-8"))
        size = target.stat().st_size
    except (OSError, ValueError):
        return None
    if not isinstance(record, dict) or record.get("key") != key or record.get("bytes") != size:
        return None
    return record


def remove_leftovers(target: Path) -> list[Path]:
    """Remove what a killed render of ``target`` left: its temporaries and its record's (no cleanup ran).

    Only names of the form :func:`mpeg4fa.atomic.partial_path` gives ``target`` and its record
    are touched; called when the job starts again, as then no other render of it runs.
    """
    removed = []
    for path in (target, record_path(target)):
        stem = path.name[: len(path.name) - len(path.suffix)][:100]
        for found in path.parent.glob(f".{glob.escape(stem)}{PARTIAL_MARK}{'[0-9a-f]' * 8}{glob.escape(path.suffix)}"):
            with contextlib.suppress(OSError):
                found.unlink()
                removed.append(found)
    return removed


def one_line(message: object) -> str:
    return " ".join(str(message).split())


# -- in the worker ----------------------------------------------------------------------------------

class _InStream(MpegFaError):
    """A stream that cannot be read, its path in front of the reader's error."""


class _ProcessState:
    """What one worker process keeps between jobs: its GL thread, faces and renderers."""

    def __init__(self) -> None:
        self.pid = os.getpid()
        self.gl = ThreadPoolExecutor(max_workers=1, thread_name_prefix="mpeg4fa-gl")
        self.faces: OrderedDict[tuple, Any] = OrderedDict()
        self.renderers: OrderedDict[tuple, Any] = OrderedDict()

    def face(self, job: Job, digests: dict[str, str]):
        from mpeg4fa.face.assemble import assemble_face

        o = job.options
        key = (digests.get("face_mesh"), digests.get("face_points"), digests.get("fdp"), o["method"], o["skull"],
               o["deformer"], o["blocks"])
        if key not in self.faces:  # the same rules as `mpeg4fa play`'s face options
            self.faces[key] = assemble_face(
                fdp=job.fdp, method=o["method"], skull=o["skull"], deformer=o["deformer"], blocks=o["blocks"],
                face_mesh=o["face_mesh"], face_points=o["face_points"])
            while len(self.faces) > FACES_KEPT:
                self.faces.popitem(last=False)
        self.faces.move_to_end(key)
        return key, self.faces[key]

    def renderer(self, job: Job, digests: dict[str, str]) -> tuple[Any, bool, tuple]:
        """``(renderer, reused, key)`` for the job's face and image options."""
        from mpeg4fa.render import Renderer

        face_key, face = self.face(job, digests)
        o = job.options
        skin = ("texture", digests["texture"]) if o["texture"] is not None else (
            ("fdp", digests["fdp"]) if job.fdp is not None and o["fdp_texture"] else None)
        key = (face_key, tuple(o["size"]), o["aa"], o["view"], skin)
        reused = key in self.renderers
        if not reused:
            width, height = o["size"]
            self.renderers[key] = Renderer(face, width=width, height=height, samples=o["aa"], view=o["view"],
                                           texture=_skin_texture(job, face, skin))
            while len(self.renderers) > RENDERERS_KEPT:
                self.renderers.popitem(last=False)[1].release()
        self.renderers.move_to_end(key)
        return self.renderers[key], reused, key

    def forget(self, key: tuple) -> None:
        """Drop a renderer that was in use when a job failed: it is not trusted with the next one."""
        renderer = self.renderers.pop(key, None)
        if renderer is not None:
            try:
                renderer.release()
            except Exception:  # releasing a broken renderer must not hide the job's own error
                pass


def _skin_texture(job: Job, face, skin: tuple | None):
    """The job's texture image, else the texture its FDP carries mapped onto the face (as ``play`` does)."""
    if skin is None:
        return None
    if skin[0] == "texture":
        from mpeg4fa.render.images import read_image
        return read_image(job.options["texture"], "texture image")
    from mpeg4fa.fdp import load_fdp
    from mpeg4fa.render.fdp_texture import fdp_skin_texture
    sent = fdp_skin_texture(face.mesh, load_fdp(job.fdp), source=str(job.fdp))
    return None if sent is None else sent.image


_STATE: _ProcessState | None = None
_STATE_LOCK = threading.Lock()


def _process_state() -> _ProcessState:
    """This process's state, made on first use (and made again in a forked child: GL does not survive a fork)."""
    global _STATE
    with _STATE_LOCK:
        if _STATE is None or _STATE.pid != os.getpid():
            _STATE = _ProcessState()
        return _STATE


def render_job(job: Job, outdir: str, key: str, digests: dict[str, str]) -> dict:
    """Render one job to ``outdir/job.output`` and write its record; the task a Dask worker runs.

    Returns a dict: status ``rendered`` (frames, duration, seconds, warnings) or ``failed``
    (error: one line saying what and where); bad input never raises out of here.
    """
    state = _process_state()
    result = state.gl.submit(_render, state, job, Path(outdir), key, digests).result()
    result["worker"] = _worker_address()
    return result


def _worker_address() -> str | None:
    try:
        from distributed import get_worker
        return get_worker().address
    except (ImportError, ValueError):  # not in a Dask worker (a direct call)
        return None


def _check_inside(target: Path, outdir: Path) -> None:
    """BatchError for an output (or its record beside it) that a symbolic link already in ``outdir`` leads out of
    it: the manifest's names are checked to stay inside (no ``..``, not absolute), and so is what they resolve to."""
    root = Path(os.path.realpath(outdir))
    for path in (target, record_path(target)):
        if not Path(os.path.realpath(path)).is_relative_to(root):
            raise BatchError(f"is a link to {os.path.realpath(path)}, outside the output folder",
                             where=str(path), hint="remove the link, or name another output")


def _render(state: _ProcessState, job: Job, outdir: Path, key: str, digests: dict[str, str]) -> dict:
    from mpeg4fa.formats import read_stream
    from mpeg4fa.render import play

    started = time.perf_counter()
    target = outdir / job.output
    done = {"pid": os.getpid()}
    renderer_key = None
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always", MpegFaWarning)
            try:
                stream, _ = read_stream(job.stream)
            except MpegFaError as exc:  # the codec's errors name the bit, not always the file
                text = one_line(exc)
                raise _InStream(text if str(job.stream) in text else f"{job.stream}: {text}") from None
            renderer, reused, renderer_key = state.renderer(job, digests)
            _check_inside(target, outdir)  # before any folder is made through a link
            target.parent.mkdir(parents=True, exist_ok=True)
            remove_leftovers(target)
            o = job.options
            played = play(stream, target, renderer=renderer, audio=job.audio, fps=o["fps"], fit=o["fit"],
                          writer_options={"crf": o["crf"]})
        seconds = time.perf_counter() - started
        record = {"key": key, "bytes": target.stat().st_size, "frames": played.n_frames, "fps": played.fps,
                  "duration": round(played.duration, 6), "seconds": round(seconds, 3), "version": __version__,
                  "inputs": {name: str(path) for name, path in job.inputs().items()}, "digests": digests,
                  "finished": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds")}
        with atomic_output(record_path(target)) as partial:
            partial.write_text(json.dumps(record, indent=1), encoding="utf-8")
        return {**done, "status": "rendered", "frames": played.n_frames, "duration": played.duration,
                "seconds": seconds, "renderer_reused": reused,
                "warnings": [one_line(w.message) for w in caught if issubclass(w.category, MpegFaWarning)]}
    except (MpegFaError, OSError) as exc:
        if renderer_key is not None:
            state.forget(renderer_key)
        return {**done, "status": "failed", "seconds": time.perf_counter() - started, "error": one_line(exc)}
