"""``tools/fuzz.py --jobs N``: chunks of cases in worker processes, their summaries merged into one table.

Why processes and not threads: each case runs under a SIGALRM timer, an address-space cap and a
per-process peak-memory reading, all of which belong to one process; and a case stuck in C code ends
only its own worker (the watchdog's exit status 3), not the campaign. A worker is the ordinary
single-process command on one target and a range of case indices (``--target T --first I --cases N``),
so every case keeps its (target, seed, index) and its replay command. Chunks of the targets are
interleaved, so a run cut short by ``--seconds`` has moved every target forward.
"""
from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path
from typing import Callable

SUMS = ("cases", "ok", "rejected", "crashes", "hangs", "memory", "peak", "mismatches", "unlocated", "seconds")
MAXES = ("peak_mib", "rss_mib", "slowest_wall")
COLUMNS = ("target", "cases", "ok", "rejected", "crash", "hang", "memory", "peak>lim", "mismatch", "unlocated",
           "peak MiB", "rss MiB", "cases/s", "slowest s", "wall s")
"""The summary table: per target, the outcomes, the largest growth of memory in one case (peak MiB) and of
the process's resident memory (rss MiB), cases per second of one process, and the slowest case on the run's
clock (``--clock``: wall or CPU seconds) and on the wall clock."""


def table_rows(summary: dict) -> list[dict]:
    """One row per target and a total, as dicts keyed by :data:`COLUMNS` (also what the JSON keeps)."""
    rows, total = [], {name: 0 for name in SUMS + MAXES}
    for target, t in summary["targets"].items():
        rows.append(dict(zip(COLUMNS, (target, t["cases"], t["ok"], t["rejected"], t["crashes"], t["hangs"],
                                       t["memory"], t["peak"], t["mismatches"], t["unlocated"],
                                       round(t["peak_mib"], 1), round(t.get("rss_mib", 0.0), 1),
                                       round(t["cases"] / max(t["seconds"], 1e-9), 1), round(t["slowest"], 2),
                                       round(t.get("slowest_wall", t["slowest"]), 2)))))
        for name in SUMS:
            total[name] += t[name]
        for name in MAXES:
            total[name] = max(total[name], t.get(name, 0.0))
    rows.append(dict(zip(COLUMNS, ("total", total["cases"], total["ok"], total["rejected"], total["crashes"],
                                   total["hangs"], total["memory"], total["peak"], total["mismatches"],
                                   total["unlocated"], round(total["peak_mib"], 1), round(total["rss_mib"], 1),
                                   round(total["cases"] / max(summary["seconds"], 1e-9), 1), "", ""))))
    return rows


def table(summary: dict) -> str:
    """The rows as aligned text (the total's cases/s is of the whole run, wall clock)."""
    rows = [COLUMNS] + [tuple(row[c] for c in COLUMNS) for row in summary.get("table") or table_rows(summary)]
    widths = [max(len(str(r[k])) for r in rows) for k in range(len(COLUMNS))]
    return "\n".join("  ".join(str(c).rjust(w) if k else str(c).ljust(w) for k, (c, w) in enumerate(zip(r, widths)))
                     for r in rows)


def report(summary: dict, path: Path) -> str:
    """What the command prints: the table, each distinct finding with its replay command, stray warnings."""
    lines = [table(summary)]
    for f in summary["findings"]:
        ours = f.get("project_frame") or ""
        ours = f" (package: {ours})" if ours and ours != f["frame"] else ""
        lines.append(f"{f['kind']}: {f['target']} {f['stage']}: {f['type']} x{f['count']} at {f['frame']}{ours}: "
                     f"{f['message'][:160]} -> {f['reproducer']}  replay: {f.get('replay', '')}")
    for failure in summary.get("worker_failures", []):
        last = failure["first"] + failure["count"] - 1
        lines.append(f"worker failed: {failure['target']} cases {failure['first']}..{last} exit status "
                     f"{failure['rc']}: {failure['tail'][-300:]}")
    for key, message in summary["unlocated_errors"].items():
        lines.append(f"unlocated: {key}: {message[:160]}")
    for key, message in summary["stray_warnings"].items():
        lines.append(f"stray warning: {key}: {message[:160]}")
    lines.append(f"summary: {path}")
    return "\n".join(lines)


def merge(parts: list[dict]) -> dict:
    """One summary of several workers' summaries: counts added, maxima kept, findings joined by key."""
    targets: dict[str, dict] = {}
    findings: dict[str, dict] = {}
    reasons: dict[str, int] = {}
    merged: dict = {"unlocated_errors": {}, "stray_warnings": {}, "seeds": {}}
    for part in parts:
        for name, t in part["targets"].items():
            m = targets.setdefault(name, {**{k: 0 for k in SUMS}, **{k: 0.0 for k in MAXES}, "slowest": 0.0,
                                          "slowest_case": ""})
            for k in SUMS:
                m[k] += t[k]
            for k in MAXES:
                m[k] = max(m[k], t.get(k, 0.0))
            if t["slowest"] > m["slowest"]:
                m["slowest"], m["slowest_case"] = t["slowest"], t["slowest_case"]
        for f in part["findings"]:
            known = findings.get(f["key"])
            if known is None:
                findings[f["key"]] = dict(f)
            else:
                known["count"] += f["count"]
                if f["first_case"] < known["first_case"]:
                    known.update({k: f[k] for k in ("first_case", "reproducer", "replay", "message")})
        for k, v in part["top_rejections"].items():
            reasons[k] = reasons.get(k, 0) + v
        for key in ("unlocated_errors", "stray_warnings", "seeds"):
            for k, v in part.get(key, {}).items():
                merged[key].setdefault(k, v)
    merged["targets"] = targets
    merged["findings"] = sorted(findings.values(), key=lambda f: (f["target"], f["kind"], f["first_case"]))
    merged["top_rejections"] = dict(sorted(reasons.items(), key=lambda kv: -kv[1])[:40])
    return merged


