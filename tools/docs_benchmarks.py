#!/usr/bin/env python3
"""The Benchmarks page's tables and plots, made from the JSON the benchmarks in tools/ write (never typed in):

    .venv/bin/python tools/docs_benchmarks.py                 # print the page's generated part (Markdown)
    .venv/bin/python tools/docs_benchmarks.py --plots DIR     # also write its plots (PNG) into DIR
    .venv/bin/python tools/docs_benchmarks.py --run NAME [-- ARGS]   # run tools/bench_NAME.py, keep its JSON

A benchmark's figures live in ``tools/bench_NAME.json`` (committed). ``--run`` runs the benchmark under
``nice -n 5`` with the page's small options (or ARGS), writes its JSON there and adds ``_made``: the machine
(CPU, cores, system, Python), the date and the command, which every table on the page then states. A JSON
written by the benchmark itself, without ``_made``, is shown with what it says about its machine and the date
of its last commit. A benchmark with no JSON gets a line saying how to make it. The site's hook
(docs/hooks.py) calls :func:`page_markdown` and :func:`plots` at every build, so the page cannot drift from
the JSON.
"""
from __future__ import annotations

import argparse
import datetime as dt
import io
import json
import os
import platform
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

ROOT = Path(__file__).resolve().parents[1]
TOOLS = ROOT / "tools"
MARKER = "<!-- mpeg4fa:benchmarks -->"
PLOT_DIR = "pictures/bench"  # where the plots go in the site


@dataclass(frozen=True)
class Bench:
    """One benchmark of tools/: what it measures, how its JSON is asked for, the small options ``--run`` uses."""

    name: str
    title: str
    what: str
    json_flag: str = "--json"
    small: tuple[str, ...] = ()
    tool: str = ""
    """The script that writes the JSON when it is not ``bench_NAME.py`` (one script, several kinds of run)."""
    required: tuple[str, ...] = ()
    """Options every run needs, small or plain (what it is compared against)."""

    @property
    def script(self) -> Path:
        return TOOLS / f"bench_{self.tool or self.name}.py"

    @property
    def json_path(self) -> Path:
        return TOOLS / f"bench_{self.name}.json"

    def command(self, extra: tuple[str, ...] | None = None) -> list[str]:
        args = [*self.required, *(self.small if extra is None else extra)]
        return [".venv/bin/python", f"tools/{self.script.name}", *args, self.json_flag,
                f"tools/bench_{self.name}.json"]


BENCHES: tuple[Bench, ...] = (
    Bench("codec", "FBA codec: speed, size, memory",
          "encode and decode frames/s of the reference and compiled paths, the real vectors, memory",
          small=("--only", "0", "--only", "1", "--repeat", "2")),
    Bench("encoder", "Text encoder: bits per frame",
          "bits per frame of each English and Chinese sentence encoded on its own at the high level",
          small=("--sentences-only",)),
    Bench("align", "Aligning a recording to its transcript",
          "pocketsphinx and DTW phone onsets against the truth (within 30 ms), x real time",
          small=("--quick",)),
    Bench("face", "Face engine", "head rig, calibration per method, frames/s of every deformer, memory"),
    Bench("calibration", "Calibration methods", "DFFD, RBF and elastic calibration on the same FDPs",
          small=("--repeat", "1")),
    Bench("render", "Rendering", "decode + deform + render + readback per frame, MP4/PNG export, memory",
          small=("--repeat", "2")),
    Bench("render_eyes", "Rendering against the tree before the eyes' shaders",
          "per-frame stages of this checkout and of an earlier one timed in turns, best of each, and their ratio",
          tool="render", required=("--against", "OLD_CHECKOUT")),
    Bench("fbajs", "fba.js in Node against the compiled Python decoder", "frames/s of both on the same streams",
          small=("--repeat", "3", "--rounds", "2")),
    Bench("photo", "Photo to FDP", "each step of `mpeg4fa fdp PHOTO` and the whole command", json_flag="--out",
          small=("--repeat", "2")),
    Bench("tracking", "Video tracking", "a 640x480 face video end to end, per stage", json_flag="--out",
          small=("--seconds", "4", "--repeat", "1")),
    Bench("serve", "Live server", "latency from text to first frame and delivery of a long speech"),
    Bench("live", "Live speech", "a spoken WAV fed live: latency and delivery"),
    Bench("lipsync_audio", "Lip sync from audio alone",
          "closures and visemes recognised without a transcript against the transcript path's track, on espeak-ng "
          "speech in six languages (recordings of people with `--human DIR`, against their transcript's forced "
          "alignment); rest on silence, noise and music; speed"),
    Bench("lipsync_festival", "Lip sync from audio alone, on festival's voices",
          "English closures recognised without a transcript against festival's own segment times (a second "
          "synthesiser: an HTS voice and two diphone voices, none in the closure detector's training); "
          "needs `apt install festival festvox-kallpc16k festvox-kdlpc16k festvox-us-slt-hts`",
          small=("--voices", "slt")),
    Bench("batch", "Batch on Dask", "the same streams rendered on 1 and 2 local workers",
          small=("--streams", "4", "--seconds", "2")),
    Bench("bits", "bitstring against the codec's BitReader", "header fields, single bits, whole decodes"),
)


