#!/usr/bin/env python3
"""Regenerate the conformance suite (streams, expected results, faces, manifest) from spec/.

Usage: .venv/bin/python tools/make_conformance.py [--out conformance]
"""
from __future__ import annotations

import argparse
import sys
import time
from collections import Counter
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.conformance.generate import generate  # noqa: E402
from mpeg4fa.errors import MpegFaError  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=None, help="folder to write (default: the committed conformance/)")
    args = parser.parse_args(argv)
    start = time.perf_counter()
    try:
        manifest = generate(args.out)
    except MpegFaError as exc:
        print(f"make_conformance: {exc}", file=sys.stderr)
        return 1
    groups = Counter(v.group for v in manifest.vectors)
    size = sum(p.stat().st_size for p in manifest.root.rglob("*") if p.is_file())
    print(f"{len(manifest.vectors)} vectors ({', '.join(f'{g} {n}' for g, n in groups.items())}), "
          f"{len(manifest.faces)} faces, {size / 1e6:.2f} MB in {manifest.root}, {time.perf_counter() - start:.1f} s")
    rules = Counter(rule for v in manifest.vectors for rule in v.check_rules.values())
    print("vector rules (spec/conformance_rules.csv; the runner adds the unsent-FAP and time-code rules): "
          + ", ".join(f"{rule} {n}" for rule, n in sorted(rules.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