def _chunks(args: argparse.Namespace, targets: list[str]) -> list[tuple[str, int, int]]:
    """``(target, first, count)`` per worker run, the targets interleaved."""
    per = {t: args.per_target if args.per_target is not None
           else args.cases // len(targets) + (k < args.cases % len(targets)) for k, t in enumerate(targets)}
    queues = {t: [(t, args.first + i, min(args.chunk, per[t] - i)) for i in range(0, per[t], args.chunk)]
              for t in targets}
    out = []
    while any(queues.values()):
        for t in targets:
            if queues[t]:
                out.append(queues[t].pop(0))
    return out


def _worker_argv(args: argparse.Namespace, tool: Path, target: str, first: int, count: int, seconds: float,
                 part: Path) -> list[str]:
    argv = [sys.executable, str(tool), "--target", target, "--first", str(first), "--per-target", str(count),
            "--seconds", f"{seconds:.1f}", "--seed", str(args.seed), "--json", str(part), "--out", str(args.out),
            "--case-seconds", str(args.case_seconds), "--memory-gib", str(args.memory_gib),
            "--peak-mib", str(args.peak_mib), "--clock", getattr(args, "clock", "wall"), "--quiet"]
    return argv + (["--no-vectors"] if args.vectors is None else ["--vectors", str(args.vectors)])


def run(args: argparse.Namespace, tool: Path, say: Callable[[str], None]) -> int:
    """Run the chunks ``--jobs`` at a time until done or ``--seconds`` is spent; merge; write and print."""
    from fuzz_inputs import TARGETS

    targets = [t for t in TARGETS if t in args.target]
    work = args.out / "workers"
    work.mkdir(parents=True, exist_ok=True)
    tasks = _chunks(args, targets)
    start = time.monotonic()
    deadline = start + args.seconds
    running: dict[subprocess.Popen, tuple] = {}
    parts, failures, interrupted = [], [], False
    say(f"{len(tasks)} worker runs over {len(targets)} targets, {args.jobs} at a time; logs in {work}")
    try:
        while tasks or running:
            while tasks and len(running) < args.jobs and time.monotonic() < deadline - 1:
                target, first, count = tasks.pop(0)
                part, log = work / f"{target}-{first}.json", work / f"{target}-{first}.log"
                part.unlink(missing_ok=True)
                seconds = deadline - time.monotonic()
                if args.target_seconds:  # a chunk's share of its target's time
                    per = args.per_target or max(args.cases // len(targets), 1)
                    seconds = min(seconds, args.target_seconds * count / per)
                argv = _worker_argv(args, tool, target, first, count, seconds, part)
                with open(log, "w", encoding="utf-8") as handle:
                    proc = subprocess.Popen(argv, stdin=subprocess.DEVNULL, stdout=handle, stderr=subprocess.STDOUT)
                running[proc] = (target, first, count, part, log)
            if not running:
                break
            time.sleep(0.2)
            for proc in [p for p in running if p.poll() is not None]:
                target, first, count, part, log = running.pop(proc)
                if part.exists():
                    summary = json.loads(part.read_text(encoding="utf-8"))
                    parts.append(summary)
                    t = summary["targets"].get(target, {})
                    say(f"{target} {first}..{first + count - 1}: {t.get('cases', 0)} cases, "
                        f"{len(summary['findings'])} findings ({time.monotonic() - start:.0f} s)")
                if proc.returncode not in (0, 1) or not part.exists():
                    tail = log.read_text(encoding="utf-8", errors="replace")[-2000:]
                    failures.append({"target": target, "first": first, "count": count, "rc": proc.returncode,
                                     "tail": tail, "log": str(log)})
                    say(f"{target} {first}..{first + count - 1}: worker exit status {proc.returncode}: "
                        f"{tail.strip().splitlines()[-1] if tail.strip() else ''}")
    except KeyboardInterrupt:  # the workers got the same Ctrl-C: each writes what it found
        interrupted = True
        say("interrupted: waiting for the workers to write what they found")
        for proc, (target, first, count, part, log) in running.items():
            proc.wait()
            if part.exists():
                parts.append(json.loads(part.read_text(encoding="utf-8")))
    elapsed = time.monotonic() - start
    summary = merge(parts)
    summary.update({"seed": args.seed, "seconds": round(elapsed, 1), "jobs": args.jobs, "chunk": args.chunk,
                    "case_seconds": args.case_seconds, "clock": getattr(args, "clock", "wall"),
                    "peak_limit_mib": args.peak_mib,
                    "memory_gib": args.memory_gib, "worker_failures": failures, "interrupted": interrupted,
                    "not_run": [{"target": t, "first": f, "count": c} for t, f, c in tasks],
                    "python": sys.version.split()[0]})
    summary["table"] = table_rows(summary)
    path = args.json or args.out / "fuzz.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(summary, indent=2, default=str), encoding="utf-8")
    if not args.quiet:
        print(report(summary, path))
    bad = sum(t["crashes"] + t["hangs"] + t["memory"] + t["peak"] + t["mismatches"]
              for t in summary["targets"].values())
    return 1 if bad or failures else 0