# ---- running a benchmark ------------------------------------------------------------------------------------
def machine() -> str:
    """This machine in one line: CPU model, cores, system, Python (the tables say where their figures come from)."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    system = platform.system()
    try:
        fields = dict(re.findall(r'^(\w+)="?([^"\n]*)"?$', Path("/etc/os-release").read_text(), re.M))
        system = fields.get("PRETTY_NAME", system)
    except OSError:
        pass
    return f"{cpu}, {os.cpu_count()} cores, {system}, Python {platform.python_version()}"


def run(bench: Bench, extra: tuple[str, ...] | None = None) -> Path:
    """Run ``bench`` (nice -n 5) with its small options or ``extra``, then stamp its JSON with ``_made``."""
    command = bench.command(extra)
    started = dt.datetime.now(dt.timezone.utc)
    load_before = os.getloadavg()[0]
    subprocess.run(["nice", "-n", "5", sys.executable, *command[1:]], cwd=ROOT, check=True)
    data = json.loads(bench.json_path.read_text(encoding="utf-8"))
    data["_made"] = {"machine": machine(), "date": started.strftime("%Y-%m-%d %H:%M UTC"),
                     "command": shlex.join(command),
                     "load": f"load average {load_before:.1f} before, {os.getloadavg()[0]:.1f} after"}
    bench.json_path.write_text(json.dumps(data, indent=1, default=str) + "\n", encoding="utf-8")
    return bench.json_path


# ---- the page ----------------------------------------------------------------------------------------------
MAX_ROWS = 40
SKIP_KEYS = {"_made", "labels"}


def load(bench: Bench) -> dict | None:
    """The benchmark's JSON, or None when it has not been made (or cannot be read: said on the page)."""
    if not bench.json_path.is_file():
        return None
    data = json.loads(bench.json_path.read_text(encoding="utf-8"))
    return data if isinstance(data, dict) else {"rows": data}  # a bare list of rows is one table


def provenance(bench: Bench, data: dict) -> str:
    """Where, when and how the figures were made: ``_made`` when ``--run`` made them, else what the JSON says."""
    made = data.get("_made")
    if isinstance(made, dict):
        load = f" ({made['load']}: other work on the machine slows what it times)" if made.get("load") else ""
        return f"Made on {made['machine']}, {made['date']}, by `{made['command']}`{load}."
    where = data.get("machine")
    if isinstance(where, dict):
        where = ", ".join(f"{k} {v}" for k, v in where.items() if isinstance(v, (str, int, float)) and v != "")
    found = [f"{k} {data[k]}" for k in ("platform", "cpu", "gl_renderer", "renderer", "node", "python")
             if isinstance(data.get(k), (str, int, float))]
    machine_text = where or ", ".join(found) or "a machine the JSON does not name"
    return (f"Made on {machine_text}, {_committed(bench.json_path)}; the command is not recorded in the JSON "
            f"(the benchmark's plain run: `{shlex.join(bench.command(()))}`).")


def _committed(path: Path) -> str:
    done = subprocess.run(["git", "log", "-1", "--format=%cd", "--date=format:%Y-%m-%d %H:%M", "--", str(path)],
                          cwd=ROOT, capture_output=True, text=True)
    if done.returncode == 0 and done.stdout.strip():
        return f"committed {done.stdout.strip()}"
    stamp = dt.datetime.fromtimestamp(path.stat().st_mtime, dt.timezone.utc)
    return f"written {stamp:%Y-%m-%d %H:%M} UTC (not committed yet)"


