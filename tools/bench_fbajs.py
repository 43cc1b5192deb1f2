#!/usr/bin/env python
"""Benchmark: fba.js in Node against the compiled Python decoder, on the same streams in one run.

A script run on demand, not a test::

    .venv/bin/python tools/bench_fbajs.py [--vectors DIR] [--repeat R] [--json OUT]

Streams: the real ``headmotion_long.fba`` (2253 frames, FAP 1, FAP 2 and all groups on every frame;
skipped with a note when ``--vectors`` is absent) and the 60 s full-mask stream of
``tools/bench_codec.py`` (FAP 1, FAP 2 and 66 low-level FAPs on every frame, tight ranges; its
generator is imported, not copied). Each is decoded by ``mpeg4fa.fba.decode(backend="compiled")`` in
this process (CPU time, as for Node; after a warm-up call, so that numba's compile is not counted) and
by ``decode()`` of fba.js in one Node process (``bench_fbajs.mjs``), taking turns: ``--rounds`` turns
of ``--repeat`` calls on each side, so that a busy spell on a shared machine hits both. The Node
process first makes ``--node-warmup`` calls per stream that are not counted, as numba's compile is
not: V8 compiles the decoder in tiers over its first calls (the first call's speed is shown apart).
Reported: the best and the median call of each side and their ratios.

The same work on both sides: each call decodes the whole stream, every value written where it can be
read at once (Python: the FapStream's arrays; Node: one Frame object per frame over the slab of values
the decoder writes, its typed arrays made on first read). As Node leaves those typed arrays to the
first read, it is timed twice: decode() alone, and decode() plus making every frame's four arrays
("arrays made"), the ratio with Python given for both. Checked: every Node call's frame count and last timestamp, the sum of every FAP value of Node's calls
against Python's, and fba.js's frames against the Python decoder's (values, masks, times). Target
(issue 31): Node at least as fast as the compiled path (ratio >= 1; aimed at >= 1.5, best and median,
so that the noise of a shared machine cannot flip it). Then the head posed from the same decoded frames by ``facerig.js``
(the pages' pose, :mod:`mpeg4fa.serve.fap_head`) in Node and by the Python face, per frame, with the
largest vertex difference between them. Prints a table and writes JSON (``tools/bench_fbajs.json``
unless ``--json``).
"""
from __future__ import annotations

import argparse
import json
import platform
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))
sys.path.insert(0, str(REPO / "tools"))

import numpy as np  # noqa: E402

from bench_codec import FPS, INTRA_SECONDS, synthetic_stream  # noqa: E402
from mpeg4fa.fba import EncodeOptions, decode, encode  # noqa: E402

NODE_BENCH = REPO / "tools" / "bench_fbajs.mjs"
DUMP = REPO / "tests" / "js" / "dump.mjs"
POSE = REPO / "tests" / "js" / "pose_rig.mjs"


def cpu_times(fn, repeat: int):
    """(CPU time of this process per call in seconds, result of the last call): CPU time, like the Node
    half, so that a busy neighbour on a shared machine does not count."""
    times, result = [], None
    for _ in range(max(1, repeat)):
        t0 = time.process_time()
        result = fn()
        times.append(time.process_time() - t0)
    return times, result


def best_time(fn, repeat: int):
    """(best CPU time in seconds, result of the last call)."""
    times, result = cpu_times(fn, repeat)
    return min(times), result


class NodeBench:
    """The Node half, one process for the whole run: ``calls(path, n)`` has it decode ``path`` n times."""

    def __init__(self, node: str) -> None:
        self.proc = subprocess.Popen([node, str(NODE_BENCH)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                                     text=True, bufsize=1)

    def calls(self, path: Path, n: int, arrays: bool = False) -> dict:
        self.proc.stdin.write(json.dumps({"path": str(path), "calls": n, "arrays": arrays}) + "\n")
        self.proc.stdin.flush()
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"{NODE_BENCH.name} stopped (exit {self.proc.wait()})")
        return json.loads(line)

    def close(self) -> None:
        self.proc.stdin.close()
        self.proc.wait(timeout=30)


def same_frames(node: str, path: Path, stream) -> bool:
    """fba.js's frames equal the Python decoder's (values, masks, times)."""
    doc = json.loads(subprocess.run([node, str(DUMP), str(path)], capture_output=True, text=True,
                                    check=True).stdout)
    frames = doc["frames"]
    return (doc["error"] is None and len(frames) == len(stream)
            and np.array_equal([f["values"] for f in frames], stream.fap_values)
            and np.array_equal([f["mask"] for f in frames], stream.fap_mask.astype(int))
            and np.array_equal([f["t"] for f in frames], stream.timestamps))


