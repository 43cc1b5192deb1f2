"""The suite's report: ``report.md`` and ``report.html`` with a summary per group and, per failure,
what was expected against what came out, with a PNG plot of the trajectory at fault.

Why plots: a wrong FAPU or a swapped side is a number off in a table, but a curve beside the
expected one shows at a glance whether it is a scale (FAPU, AU), a sign, a lag (hold instead of
interpolate) or a time axis (frame rate). Plots use matplotlib's Agg backend (no display).
"""
from __future__ import annotations

import html
from pathlib import Path

import numpy as np

from mpeg4fa.conformance.compare import FAIL, STATUSES, Check, pinned_axes
from mpeg4fa.conformance.runner import SuiteResult, VectorResult

MAX_PLOTS = 200
"""Plots drawn at most (a decoder failing everything gets a table, not thousands of images)."""


def _trajectories(v: VectorResult, check: Check) -> tuple[str, np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]] | None:
    """(y label, time axis, {curve name: (expected, got)}) for a failed check, or None if nothing to plot."""
    out, exp = v.result.output if v.result else None, v.expected
    if out is None or exp is None or check.status != FAIL or "expected_frames" in check.worst:
        return None
    t = np.asarray(exp.get("timestamps", np.arange(len(out))), dtype=np.float64)
    if check.name == "timestamps":
        return "time (s)", np.arange(len(t), dtype=np.float64), {"timestamp": (t, out.timestamps)}
    if check.name in ("shown", "sent") and "fap" in check.worst:
        col = check.worst["fap"] - 1
        if check.name == "shown":
            want, got = np.asarray(exp["shown"])[:, col], out.shown[:, col]
        elif out.sent is not None:
            want, got = np.asarray(exp["sent"]["values"])[:, col], out.sent["values"][:, col]
        else:
            return None
        return f"FAP {col + 1} ({'FAPU' if check.name == 'shown' else 'sent'})", t, {f"FAP {col + 1}": (want, got)}
    if check.name == "feature_points" and "label" in check.worst and out.fp_positions is not None:
        label = check.worst["label"]
        fp = exp["feature_points"]
        j = list(fp["labels"]).index(label)
        want = np.asarray(fp["positions"], dtype=np.float64)[:, j]
        got = out.fp_positions[:, list(out.fp_labels).index(label)]
        axes = pinned_axes(fp, len(out))[:, j].any(axis=0)
        curves = {f"{label}.{name}": (want[:, i], got[:, i]) for i, name in enumerate("xyz") if axes[i]}
        return "position (FDP units)", t, curves
    return None