def number(value: Any) -> str:
    """A figure as the page shows it: thousands separated, three significant digits below 1000."""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, int):
        return f"{value:,}"
    if isinstance(value, float):
        if value != value:
            return "n/a"
        if value == 0 or abs(value) >= 1000:
            return f"{value:,.0f}"
        if abs(value) < 0.001:
            return f"{value:.2g}"
        return f"{value:.3g}"
    if value is None:
        return "-"
    if isinstance(value, list):
        return ", ".join(number(v) for v in value) if len(value) <= 6 else f"({len(value)} values)"
    return str(value).replace("|", "\\|").replace("\n", " ")


def _scalar(value: Any) -> bool:
    return not isinstance(value, (dict, list)) or (isinstance(value, list) and
                                                      not any(isinstance(v, (dict, list)) for v in value))


def _flat(row: dict, prefix: str = "", depth: int = 0) -> dict[str, Any]:
    """A row's scalar fields, nested dicts flattened to ``a.b`` (two levels); lists of dicts are left out."""
    out: dict[str, Any] = {}
    for key, value in row.items():
        if key in SKIP_KEYS:
            continue
        if isinstance(value, dict) and any(re.search(r"[:/]", str(k)) for k in value):
            out[f"{prefix}{key}"] = list(value.values())  # keyed by addresses or paths: the values, in order
        elif isinstance(value, dict) and depth < 2:
            out.update(_flat(value, f"{prefix}{key}.", depth + 1))
        elif _scalar(value):
            out[f"{prefix}{key}"] = value
    return out


def table(rows: list[dict], source: str) -> str:
    """A Markdown table of dict rows (columns: the union of their scalar fields, in order)."""
    flat = [_flat(r) for r in rows]
    columns: list[str] = []
    for r in flat:
        columns += [c for c in r if c not in columns]
    if not columns:
        return ""
    lines = ["| " + " | ".join(c.replace("_", " ") for c in columns) + " |", "|" + " --- |" * len(columns)]
    for r in flat[:MAX_ROWS]:
        lines.append("| " + " | ".join(number(r.get(c)) for c in columns) + " |")
    if len(flat) > MAX_ROWS:
        lines.append(f"\n{len(flat) - MAX_ROWS} more rows in `{source}`.")
    return "\n".join(lines) + "\n"


def _label(row: dict) -> str:
    return next((str(v) for v in row.values() if isinstance(v, str)), "row")


def _caption(name: str) -> str:
    """A table's caption: bold text, not a heading (the page's contents list only the benchmarks)."""
    return f"**{name}**\n\n"


def sections(data: Any, source: str, title: str = "") -> list[str]:
    """The JSON as Markdown: its scalars as one key/value table, each list of records as a table, nested
    objects as their own sections (an object whose values are all objects: one table, a row each)."""
    out: list[str] = []
    if not isinstance(data, dict):
        return out
    heading = _caption(title) if title else ""
    scalars = {k: v for k, v in data.items() if k not in SKIP_KEYS and _scalar(v)}
    if scalars:
        out.append(heading + table([{"figure": k, "value": v} for k, v in scalars.items()], source))
        heading = ""
    grouped = _sibling_records(data)
    for keys in grouped:
        first = keys[0]
        name = f"{title}: {first}" if title else first
        out.append(heading + _caption(f"{name}, ...")
                   + table([{"": k, **data[k]} for k in keys], source))
        heading = ""
    done = {k for keys in grouped for k in keys}
    for key, value in data.items():
        if key in SKIP_KEYS or key in done or _scalar(value):
            continue
        name = f"{title}: {key}" if title else key
        if isinstance(value, list):
            records = [v for v in value if isinstance(v, dict)]
            if records:
                out.append(heading + _caption(name) + table(records, source))
                heading = ""
                for row in records[:MAX_ROWS]:
                    for sub, inner in row.items():
                        if isinstance(inner, list) and inner and all(isinstance(v, dict) for v in inner):
                            out.append(_caption(f"{name}: {_label(row)}, {sub}")
                                       + table(inner, source))
        elif isinstance(value, dict):
            if len(value) >= 2 and all(isinstance(v, dict) for v in value.values()) and \
                    all(all(_scalar(x) or isinstance(x, dict) for x in v.values()) for v in value.values()):
                out.append(heading + _caption(name)
                           + table([{"": k, **v} for k, v in value.items()], source))
                heading = ""
            else:
                out += sections(value, source, name)
    return out


