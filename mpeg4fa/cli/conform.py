"""``mpeg4fa conform``: run the conformance suite on this project's decoder or an external one."""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .options import Commands, real
from .progress import ProgressBar

timeout = real(0.1, 3600.0, what="timeout")
"""Seconds a decoder may take on one vector."""


def jobs(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a whole number: {text!r}") from None
    if not 1 <= n <= 64:
        raise argparse.ArgumentTypeError("give 1 to 64 jobs")
    return n


def _groups(text: str) -> list[str]:
    groups = [g.strip() for g in text.split(",") if g.strip()]
    if not groups:
        raise argparse.ArgumentTypeError("give one or more group names, comma-separated")
    return groups


def register(commands: Commands) -> None:
    from ..conformance.manifest import default_root

    p = commands.add_parser(
        "conform", help="run the conformance suite on a decoder (this project's by default)",
        description="Decode every vector of the suite with a decoder and check what it shows (values per "
                    "frame, time stamps, feature points with a face) and what it rejects. Every check names "
                    "its rule (spec/conformance_rules.csv); exit status 0 only when every check of a required "
                    "rule (V or S) passes: informative rules are reported as 'differs', never failed. An "
                    "external decoder is called as 'CMD STREAM OUT.json [--fdp FDP]' (see conformance/README.md; "
                    "example adapters in conformance/adapters/).",
        epilog="examples:\n  mpeg4fa conform\n  mpeg4fa conform --only syntax,reject --report out/conform\n"
               "  mpeg4fa conform --decoder './mydecoder --suite-mode' --timeout 60 --json\n"
               "  mpeg4fa conform --decoder 'python3 conformance/adapters/mpeg4fa_decoder.py'",
        formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--suite", type=Path, default=default_root(),
                   help="the folder holding manifest.json (default: the suite shipped with the project)")
    p.add_argument("--decoder", metavar="CMD",
                   help="an external decoder's command line (default: this project's, in-process)")
    p.add_argument("--only", type=_groups, metavar="GROUP[,GROUP]", help="run only these groups")
    p.add_argument("--report", type=Path, metavar="DIR", help="write report.md, report.html and plots here")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of the table")
    p.add_argument("--timeout", type=timeout, default=None, metavar="S",
                   help="seconds per vector before it counts as a timeout (default 20)")
    p.add_argument("--jobs", "-j", type=jobs, default=1, metavar="N",
                   help="vectors decoded at once by an external decoder (default 1; the in-process one runs one at a time)")
    p.set_defaults(run=run_conform)


def run_conform(args: argparse.Namespace) -> int:
    from ..conformance.errors import ConformanceError
    from ..conformance.manifest import load_manifest
    from ..conformance.protocol import DEFAULT_TIMEOUT, CommandDecoder
    from ..conformance.runner import run_suite, summary_table

    if not (args.suite / "manifest.json").is_file() and not args.suite.is_file():
        raise ConformanceError("no conformance suite here (manifest.json missing)", where=str(args.suite),
                               hint="give --suite DIR, the folder holding manifest.json")
    manifest = load_manifest(args.suite)
    if args.decoder is not None:  # an empty command is an error, not this project's decoder
        decoder = CommandDecoder(args.decoder)
    else:
        from ..conformance.adapter import in_process
        decoder = in_process()
    bar = ProgressBar("conform", unit="vectors")
    try:
        suite = run_suite(manifest, decoder, only=args.only, progress=bar, jobs=args.jobs if args.decoder else 1,
                          timeout=args.timeout if args.timeout is not None else DEFAULT_TIMEOUT)
    finally:
        bar.close()
    written = None
    if args.report:
        from ..conformance.report import write_report
        written = write_report(suite, args.report)
    if args.json:
        doc = suite.to_json()
        if written:
            doc["report"] = {"markdown": str(written["markdown"]), "html": str(written["html"])}
        json.dump(doc, sys.stdout, indent=1)
        print()
    else:
        print(f"{suite.decoder} on {manifest.root}: {len(suite.vectors)} vectors in {suite.seconds:.1f} s")
        print(summary_table(suite))
        failing = suite.failing()
        findings = suite.by_rule()
        if findings:
            print("by rule:")
        for g in findings:
            kind = "required" if g["required"] else "informative"
            print(f"  {g['rule']} [{g['confidence']}, {kind}]: {len(g['vectors'])} vector(s), {g['checks']} check(s); "
                  f"e.g. {g['example'][:160]}")
        print("PASSED" if suite.passed else f"FAILED: {len(failing)} required vector(s)")
        if written:
            print(f"report: {written['html']}", file=sys.stderr)
    return 0 if suite.passed else 1
