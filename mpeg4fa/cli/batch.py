"""``mpeg4fa batch``: render the streams of a manifest to MP4 on a Dask cluster, resumably."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from . import options
from .options import Commands
from .progress import ProgressBar


def register(commands: Commands) -> None:
    p = commands.add_parser(
        "batch", help="render many streams (each with its audio and FDP) to MP4 on a Dask cluster",
        description="Render every job of a manifest to an MP4 in OUTDIR, one Dask task a stream: on a local "
                    "cluster of worker processes (one GL context each), or on a running dask.distributed "
                    "cluster with --scheduler (its workers must see the files at the same paths). Outputs "
                    "already complete for the same inputs and options are skipped, so a stopped batch is run "
                    "again to finish it; outputs appear whole or not at all. A job that fails is reported and "
                    "the others go on; OUTDIR/batch-summary.json says what each job did. Exit status 1 when "
                    "any job failed.",
        epilog="manifest (JSON; paths relative to the manifest, outputs to OUTDIR):\n"
               '  {"defaults": {"size": "320x320"},\n'
               '   "jobs": [{"stream": "a.fba", "audio": "a.wav", "fdp": "anna.fdp", "output": "a.mp4"},\n'
               '            {"stream": "b.fap", "view": "left", "crf": 23}]}\n'
               "or CSV with a header row: stream,audio,fdp,output,size\n"
               "keys: stream, audio, fdp, output and play's options: size, aa, view, fps, fit, crf, deformer,\n"
               "  blocks, method, skull, texture, fdp_texture, face_mesh, face_points\n"
               "examples:\n  mpeg4fa batch jobs.json -o videos/\n"
               "  mpeg4fa batch jobs.csv -o videos/ --scheduler tcp://head-node:8786 --json",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("manifest", type=Path, help="the jobs: a .json file, or CSV with a header row")
    p.add_argument("-o", "--output", type=Path, required=True, metavar="OUTDIR",
                   help="folder for the MP4s (made if missing)")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=options.workers, metavar="N",
                       help="worker processes of the local cluster (default: one a core, at most one a job)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="a running dask.distributed scheduler, e.g. tcp://head-node:8786, instead of a local "
                            "cluster")
    p.add_argument("--force", action="store_true", help="render every job again, complete or not")
    p.add_argument("--json", action="store_true", help="print the JSON summary when done")
    p.set_defaults(run=run_batch_command)


def run_batch_command(args: argparse.Namespace) -> int:
    from ..extras import require

    require("batch", "dask", "distributed")
    from ..batch import load_manifest, run_batch
    from ..batch.run import SUMMARY_NAME

    manifest = load_manifest(args.manifest)
    bar = ProgressBar(f"rendering {len(manifest.jobs)} streams", unit="streams")
    try:
        summary = run_batch(manifest, args.output, workers=args.workers, scheduler=args.scheduler,
                            force=args.force, progress=bar)
    finally:
        bar.close()
    for job in summary.jobs:
        for warning in job.warnings:
            print(f"mpeg4fa batch: warning: {job.output}: {warning}", file=sys.stderr)
        if job.status == "failed":
            print(f"mpeg4fa batch: error: {job.output} ({job.where}): {job.error}", file=sys.stderr)
    if args.json:
        print(json.dumps(summary.as_dict(), indent=2))
    else:
        ran_on = f" on {summary.workers} worker{'s' if summary.workers != 1 else ''}" if summary.workers else ""
        print(f"{summary.count('rendered')} rendered, {summary.count('skipped')} skipped, "
              f"{summary.count('failed')} failed in {summary.seconds:.1f} s{ran_on}; "
              f"summary: {Path(args.output) / SUMMARY_NAME}")
    return 1 if summary.failed else 0