def _sibling_records(data: dict) -> list[list[str]]:
    """Keys of sibling objects of scalars with the same fields (``deformer_fap``, ``deformer_arkit``...): each
    such set of two or more is one table, a row per key."""
    by_fields: dict[tuple[str, ...], list[str]] = {}
    for key, value in data.items():
        if key not in SKIP_KEYS and isinstance(value, dict) and value and all(_scalar(v) for v in value.values()):
            by_fields.setdefault(tuple(k for k in value if k not in SKIP_KEYS), []).append(key)
    return [keys for keys in by_fields.values() if len(keys) >= 2]


def bench_markdown(bench: Bench, plotted: set[str]) -> str:
    head = f"### {bench.title}\n\n`tools/{bench.script.name}`: {bench.what}.\n\n"
    try:
        data = load(bench)
    except (OSError, ValueError) as exc:
        return head + f"`{bench.json_path.relative_to(ROOT)}` cannot be read ({exc}).\n"
    if data is None:
        return head + (f"No figures committed yet. To make them: `{shlex.join(bench.command(()))}`, or "
                       f"`.venv/bin/python tools/docs_benchmarks.py --run {bench.name}` (small options, and the "
                       "machine, date and command recorded), then build the docs again.\n")
    parts = [head, provenance(bench, data) + "\n"]
    if f"{bench.name}.png" in plotted:
        parts.append(f"\n![{bench.title}]({PLOT_DIR}/{bench.name}.png)\n")
    elif bench.name in PLOT_ERRORS:
        parts.append(f"\nNo plot: {PLOT_ERRORS[bench.name]}.\n")
    parts.append("\n" + "\n".join(sections(data, f"tools/bench_{bench.name}.json")))
    return "".join(parts)


def page_markdown(plotted: set[str] | None = None) -> str:
    """The page's generated part: every benchmark's tables (and plot, when ``plotted`` names it)."""
    plotted = set(plots()) if plotted is None else plotted
    present = [b for b in BENCHES if b.json_path.is_file()]
    missing = [b for b in BENCHES if not b.json_path.is_file()]
    known = {b.json_path for b in BENCHES}
    others = [Bench(p.stem[len("bench_"):], p.stem, "figures of a benchmark this page does not describe yet")
              for p in sorted(TOOLS.glob("bench_*.json")) if p not in known]
    out = [f"Generated from {len(present) + len(others)} benchmark JSON files in `tools/` by "
           "`tools/docs_benchmarks.py` when the site is built.\n"]
    out += [bench_markdown(b, plotted) for b in present + others]
    if missing:
        out.append("### Not measured yet\n")
        out += [f"- **{b.title}** (`tools/{b.script.name}`: {b.what}): no JSON committed; make it with "
                f"`{shlex.join(b.command(()))}`" for b in missing]
    return "\n".join(out) + "\n"


