"""Batch rendering: many streams (each with its audio and FDP) to MP4 on a Dask cluster, resumably.

:func:`load_manifest` reads the jobs (JSON or CSV, every fault located), :func:`run_batch` renders
them (a local cluster of worker processes, or a dask.distributed scheduler's address), skipping
the outputs already complete for their inputs (:mod:`.job`). ``mpeg4fa batch`` is the command.
"""
from mpeg4fa.batch.errors import BatchError
from mpeg4fa.batch.job import completed, job_key, render_job
from mpeg4fa.batch.manifest import Job, Manifest, load_manifest
from mpeg4fa.batch.run import SUMMARY_NAME, BatchSummary, JobResult, run_batch

__all__ = ["BatchError", "Job", "Manifest", "load_manifest", "run_batch", "BatchSummary", "JobResult",
           "render_job", "job_key", "completed", "SUMMARY_NAME"]
