#!/usr/bin/env python3
"""Benchmark batch rendering on Dask: the same streams on a local cluster of 1 and of 2 workers.

Run on demand (not a test):
    .venv/bin/python tools/bench_batch.py [--streams 8] [--seconds 4] [--size 256] [--json bench_batch.json]

Each configuration renders every stream from scratch (a fresh output folder) through
:func:`mpeg4fa.batch.run_batch`, timed from the call to its return: cluster start, worker
start-up (imports, face rig, GL context) and the renders. ``warm`` is the wall time minus the
slowest worker's first job, i.e. roughly what a long batch costs per stream once workers are up.
``LP_NUM_THREADS`` (Mesa llvmpipe's rasteriser threads per GL context) is set per worker to the
cores divided among the workers, as ``run_batch`` does; the last row gives 2 workers 2 threads
each to show what oversubscribing the cores costs. The face is the generic head when it is
built, else the procedural head's skin (tests/procedural_head.py) given as face_mesh.
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import resource
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "tests"), str(ROOT / "tests" / "batch")]

from mpeg4fa.batch import run_batch  # noqa: E402
from mpeg4fa.batch.run import default_workers  # noqa: E402
from mpeg4fa.face import asset  # noqa: E402
from workload import write_face, write_stream, write_tone  # noqa: E402

CONFIGS = ((1, None), (2, None), (2, 2))
"""(workers, LP_NUM_THREADS; None = what run_batch sets: the cores divided among the workers)."""


def make_inputs(folder: Path, n: int, seconds: float, size: int) -> tuple[Path, str]:
    face = "generic head" if asset.is_installed() else "procedural head (skin, as face_mesh)"
    defaults: dict = {"size": f"{size}x{size}"}
    if not asset.is_installed():
        obj, points = write_face(folder)
        defaults.update(face_mesh=obj.name, face_points=points.name)
    jobs = []
    for i in range(n):
        write_stream(folder / f"talk{i}.fba", seconds, phase=0.7 * i)
        job = {"stream": f"talk{i}.fba"}
        if i % 2 == 0:  # half of them with speech to mux
            write_tone(folder / f"talk{i}.wav", seconds)
            job["audio"] = f"talk{i}.wav"
        jobs.append(job)
    manifest = folder / "jobs.json"
    manifest.write_text(json.dumps({"defaults": defaults, "jobs": jobs}, indent=1))
    return manifest, face


def _children_cpu() -> float:
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def run_config(manifest: Path, folder: Path, workers: int, lp_threads: int | None) -> dict:
    saved = os.environ.pop("LP_NUM_THREADS", None)
    if lp_threads is not None:
        os.environ["LP_NUM_THREADS"] = str(lp_threads)
    try:
        out = Path(tempfile.mkdtemp(prefix=f"out-{workers}-{lp_threads or 'auto'}-", dir=folder))  # nothing to skip
        cpu_before = _children_cpu()
        started = time.perf_counter()
        summary = run_batch(manifest, out, workers=workers)
        wall = time.perf_counter() - started
        cpu = _children_cpu() - cpu_before  # the worker processes, reaped when the cluster closed
    finally:
        os.environ.pop("LP_NUM_THREADS", None)
        if saved is not None:
            os.environ["LP_NUM_THREADS"] = saved
    if summary.failed:
        raise SystemExit(f"a job failed: {summary.failed[0].error}")
    by_worker: dict[str, list[float]] = {}
    for job in summary.jobs:  # each worker's first job carries its start-up: its slowest
        by_worker.setdefault(job.worker, []).append(job.seconds)
    frames = sum(j.frames for j in summary.jobs)
    return {"workers": workers, "lp_num_threads": lp_threads or max(default_workers() // workers, 1),
            "wall_s": wall, "worker_cpu_s": cpu, "cores_busy": cpu / wall,
            "frames": frames, "frames_per_s": frames / wall,
            "jobs_per_worker": {w: len(s) for w, s in by_worker.items()},
            "first_job_s": max(max(s) for s in by_worker.values()),
            "warm_s": wall - max(max(s) for s in by_worker.values()),
            "mean_job_s": sum(j.seconds for j in summary.jobs) / len(summary.jobs)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--streams", type=int, default=8, help="streams to render (default 8)")
    ap.add_argument("--seconds", type=float, default=4.0, help="length of each stream (default 4 s, 100 frames)")
    ap.add_argument("--size", type=int, default=256, help="image side in pixels (default 256)")
    ap.add_argument("--json", type=Path, default=Path("bench_batch.json"))
    ap.add_argument("--repeat", type=int, default=1, help="runs of each configuration; the fastest counts (default 1)")
    args = ap.parse_args()
    with tempfile.TemporaryDirectory(prefix="bench-batch-") as tmp:
        folder = Path(tmp)
        manifest, face = make_inputs(folder, args.streams, args.seconds, args.size)
        rows = [min((run_config(manifest, folder, workers, lp) for _ in range(args.repeat)), key=lambda r: r["wall_s"])
                for workers, lp in CONFIGS]
    base = rows[0]["wall_s"]
    base_warm = rows[0]["warm_s"]
    for row in rows:
        row["speedup"] = base / row["wall_s"]
        row["warm_speedup"] = base_warm / row["warm_s"] if row["warm_s"] > 0 else None
    print(f"{args.streams} streams x {args.seconds:g} s at {args.size}x{args.size}, {face}; "
          f"{default_workers()} cores, load average {os.getloadavg()[0]:.1f} at the end")
    print(f"{'workers':>7} {'LP thr':>6} {'wall s':>7} {'frames/s':>8} {'speed-up':>8} {'1st job s':>9} "
          f"{'warm s':>7} {'warm x':>6} {'cores busy':>10}  jobs per worker")
    for r in rows:
        warm_x = f"{r['warm_speedup']:.2f}" if r["warm_speedup"] else "-"
        print(f"{r['workers']:>7} {r['lp_num_threads']:>6} {r['wall_s']:>7.1f} {r['frames_per_s']:>8.1f} "
              f"{r['speedup']:>8.2f} {r['first_job_s']:>9.1f} {r['warm_s']:>7.1f} {warm_x:>6} "
              f"{r['cores_busy']:>10.2f}  "
              f"{sorted(r['jobs_per_worker'].values())}")
    result = {"streams": args.streams, "seconds": args.seconds, "size": args.size, "face": face,
              "cores": default_workers(), "load_average": os.getloadavg(), "machine": platform.platform(),
              "rows": rows}
    args.json.write_text(json.dumps(result, indent=1, default=float))
    print(f"wrote {args.json}")


if __name__ == "__main__":
    main()
