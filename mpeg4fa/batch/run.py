"""Render a manifest's streams on Dask: one task a stream, on a local cluster or any scheduler.

Why Dask futures: each job is a separate MP4 and independent of the others, so the jobs are
submitted at once and collected with ``as_completed`` (the progress bar moves as each
finishes, a failed one is recorded and the others go on). The default is a
``LocalCluster`` of worker *processes* with one thread each: a process has one GL context, and
Mesa's llvmpipe rasterises on threads of its own (``LP_NUM_THREADS``, set here to the cores
divided among the workers unless the environment already says), so more threads per worker
would only contend. ``scheduler="tcp://host:8786"`` sends the same tasks to a running
``dask.distributed`` cluster, whose workers must see the manifest's files and the output
folder at the same paths (a shared file system).

Resumable: a job whose output is complete for its inputs (:func:`.job.completed`) is skipped
before any cluster starts; the summary (``batch-summary.json`` in the output folder, written
whole) says what each job did.
"""
from __future__ import annotations

import contextlib
import json
import logging
import os
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path
from typing import Callable, Iterator

from mpeg4fa.atomic import atomic_output
from mpeg4fa.batch.errors import BatchError
from mpeg4fa.batch.job import completed, job_key, one_line, remove_leftovers, render_job
from mpeg4fa.batch.manifest import Job, Manifest, load_manifest

SUMMARY_NAME = "batch-summary.json"
STATUSES = ("rendered", "skipped", "failed")
CONNECT_TIMEOUT_S = 20

Progress = Callable[[int, int], None]


@dataclass
class JobResult:
    index: int
    where: str
    output: str
    status: str                       # rendered, skipped or failed
    seconds: float = 0.0
    frames: int | None = None
    error: str | None = None
    warnings: list[str] = field(default_factory=list)
    worker: str | None = None
    pid: int | None = None
    renderer_reused: bool | None = None


@dataclass
class BatchSummary:
    manifest: str
    outdir: str
    scheduler: str | None             # the address given, else None (a local cluster)
    workers: int                      # worker processes this run's jobs ran on (0 when all were skipped)
    seconds: float
    jobs: list[JobResult]

    def count(self, status: str) -> int:
        return sum(j.status == status for j in self.jobs)

    @property
    def failed(self) -> list[JobResult]:
        return [j for j in self.jobs if j.status == "failed"]

    def as_dict(self) -> dict:
        return {"manifest": self.manifest, "outdir": self.outdir, "scheduler": self.scheduler or "local",
                "workers": self.workers, "seconds": round(self.seconds, 3),
                "counts": {s: self.count(s) for s in STATUSES},
                "jobs": [{**asdict(j), "seconds": round(j.seconds, 3)} for j in self.jobs]}


def default_workers() -> int:
    """The cores this process may use (its CPU affinity where the system has one)."""
    try:
        return max(len(os.sched_getaffinity(0)), 1)
    except AttributeError:  # pragma: no cover - macOS, Windows
        return os.cpu_count() or 1


def run_batch(manifest: Manifest | str | os.PathLike, outdir: str | os.PathLike, *, workers: int | None = None,
              scheduler: str | None = None, force: bool = False, progress: Progress | None = None) -> BatchSummary:
    """Render every job of ``manifest`` into ``outdir``; jobs already complete are skipped (unless ``force``).

    ``workers``: processes of the local cluster (default: one a core, at most one a job);
    ``scheduler``: a dask.distributed scheduler's address instead of a local cluster.
    One job's failure is in its :class:`JobResult` and stops no other; the summary is
    returned and written to ``outdir/batch-summary.json``.
    """
    started = time.perf_counter()
    if not isinstance(manifest, Manifest):
        manifest = load_manifest(manifest)
    if workers is not None and workers < 1:
        raise BatchError(f"{workers} workers", where="workers", hint="one or more")
    out = Path(outdir)
    _check_outdir(manifest, out)
    results: dict[int, JobResult] = {}
    todo: list[tuple[Job, str, dict[str, str]]] = []
    seen: dict = {}  # a face mesh or FDP that many jobs share is hashed once
    for job in manifest.jobs:
        try:
            key, digests = job_key(job, seen)
        except OSError as exc:
            results[job.index] = JobResult(job.index, job.where, job.output, "failed",
                                           error=f"cannot read an input ({one_line(exc)})")
            continue
        record = None if force else completed(out / job.output, key)
        if record is not None:
            results[job.index] = JobResult(job.index, job.where, job.output, "skipped", frames=record.get("frames"))
        else:
            todo.append((job, key, digests))
    total = len(manifest.jobs)
    if progress is not None:
        progress(len(results), total)
    if todo:
        if scheduler is None:
            _generic_head_first(todo)
        try:
            with _client(scheduler, min(workers or default_workers(), len(todo))) as client:
                for job, result in _submitted(client, todo, out):
                    results[job.index] = result
                    if progress is not None:
                        progress(len(results), total)
        except BaseException:  # Ctrl-C, SIGTERM (mpeg4fa.atomic.Terminated), a lost scheduler...
            if scheduler is None:  # the local cluster is closed: no worker writes any more
                for job, _, _ in todo:
                    if job.index not in results:
                        remove_leftovers(out / job.output)
            raise
    used = len({r.worker for r in results.values() if r.worker is not None})
    summary = BatchSummary(str(manifest.path), str(out), scheduler, used, time.perf_counter() - started,
                           [results[j.index] for j in manifest.jobs])
    write_summary(summary, out / SUMMARY_NAME)
    return summary