def pose_times(node: str, stream, folder: Path, n: int) -> dict:
    """The head posed from ``n`` decoded frames: facerig.js in Node (the pages' pose) against the Python face
    (``FaceModel.pose_values``, CPU time), and how far apart their vertices are (checked: the same face)."""
    import warnings

    from mpeg4fa.decoded import resolve
    from mpeg4fa.face import FaceModel
    from mpeg4fa.serve.fap_head import rig_data

    face = FaceModel.default()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        values = resolve(stream)[:n]
    rig, rows, out = folder / "rig.json", folder / "rows.json", folder / "poses.bin"
    rig.write_text(json.dumps(rig_data(face)))
    rows.write_text(json.dumps(values.tolist()))
    run = subprocess.run([node, str(POSE), str(rig), str(rows), str(out)], capture_output=True, text=True, check=True)
    node_ms = json.loads(run.stdout)["ms_per_pose"]
    face.pose_values(values[0])  # set-up (rig) not counted
    py_s, poses = best_time(lambda: [face.pose_values(v).vertices for v in values], 1)
    got = np.fromfile(out, "<f8").reshape(len(values), -1, 3)
    return {"frames": len(values), "vertices": got.shape[1], "node_ms_per_pose": node_ms,
            "python_ms_per_pose": py_s / len(values) * 1e3, "max_vertex_difference_mm": float(np.abs(got - poses).max())}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--vectors", type=Path, default=REPO.parent / "shared" / "vectors" / "fba")
    parser.add_argument("--repeat", type=int, default=3, help="calls per turn on each side")
    parser.add_argument("--rounds", type=int, default=15,
                        help="turns of Node then Python per stream (all calls pooled: best and median reported)")
    parser.add_argument("--node-warmup", type=int, default=10,
                        help="Node calls per stream before those counted (V8's tiers compile the decoder)")
    parser.add_argument("--frames", type=int, default=int(60 * FPS), help="frames of the full-mask stream")
    parser.add_argument("--json", type=Path, default=REPO / "tools" / "bench_fbajs.json")
    parser.add_argument("--pose-frames", type=int, default=250, help="frames posed by facerig.js and by Python")
    args = parser.parse_args(argv)
    node = shutil.which("node")
    if node is None:
        print("node is not installed: nothing to compare", file=sys.stderr)
        return 1
    version = subprocess.run([node, "--version"], capture_output=True, text=True).stdout.strip()
    with tempfile.TemporaryDirectory(prefix="bench_fbajs_") as tmp:
        cases = []
        head = args.vectors / "headmotion_long.fba"
        if head.is_file():
            cases.append(("headmotion_long.fba (real)", head))
        else:
            print(f"note: {head} is absent; only the synthetic stream is measured")
        full = Path(tmp) / "full_mask.fba"
        options = EncodeOptions(fap_quant=1, intra_period=int(round(INTRA_SECONDS * FPS)), optimize=True)
        full.write_bytes(encode(synthetic_stream(args.frames), options))
        cases.append((f"full mask, 66 FAPs + FAP 1/2, {args.frames / FPS:g} s", full))
        decode(full, backend="compiled")  # numba's compile, not counted
        node_s: dict[str, list] = {str(p): [] for _, p in cases}
        arrays_s: dict[str, list] = {str(p): [] for _, p in cases}  # decode() plus every frame's arrays made
        first_s: dict[str, float] = {}
        shown_s: dict[str, list] = {str(p): [] for _, p in cases}
        py_s: dict[str, list] = {str(p): [] for _, p in cases}
        decoded: dict[str, set] = {str(p): set() for _, p in cases}  # (frames, sum of FAP values) of Node's calls
        streams = {}
        bench = NodeBench(node)
        try:
            for _, path in cases:
                first_s[str(path)] = bench.calls(path, max(1, args.node_warmup))["times_s"][0]
                bench.calls(path, max(1, args.node_warmup), arrays=True)
            for _ in range(args.rounds):  # turns, so that a busy spell on the machine hits both
                for _, path in cases:
                    key, data = str(path), path.read_bytes()
                    j = bench.calls(path, args.repeat)
                    decoded[key].add((j["frames"], j["value_sum"]))
                    node_s[key] += j["times_s"]
                    shown_s[key] += j["shown_times_s"]
                    arrays_s[key] += bench.calls(path, args.repeat, arrays=True)["times_s"]
                    t, streams[path] = cpu_times(lambda: decode(data, backend="compiled"), args.repeat)
                    py_s[key] += t
        finally:
            bench.close()
        rows = []
        for name, path in cases:
            data = path.read_bytes()
            stream, key = streams[path], str(path)
            if decoded[key] != {(len(stream), int(stream.fap_values.astype(np.int64).sum()))}:
                print(f"{name}: the timed Node calls decoded other frames than Python's", file=sys.stderr)
                return 1
            if not same_frames(node, path, stream):
                print(f"{name}: fba.js decodes differently from the Python decoder", file=sys.stderr)
                return 1
            n = len(stream)
            py_best, py_med = min(py_s[key]), float(np.median(py_s[key]))
            js_best, js_med = min(node_s[key]), float(np.median(node_s[key]))
            rows.append({"stream": name, "frames": n, "bytes": len(data), "calls_each": len(py_s[key]),
                         "python_compiled_fps": n / py_best, "python_compiled_median_fps": n / py_med,
                         "node_fps": n / js_best, "node_median_fps": n / js_med,
                         "node_first_call_fps": n / first_s[key],
                         "node_shown_fps": n / min(shown_s[key]),
                         "ratio_node_over_python": py_best / js_best,
                         "ratio_median_node_over_python": py_med / js_med,
                         "node_arrays_made_fps": n / min(arrays_s[key]),
                         "node_arrays_made_median_fps": n / float(np.median(arrays_s[key])),
                         "ratio_arrays_made_node_over_python": py_best / min(arrays_s[key]),
                         "ratio_arrays_made_median_node_over_python": py_med / float(np.median(arrays_s[key]))})
        pose = pose_times(node, streams[full], Path(tmp), args.pose_frames)
    head_line = (f"{'stream':36} {'frames':>7} {'Python f/s best':>16} {'median':>8} {'Node f/s best':>14} "
                 f"{'median':>8} {'1st call':>9} {'ratio best':>10} {'median':>7}")
    print(f"fba.js (Node {version}) vs mpeg4fa.fba compiled: {args.rounds} turns x {args.repeat} calls on each side "
          f"after warm-up ({args.node_warmup} Node calls, 1 Python call) ({platform.processor() or platform.machine()})")
    print(head_line)
    print("-" * len(head_line))
    for r in rows:
        ok = min(r["ratio_node_over_python"], r["ratio_median_node_over_python"]) >= 1
        print(f"{r['stream']:36} {r['frames']:>7} {r['python_compiled_fps']:>16,.0f} {r['python_compiled_median_fps']:>8,.0f} "
              f"{r['node_fps']:>14,.0f} {r['node_median_fps']:>8,.0f} {r['node_first_call_fps']:>9,.0f} "
              f"{r['ratio_node_over_python']:>9.2f}x {r['ratio_median_node_over_python']:>6.2f}x {'PASS' if ok else 'FAIL'}")
    print("(ratio: Node frames/s over the compiled path's, of the best and of the median calls; target >= 1, "
          "aim >= 1.5. 1st call: the Node process's first call, with V8's warm-up. shown.js resolves "
          + ", ".join(f"{r['node_shown_fps']:,.0f}" for r in rows) + " frames/s on top.)")
    print("with every frame's four typed arrays made in the timed call (fba.js makes them on first read): "
          + "; ".join(f"{r['stream'].split(' ')[0]} {r['node_arrays_made_fps']:,.0f} f/s best, "
                      f"{r['node_arrays_made_median_fps']:,.0f} median, ratio {r['ratio_arrays_made_node_over_python']:.2f}x / "
                      f"{r['ratio_arrays_made_median_node_over_python']:.2f}x" for r in rows))
    print(f"\nthe head posed (facerig.js, the player's pose) from {pose['frames']} frames of the full-mask stream, "
          f"{pose['vertices']} vertices: Node {pose['node_ms_per_pose']:.2f} ms/frame, Python "
          f"{pose['python_ms_per_pose']:.2f} ms/frame, vertices at most {pose['max_vertex_difference_mm']:.1e} mm apart")
    args.json.write_text(json.dumps({"node": version, "repeat": args.repeat, "rounds": args.rounds,
                                     "node_warmup": args.node_warmup, "rows": rows,
                                     "pose": pose}, indent=2))
    print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