def plot(v: VectorResult, check: Check, path: Path) -> bool:
    """Draw the failed check's trajectory (expected dashed, decoder solid) into ``path``; False if none."""
    series = _trajectories(v, check)
    if series is None:
        return False
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    ylabel, t, curves = series
    fig = Figure(figsize=(6.4, 1.2 + 2.0 * len(curves)), dpi=100)
    axes = fig.subplots(len(curves), 1, sharex=True, squeeze=False)[:, 0]  # one panel each: own scale
    for i, (ax, (name, (want, got))) in enumerate(zip(axes, curves.items())):
        colour = f"C{i}"
        ax.plot(t[:len(want)], want, "--", color=colour, linewidth=2.2, alpha=0.6, label=f"{name} expected")
        ax.plot(t[:len(got)], got, "-", color=colour, linewidth=1.2, marker=".", label=f"{name} decoder")
        ax.set_ylabel(ylabel, fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    axes[-1].set_xlabel("frame" if check.name == "timestamps" else "time (s)")
    axes[0].set_title(f"{v.vector.id}: {check.name}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return True


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)


def _failures(suite: SuiteResult) -> list[tuple[VectorResult, Check]]:
    return [(v, c) for v in suite.vectors for c in v.checks if c.status not in ("pass", "not supported")]


def _worst_text(check: Check) -> str:
    w = check.worst
    if "expected" in w and "got" in w:
        return f"expected {w['expected']}, got {w['got']}"
    return ""


def write_report(suite: SuiteResult, folder: Path) -> dict[str, Path]:
    """Write report.md, report.html and the plots into ``folder``; return their paths by kind."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    plots: dict[tuple[str, str], str] = {}
    for v, c in _failures(suite)[:MAX_PLOTS]:
        name = f"{_slug(v.vector.id)}-{c.name}.png"
        if plot(v, c, folder / name):
            plots[(v.vector.id, c.name)] = name
    md = _markdown(suite, plots)
    (folder / "report.md").write_text(md, encoding="utf-8")
    (folder / "report.html").write_text(_html(suite, plots), encoding="utf-8")
    return {"markdown": folder / "report.md", "html": folder / "report.html",
            **{f"plot:{k[0]}:{k[1]}": folder / p for k, p in plots.items()}}


def _summary_rows(suite: SuiteResult) -> list[list[str]]:
    rows = []
    for group, s in suite.summary().items():
        rows.append([group + ("" if s["required"] or group == "informative" else " (informative)"), str(s["vectors"]), str(s["checks"]),
                     *(str(s[k]) for k in STATUSES), str(s["vectors_failed"])])
    return rows


_HEAD = ["group", "vectors", "checks", *STATUSES, "vectors failing the suite"]


def _markdown(suite: SuiteResult, plots: dict[tuple[str, str], str]) -> str:
    verdict = "PASSED" if suite.passed else "FAILED"
    lines = [f"# Conformance report: {suite.decoder}", "",
             f"Suite `{suite.suite}`, {len(suite.vectors)} vectors in {suite.seconds:.1f} s: **{verdict}** "
             "(every required check passes; informative vectors and \"not supported\" optional checks do not fail it).",
             "", "| " + " | ".join(_HEAD) + " |", "|" + "---|" * len(_HEAD)]
    lines += ["| " + " | ".join(row) + " |" for row in _summary_rows(suite)]
    failures = _failures(suite)
    lines += ["", f"## Failures ({len(failures)})", ""]
    if not failures:
        lines.append("None.")
    for v, c in failures:
        required = "required" if v.vector.required else "informative"
        lines += [f"### {v.vector.id}: {c.name} ({c.status}, {required})", "",
                  f"{v.vector.description}", "", f"- result: {c.message}"]
        if _worst_text(c):
            lines.append(f"- worst: {_worst_text(c)}")
        if v.vector.rules:
            lines.append(f"- rules: {'; '.join(v.vector.rules)}")
        if (v.vector.id, c.name) in plots:
            lines += ["", f"![{v.vector.id} {c.name}]({plots[(v.vector.id, c.name)]})"]
        lines.append("")
    unsupported = sorted({c.name for v in suite.vectors for c in v.checks if c.status == "not supported"})
    if unsupported:
        lines += ["## Not supported", "", f"Optional checks the decoder gives no output for: {', '.join(unsupported)}.", ""]
    return "\n".join(lines) + "\n"


def _html(suite: SuiteResult, plots: dict[tuple[str, str], str]) -> str:
    e = html.escape
    verdict = "PASSED" if suite.passed else "FAILED"
    colour = {"pass": "#2e7d32", "fail": "#c62828", "not supported": "#757575", "crash": "#6a1b9a",
              "timeout": "#ef6c00"}
    head = "".join(f"<th>{e(h)}</th>" for h in _HEAD)
    rows = "".join("<tr>" + "".join(f"<td>{e(c)}</td>" for c in row) + "</tr>" for row in _summary_rows(suite))
    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>Conformance report: {e(suite.decoder)}</title>",
             "<style>body{font-family:sans-serif;max-width:60em;margin:auto}table{border-collapse:collapse}"
             "td,th{border:1px solid #ccc;padding:2px 8px;text-align:right}td:first-child{text-align:left}"
             ".s{font-weight:bold}</style></head><body>",
             f"<h1>Conformance report: {e(suite.decoder)}</h1>",
             f"<p>Suite <code>{e(suite.suite)}</code>, {len(suite.vectors)} vectors in {suite.seconds:.1f} s: "
             f"<b>{verdict}</b></p>", f"<table><tr>{head}</tr>{rows}</table>"]
    failures = _failures(suite)
    parts.append(f"<h2>Failures ({len(failures)})</h2>" + ("<p>None.</p>" if not failures else ""))
    for v, c in failures:
        parts.append(f"<h3>{e(v.vector.id)}: {e(c.name)} <span class='s' style='color:{colour.get(c.status, '#000')}'>"
                     f"{e(c.status)}</span> ({'required' if v.vector.required else 'informative'})</h3>"
                     f"<p>{e(v.vector.description)}</p><p>{e(c.message)}</p>")
        if _worst_text(c):
            parts.append(f"<p>{e(_worst_text(c))}</p>")
        if (v.vector.id, c.name) in plots:
            parts.append(f"<img src='{e(plots[(v.vector.id, c.name)])}' alt='{e(v.vector.id)}'>")
    parts.append("<h2>All vectors</h2><table><tr><th>vector</th><th>confidence</th>"
                 + "".join(f"<th>{n}</th>" for n in ("checks", "status", "seconds")) + "</tr>")
    for v in suite.vectors:
        checks = ", ".join(f"{c.name}: {c.status}" for c in v.checks)
        parts.append(f"<tr><td>{e(v.vector.id)}</td><td>{e(v.vector.confidence)}</td><td>{e(checks)}</td>"
                     f"<td style='color:{colour.get(v.status, '#000')}'>{e(v.status)}</td><td>{v.seconds:.3f}</td></tr>")
    parts.append("</table></body></html>")
    return "\n".join(parts) + "\n"
