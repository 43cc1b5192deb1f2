#!/usr/bin/env python
"""Timing of the Sibson coordinates (mpeg4fa.face.sibson) and the RBF field (mpeg4fa.face.rbf).

A script run on demand, not a test::

    .venv/bin/python tools/bench_sibson.py [--sites 20 100 110] [--queries 5000 20000] [--repeat 3]

For every (sites, queries) pair it draws random control points in the unit cube,
adds the 14 :func:`cage_points`, draws random queries in the cube and reports,
in one process pinned to one core where the platform allows it: the one-time
triangulation, the weights (best of ``--repeat``), the mean number of natural
neighbours per query, and the worst linear-precision error ``|W @ sites - x|``;
then the same for an RbfField through the same controls.  The target is 5,000
queries against about 100 sites well under 1 s.
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from mpeg4fa.face.rbf import RbfField  # noqa: E402
from mpeg4fa.face.sibson import NaturalNeighbours, cage_points  # noqa: E402


def best(fn, repeat: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeat):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sites", type=int, nargs="+", default=[20, 100, 110])
    ap.add_argument("--queries", type=int, nargs="+", default=[5000, 20000])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args(argv)
    if hasattr(os, "sched_setaffinity"):
        try:
            os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})
        except OSError:
            pass
    rng = np.random.default_rng(args.seed)
    print(f"{'sites':>6} {'+cage':>6} {'tets':>5} {'queries':>8} {'build s':>8} {'weights s':>10} "
          f"{'nn/query':>9} {'lin err':>9} {'rbf s':>7}")
    ok = True
    for n in args.sites:
        pts = rng.random((n, 3))
        sites = np.vstack([pts, cage_points(pts)])
        t_build, nn = best(lambda sites=sites: NaturalNeighbours(sites), args.repeat)
        for m in args.queries:
            queries = rng.random((m, 3))
            nn.weights(queries[:10])  # warm up
            t_w, W = best(lambda nn=nn, queries=queries: nn.weights(queries), args.repeat)
            lin = float(np.abs(W @ sites - queries).max())
            ok &= lin < 1e-9
            disp = rng.normal(size=(len(sites), 3))
            t_r, _ = best(lambda s=sites, d=disp, q=queries: RbfField(s, d)(q), args.repeat)
            print(f"{n:>6} {len(sites):>6} {len(nn._S):>5} {m:>8} {t_build:>8.4f} {t_w:>10.3f} "
                  f"{W.nnz / m:>9.2f} {lin:>9.1e} {t_r:>7.3f}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