def write_summary(summary: BatchSummary, path: Path) -> None:
    with atomic_output(path) as partial:
        partial.write_text(json.dumps(summary.as_dict(), indent=2) + "\n", encoding="utf-8")


def _check_outdir(manifest: Manifest, out: Path) -> None:
    """The output folder exists (made if not) and no output is one of the jobs' inputs (by path or inode)."""
    if out.exists() and not out.is_dir():
        raise BatchError("the output folder is a file", where=str(out), hint="give a folder (made if missing)")
    read: dict[object, str] = {}
    for job in manifest.jobs:
        for name, path in job.inputs().items():
            read.setdefault(os.path.realpath(path), f"the {name} of {job.where}")
            with contextlib.suppress(OSError):
                info = os.stat(path)
                read.setdefault((info.st_dev, info.st_ino), f"the {name} of {job.where}")
    clashes = []
    for job in manifest.jobs:
        target = out / job.output
        found = read.get(os.path.realpath(target))
        with contextlib.suppress(OSError):
            info = os.stat(target)
            found = found or read.get((info.st_dev, info.st_ino))
        if found:
            clashes.append(f"{job.where}: output {job.output} is {found}")
    if clashes:
        raise BatchError(f"an output would overwrite an input: {'; '.join(clashes)}", where=str(manifest.path),
                         hint="give another output folder or other output names")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise BatchError(f"cannot make the output folder ({exc.strerror or exc})", where=str(out)) from None


def _generic_head_first(todo: list[tuple[Job, str, dict[str, str]]]) -> None:
    """Build the generic head here once, before the local workers would each try to (they share this cache)."""
    from mpeg4fa.face import asset

    if any(job.options.get("face_mesh") is None for job, _, _ in todo) and not asset.is_installed():
        asset.load_head()


@contextlib.contextmanager
def _client(scheduler: str | None, n_workers: int) -> Iterator:
    """A Dask client: on the scheduler at ``scheduler``, else on a local cluster made (and closed) here."""
    from distributed import Client, LocalCluster

    if scheduler is not None:
        try:
            client = Client(scheduler, timeout=CONNECT_TIMEOUT_S)
        except (OSError, TimeoutError, ValueError) as exc:
            raise BatchError(f"cannot reach the Dask scheduler ({one_line(exc)})", where=scheduler,
                             hint="start one with `dask scheduler` and give its tcp://HOST:PORT") from None
        with client:
            try:
                client.wait_for_workers(1, timeout=CONNECT_TIMEOUT_S)
            except TimeoutError:
                raise BatchError(f"the scheduler has had no workers for {CONNECT_TIMEOUT_S} s", where=scheduler,
                                 hint="start some with `dask worker ADDRESS --nthreads 1`") from None
            yield client
        return
    env = {"LP_NUM_THREADS": os.environ.get("LP_NUM_THREADS") or str(max(default_workers() // n_workers, 1))}
    with LocalCluster(n_workers=n_workers, threads_per_worker=1, processes=True, dashboard_address=None,
                      scheduler_kwargs={"dashboard_address": "127.0.0.1:0"},  # no dashboard; its HTTP port free
                      silence_logs=logging.ERROR, env=env) as cluster, Client(cluster) as client:
        yield client


def _submitted(client, todo: list[tuple[Job, str, dict[str, str]]], out: Path) -> Iterator[tuple[Job, JobResult]]:
    """Submit every job, then yield each one's result as it finishes (a task that raised is a failed job)."""
    from distributed import as_completed

    futures = {}
    for job, key, digests in todo:
        future = client.submit(render_job, job, str(out), key, digests, key=f"mpeg4fa-render-{job.index}-{key[:16]}",
                               retries=0)
        futures[future] = job
    for future in as_completed(futures):
        job = futures[future]
        yield job, _result(job, future)


def _result(job: Job, future) -> JobResult:
    if future.status == "finished":
        got = future.result()
        return JobResult(job.index, job.where, job.output, got["status"], seconds=got.get("seconds", 0.0),
                         frames=got.get("frames"), error=got.get("error"), warnings=got.get("warnings", []),
                         worker=got.get("worker"), pid=got.get("pid"), renderer_reused=got.get("renderer_reused"))
    if future.status == "error":  # a bug, or a worker that died (KilledWorker): this job failed, not the batch
        exc = future.exception()
        return JobResult(job.index, job.where, job.output, "failed", error=f"{type(exc).__name__}: {one_line(exc)}")
    return JobResult(job.index, job.where, job.output, "failed", error=f"the task was {future.status}")