# ---- the plots -----------------------------------------------------------------------------------------------
def _bars(ax, labels: list[str], groups: dict[str, list[float]], unit: str, log: bool = False) -> None:
    """Horizontal bars: one row per label, one bar per group (series), values printed at their ends."""
    import numpy as np

    n = len(groups)
    height = 0.8 / max(n, 1)
    y = np.arange(len(labels))
    for k, (name, values) in enumerate(groups.items()):
        v = np.array([np.nan if x is None else x for x in values], float)
        bars = ax.barh(y + (k - (n - 1) / 2) * height, v, height, label=name)
        for bar, x in zip(bars, v):
            if x == x:
                ax.text(bar.get_width(), bar.get_y() + bar.get_height() / 2, f" {number(float(x))}",
                        va="center", fontsize=7)
    ax.set_yticks(y, labels, fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel(unit, fontsize=8)
    if log:
        ax.set_xscale("log")
    ax.tick_params(axis="x", labelsize=7)
    if n > 1:
        ax.legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
    ax.margins(x=0.18)


def _plot_codec(d: dict, fig) -> None:
    cases = d["paths"]["cases"]
    ax = fig.add_subplot(111)
    labels = [f"{c['name']}\n{op}" for c in cases for op in ("decode", "encode")]
    _bars(ax, labels, {"reference (Python)": [c["python"][f"{op}_fps"] for c in cases for op in ("decode", "encode")],
                       "compiled (numba)": [c["compiled"][f"{op}_fps"] for c in cases for op in ("decode", "encode")]},
          "frames per second (log)", log=True)
    ax.set_title("FBA codec: frames per second, one core", loc="left", fontsize=10)


def _plot_encoder(d: dict, fig) -> None:
    ax = fig.add_subplot(111)
    for lang in d["sentences"]:
        bpf = [s["bits_per_frame"] for s in lang["sentences"]]
        ax.plot(sorted(bpf), range(1, len(bpf) + 1), marker="o", ms=3, label=f"{lang['language']} "
                f"(mean {lang['mean']:.1f})")
    ax.set_xlabel("bits per frame of a sentence (high level, 25 fps)", fontsize=8)
    ax.set_ylabel("sentences at or below", fontsize=8)
    ax.legend(fontsize=7)
    ax.set_title("Text encoder: bits per frame, each sentence on its own", loc="left", fontsize=10)


def _plot_face(d: dict, fig) -> None:
    ax = fig.add_subplot(111)
    names = [k for k in d if k.startswith("deformer_")]
    _bars(ax, [k[len("deformer_"):] for k in names], {"frames/s": [d[k]["frames_per_s"] for k in names]},
          "frames per second (one frame's mesh deformed)")
    ax.set_title("Face engine: deformers", loc="left", fontsize=10)


def _plot_calibration(d: dict, fig) -> None:
    rows = d["rows"]
    fdps = list(dict.fromkeys(r["fdp"] for r in rows))
    methods = list(dict.fromkeys(r["method"] for r in rows))
    by = {(r["fdp"], r["method"]): r for r in rows}
    ax = fig.add_subplot(121)
    _bars(ax, fdps, {m: [by.get((f, m), {}).get("seconds") for f in fdps] for m in methods}, "seconds")
    ax.set_title("Calibration: time per FDP", loc="left", fontsize=10)
    ax = fig.add_subplot(122)
    _bars(ax, fdps, {m: [by.get((f, m), {}).get("max_error_mm") for f in fdps] for m in methods},
          "largest feature-point error after calibration, mm")
    ax.set_yticks([])


def _plot_fbajs(d: dict, fig) -> None:
    ax = fig.add_subplot(111)
    rows = d["rows"]
    _bars(ax, [r["stream"] for r in rows], {"Python, compiled": [r["python_compiled_fps"] for r in rows],
                                            "fba.js in Node": [r["node_fps"] for r in rows]},
          "frames per second decoded")
    ax.set_title(f"fba.js (Node {d.get('node', '')}) against the compiled Python decoder", loc="left", fontsize=10)


def _plot_photo(d: dict, fig) -> None:
    ax = fig.add_subplot(111)
    steps = d["steps_ms"]
    _bars(ax, list(steps), {"ms": list(steps.values())}, "milliseconds (best of the repeats)")
    ax.set_title(f"Photo to FDP, each step ({d.get('photo', '')})", loc="left", fontsize=10)


def _plot_align(d: dict, fig) -> None:
    ax = fig.add_subplot(111)
    rows = d["synthetic"]
    methods = list(dict.fromkeys(f"{r['method']} ({r['reference_rate']})" for r in rows))
    voices = list(dict.fromkeys(f"{r['voice']} at {r['rate']} wpm" for r in rows))
    by = {(f"{r['voice']} at {r['rate']} wpm", f"{r['method']} ({r['reference_rate']})"): r for r in rows}
    _bars(ax, voices, {m: [100 * by[(v, m)]["within_30ms"] if (v, m) in by else None for v in voices]
                       for m in methods}, "phone onsets within 30 ms, %")
    ax.set_title("Alignment of a recording to its transcript", loc="left", fontsize=10)


def _plot_batch(d: dict, fig) -> None:
    ax = fig.add_subplot(111)
    rows = d["rows"]
    _bars(ax, [f"{r['workers']} worker(s), {r['lp_num_threads']} llvmpipe threads" for r in rows],
          {"wall": [r["wall_s"] for r in rows], "warm (first job left out)": [r["warm_s"] for r in rows]},
          f"seconds for {d['streams']} streams of {d['seconds']} s at {d['size']} px")
    ax.set_title("Batch rendering on a local Dask cluster", loc="left", fontsize=10)


def _plot_render(d: dict, fig) -> None:
    ax = fig.add_subplot(121)
    sizes = [k for k in d if k.startswith("per_frame")]
    stages = [k for k in d[sizes[0]] if k not in ("total", "frames") and not k.endswith("_s")]
    _bars(ax, [k[len("per_frame "):] for k in sizes],
          {stage: [1000 * d[k][stage] for k in sizes] for stage in stages}, "milliseconds a frame")
    ax.set_title(f"Playback per frame on {d['gl'].get('GL_RENDERER', 'GL')}", loc="left", fontsize=10)
    ax = fig.add_subplot(122)
    _bars(ax, list(d["export"]), {"x real time": [v["speed_x_realtime"] for v in d["export"].values()]},
          "x real time (1 = as fast as it plays)")
    ax.axvline(1.0, color="k", lw=0.6)
    ax.set_title("Export", loc="left", fontsize=10)


def _plot_tracking(d: dict, fig) -> None:
    ax = fig.add_subplot(111)
    stages = d["stages_s"]
    _bars(ax, [*stages, "end to end"], {"ms a frame": [1000 * v / d["frames"] for v in
                                                      [*stages.values(), d["end_to_end_s"]]]},
          f"milliseconds a frame ({1000 / d['target_fps']:.0f} ms = the {d['target_fps']:g} frames/s target)")
    ax.axvline(1000 / d["target_fps"], color="k", lw=0.6)
    ax.set_title(f"Video tracking, 640x480: {d['end_to_end_fps']:.1f} frames/s end to end", loc="left", fontsize=10)


PLOT_ERRORS: dict[str, str] = {}
"""Why the last :func:`plots` drew no plot for a benchmark whose JSON is there (the page says it)."""

PLOTS: dict[str, tuple[Callable[[dict, Any], None], tuple[float, float]]] = {
    "codec": (_plot_codec, (8, 3.2)), "encoder": (_plot_encoder, (7, 3.2)), "face": (_plot_face, (7, 2.6)),
    "calibration": (_plot_calibration, (11, 4.5)), "fbajs": (_plot_fbajs, (8, 2.4)),
    "photo": (_plot_photo, (8, 3)), "align": (_plot_align, (8, 3.4)), "batch": (_plot_batch, (8, 2.4)),
    "render": (_plot_render, (12, 2.8)), "tracking": (_plot_tracking, (8, 2.4)),
}


def plots() -> dict[str, bytes]:
    """``NAME.png`` -> PNG bytes of each benchmark with JSON and a plot; a plot whose JSON lacks what it draws
    is left out (its tables still show), and a line on stderr says so."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out: dict[str, bytes] = {}
    PLOT_ERRORS.clear()
    for bench in BENCHES:
        if bench.name not in PLOTS:
            continue
        try:
            data = load(bench)
        except (OSError, ValueError):
            continue
        if data is None:
            continue
        draw, size = PLOTS[bench.name]
        fig = plt.figure(figsize=size, dpi=100)
        try:
            draw(data, fig)
            fig.tight_layout()
            buffer = io.BytesIO()
            fig.savefig(buffer, format="png", metadata={"Software": "mpeg4fa tools/docs_benchmarks.py"})
            out[f"{bench.name}.png"] = buffer.getvalue()
        except (KeyError, TypeError, ValueError, IndexError) as exc:
            PLOT_ERRORS[bench.name] = (f"`{bench.json_path.name}` is not in the form its plot was written for "
                                       f"({type(exc).__name__}: {exc})")
            print(f"docs_benchmarks: no plot for {bench.json_path.name}: {exc!r}", file=sys.stderr)
        finally:
            plt.close(fig)
    return out


def main(argv: list[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    extra = None
    if "--" in argv:
        extra, argv = tuple(argv[argv.index("--") + 1:]), argv[:argv.index("--")]
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--run", choices=[b.name for b in BENCHES], action="append", default=[],
                        help="run this benchmark and keep its JSON in tools/ (repeatable)")
    parser.add_argument("--plots", type=Path, help="write the page's plots (PNG) into this folder")
    args = parser.parse_args(argv)
    for name in args.run:
        run(next(b for b in BENCHES if b.name == name), extra)
    if args.run:
        return 0
    print(page_markdown())
    if args.plots:
        args.plots.mkdir(parents=True, exist_ok=True)
        for name, png in plots().items():
            (args.plots / name).write_bytes(png)
            print(f"{args.plots / name}  {len(png) // 1024} KiB", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
