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

from mpeg4fa.conformance.compare import DIFFERS, FAIL, NOT_SUPPORTED, PASS, STATUSES, Check, pinned_axes
from mpeg4fa.conformance.rules import rule_of
from mpeg4fa.spec import FAP_PARTNERS
from mpeg4fa.conformance.runner import SuiteResult, VectorResult

MAX_PLOTS = 200
"""Plots drawn at most (a decoder failing everything gets a table, not thousands of images)."""


def _trajectories(v: VectorResult, check: Check) -> tuple[str, np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]] | None:
    """(y label, time axis, {curve name: (expected, got)}) for a failed check, or None if nothing to plot."""
    out, exp = v.result.output if v.result else None, v.expected
    if out is None or exp is None or check.status not in (FAIL, DIFFERS):
        return None
    if "expected_frames" in check.worst:  # a frame count off: the worst FAP over the frames both have, by frame
        return _by_frame(out, exp)
    t = np.asarray(exp.get("timestamps", np.arange(len(out))), dtype=np.float64)
    if check.name.startswith("timestamps"):  # the error, in ms: a 1 ms truncation is invisible on a time axis
        frames = np.arange(len(t), dtype=np.float64)
        if len(out.timestamps) == len(t):
            tol = check.worst.get("tolerance", 0.0) * 1e3
            return f"decoder - expected (ms), tolerance {tol:g}", frames, \
                {"time stamp error": (np.zeros(len(t)), (out.timestamps - t) * 1e3)}
        return "time (s)", frames, {"timestamp": (t, out.timestamps)}
    if check.name.startswith(("shown", "sent")) and "fap" in check.worst:
        col = check.worst["fap"] - 1
        if check.name.startswith("shown"):
            want, got = np.asarray(exp["shown"])[:, col], out.shown[:, col]
        elif out.sent is not None:
            want, got = np.asarray(exp["sent"]["values"])[:, col], out.sent["values"][:, col]
        else:
            return None
        curves = {f"FAP {col + 1}": (want, got)}
        if check.name == "shown_partner":  # the counterpart that was sent, whose value the decoder may copy
            for partner in FAP_PARTNERS[col]:
                if partner >= 0:
                    curves[f"FAP {partner + 1} (sent counterpart)"] = (np.asarray(exp["shown"])[:, partner],
                                                                       out.shown[:, partner])
        return f"FAP ({'FAPU' if check.name.startswith('shown') else 'sent'})", t, curves
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


def _by_frame(out, exp) -> tuple[str, np.ndarray, dict[str, tuple[np.ndarray, np.ndarray]]] | None:
    """For an answer with the wrong number of frames: the FAP that differs most over the frames both have
    (or the time stamps), against the frame number, each curve as long as it is."""
    want = np.asarray(exp["shown"], dtype=np.float64)
    n = min(len(want), len(out))
    frames = np.arange(max(len(want), len(out)), dtype=np.float64)
    if n and np.abs(out.shown[:n] - want[:n]).max() > 0:
        col = int(np.argmax(np.abs(out.shown[:n] - want[:n]).max(axis=0)))
        return f"FAP {col + 1} (FAPU) by frame", frames, {f"FAP {col + 1}": (want[:, col], out.shown[:, col])}
    return "time (s) by frame", frames, {"timestamp": (np.asarray(exp["timestamps"], dtype=np.float64), out.timestamps)}


def plot(v: VectorResult, check: Check, path: Path) -> bool:
    """Draw the check's trajectory (expected dashed, decoder solid) into ``path``; False if there is none.
    Never raises on a decoder's answer: curves of different lengths are drawn each over its own frames."""
    try:
        series = _trajectories(v, check)
    except (KeyError, IndexError, ValueError, TypeError):
        return False
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
        want, got = np.asarray(want, dtype=np.float64), np.asarray(got, dtype=np.float64)
        ax.plot(_axis(t, len(want)), want, "--", color=colour, linewidth=2.2, alpha=0.6, marker="o", fillstyle="none",
                markersize=7, label=f"{name} expected")
        ax.plot(_axis(t, len(got)), got, "-", color=colour, linewidth=1.2, marker=".", label=f"{name} decoder")
        ax.set_ylabel(ylabel, fontsize=8)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    axes[-1].set_xlabel("frame" if check.name.startswith("timestamps") or "by frame" in ylabel else "time (s)")
    axes[0].set_title(f"{v.vector.id}: {check.name} (rule {check.rule})", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return True


def _axis(t: np.ndarray, n: int) -> np.ndarray:
    """``n`` x positions: the time axis where it is long enough, then whole frames on from its end."""
    if n <= len(t):
        return t[:n]
    step = float(t[-1] - t[-2]) if len(t) > 1 and np.isfinite(t[-2:]).all() else 1.0
    tail = (t[-1] if len(t) else -step) + step * np.arange(1, n - len(t) + 1)
    return np.concatenate([t, tail])


def _slug(text: str) -> str:
    return "".join(c if c.isalnum() or c in "-_" else "_" for c in text)


def _failures(suite: SuiteResult) -> list[tuple[VectorResult, Check]]:
    """Checks of required rules that failed, crashed or timed out (what fails the suite), in suite order."""
    return [(v, c) for v in suite.vectors for c in v.checks if c.status not in (PASS, NOT_SUPPORTED, DIFFERS)]


def _differences(suite: SuiteResult) -> list[tuple[VectorResult, Check]]:
    """Checks of informative rules the decoder does not meet (reported, never failed)."""
    return [(v, c) for v in suite.vectors for c in v.checks if c.status == DIFFERS]


def _worst_text(check: Check) -> str:
    """Where it went wrong and by how much: frame, FAP or point, expected against got."""
    w = check.worst
    place = []
    if "frame" in w:
        place.append(f"frame {w['frame']}")
    if "fap" in w:
        place.append(f"FAP {w['fap']}")
    if "label" in w:
        place.append(f"feature point {w['label']}")
    if "expected" in w and "got" in w:
        return f"{', '.join(place) + ': ' if place else ''}expected {w['expected']}, got {w['got']}"
    if "expected_frames" in w:
        return f"{w['frames']} frames, expected {w['expected_frames']}"
    return ", ".join(place)


def _rule_text(check: Check) -> tuple[str, str]:
    rule = rule_of(check.name, {check.name: check.rule} if check.rule else None)
    kind = "required" if rule.required else "informative"
    return f"{rule.id} [{rule.confidence}], {kind}", f"{rule.statement} (source: {rule.source})"


def write_report(suite: SuiteResult, folder: Path) -> dict[str, Path]:
    """Write report.md, report.html and the plots into ``folder``; return their paths by kind. Plots: every
    required failure up to :data:`MAX_PLOTS`, and the first difference of each informative rule."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    plots: dict[tuple[str, str], str] = {}
    first_of_rule: dict[str, tuple[VectorResult, Check]] = {}
    for v, c in _differences(suite):
        first_of_rule.setdefault(c.rule, (v, c))
    for v, c in _failures(suite)[:MAX_PLOTS] + list(first_of_rule.values()):
        name = f"{_slug(v.vector.id)}-{_slug(c.name)}.png"
        if plot(v, c, folder / name):
            plots[(v.vector.id, c.name)] = name
    atomic_write(folder / "report.md", _markdown(suite, plots))
    atomic_write(folder / "report.html", _html(suite, plots))
    return {"markdown": folder / "report.md", "html": folder / "report.html",
            **{f"plot:{k[0]}:{k[1]}": folder / p for k, p in plots.items()}}


def atomic_write(path: Path, text: str) -> None:
    """Write ``text`` beside ``path`` and move it there, so a report is whole or absent."""
    tmp = path.with_name(f".{path.name}.tmp")
    tmp.write_text(text, encoding="utf-8")
    tmp.replace(path)


def _summary_rows(suite: SuiteResult) -> list[list[str]]:
    rows = []
    for group, s in suite.summary().items():
        rows.append([group, str(s["vectors"]), str(s["checks"]), *(str(s[k]) for k in STATUSES), str(s["vectors_failed"])])
    return rows


_HEAD = ["group", "vectors", "checks", *STATUSES, "vectors failing the suite"]
_RULE_HEAD = ["rule", "confidence", "kind", "checks", "vectors", "what the decoder did", "first", "source"]


def _rule_rows(suite: SuiteResult) -> list[list[str]]:
    rows = []
    for g in suite.by_rule():
        did = "; ".join(f"{k} ({n})" for k, n in g["decoder_did"].items()) or \
            ", ".join(f"{n} {s}" for s, n in g["statuses"].items())
        rows.append([g["rule"], g["confidence"], "required" if g["required"] else "informative", str(g["checks"]),
                     str(len(g["vectors"])), did, g["example"], g["source"]])
    return rows


def _md_cell(text: str) -> str:
    return text.replace("|", "\\|").replace("\n", " ")


def _markdown(suite: SuiteResult, plots: dict[tuple[str, str], str]) -> str:
    verdict = "PASSED" if suite.passed else "FAILED"
    lines = [f"# Conformance report: {suite.decoder}", "",
             f"Suite `{suite.suite}`, {len(suite.vectors)} vectors in {suite.seconds:.1f} s: **{verdict}** "
             "(every check of a required rule passes: V or S rules of `spec/conformance_rules.csv`; checks of "
             "informative rules \"differ\" at most, and optional checks may be \"not supported\").",
             "", "| " + " | ".join(_HEAD) + " |", "|" + "---|" * len(_HEAD)]
    lines += ["| " + " | ".join(row) + " |" for row in _summary_rows(suite)]
    rule_rows = _rule_rows(suite)
    lines += ["", f"## Findings by rule ({len(rule_rows)})", "",
              "One row per rule the decoder does not meet: required rules fail the suite, informative ones "
              "are what the decoder does where the standard leaves it open or no source settles it.", ""]
    if rule_rows:
        lines += ["| " + " | ".join(_RULE_HEAD) + " |", "|" + "---|" * len(_RULE_HEAD)]
        lines += ["| " + " | ".join(_md_cell(c) for c in row) + " |" for row in rule_rows]
    else:
        lines.append("None: every check passed.")
    failures = _failures(suite)
    lines += ["", f"## Failures ({len(failures)})", ""]
    if not failures:
        lines.append("None.")
    lines += _md_items(failures, plots)
    differences = _differences(suite)
    lines += ["", f"## Informative differences ({len(differences)}): reported, never failed", ""]
    if not differences:
        lines.append("None.")
    lines += _md_items(differences, plots)
    unsupported = sorted({c.name for v in suite.vectors for c in v.checks if c.status == NOT_SUPPORTED})
    if unsupported:
        lines += ["## Not supported", "", f"Optional checks the decoder gives no output for: {', '.join(unsupported)}.", ""]
    return "\n".join(lines) + "\n"


def _md_items(items: list[tuple[VectorResult, Check]], plots: dict[tuple[str, str], str]) -> list[str]:
    lines = []
    for v, c in items:
        rule, statement = _rule_text(c)
        lines += [f"### {v.vector.id}: {c.name} ({c.status}, rule {rule})", "", f"{v.vector.description}", "",
                  f"- result: {c.message}"]
        if _worst_text(c):
            lines.append(f"- where: {_worst_text(c)}")
        lines.append(f"- rule: {statement}")
        if v.vector.rules:
            lines.append(f"- vector's sources: {'; '.join(v.vector.rules)}")
        if (v.vector.id, c.name) in plots:
            lines += ["", f"![{v.vector.id} {c.name}]({plots[(v.vector.id, c.name)]})"]
        lines.append("")
    return lines


def _html(suite: SuiteResult, plots: dict[tuple[str, str], str]) -> str:
    e = html.escape
    verdict = "PASSED" if suite.passed else "FAILED"
    colour = {"pass": "#2e7d32", "fail": "#c62828", "differs": "#1565c0", "not supported": "#757575",
              "crash": "#6a1b9a", "timeout": "#ef6c00"}

    def table(head: list[str], rows: list[list[str]]) -> str:
        return ("<table><tr>" + "".join(f"<th>{e(h)}</th>" for h in head) + "</tr>"
                + "".join("<tr>" + "".join(f"<td>{e(c)}</td>" for c in row) + "</tr>" for row in rows) + "</table>")

    parts = [f"<!doctype html><html><head><meta charset='utf-8'><title>Conformance report: {e(suite.decoder)}</title>",
             "<style>body{font-family:sans-serif;max-width:70em;margin:auto}table{border-collapse:collapse}"
             "td,th{border:1px solid #ccc;padding:2px 8px;text-align:right;vertical-align:top}td:first-child{text-align:left}"
             ".s{font-weight:bold}.r td{text-align:left}</style></head><body>",
             f"<h1>Conformance report: {e(suite.decoder)}</h1>",
             f"<p>Suite <code>{e(suite.suite)}</code>, {len(suite.vectors)} vectors in {suite.seconds:.1f} s: "
             f"<b>{verdict}</b> (every check of a required rule, V or S, passes; informative rules only differ)</p>",
             table(_HEAD, _summary_rows(suite))]
    rule_rows = _rule_rows(suite)
    parts.append(f"<h2>Findings by rule ({len(rule_rows)})</h2>")
    parts.append(("<div class='r'>" + table(_RULE_HEAD, rule_rows) + "</div>") if rule_rows else "<p>None.</p>")
    for title, items in ((f"Failures ({len(_failures(suite))})", _failures(suite)),
                         (f"Informative differences ({len(_differences(suite))}): reported, never failed",
                          _differences(suite))):
        parts.append(f"<h2>{e(title)}</h2>" + ("<p>None.</p>" if not items else ""))
        for v, c in items:
            rule, statement = _rule_text(c)
            parts.append(f"<h3>{e(v.vector.id)}: {e(c.name)} <span class='s' style='color:{colour.get(c.status, '#000')}'>"
                         f"{e(c.status)}</span> (rule {e(rule)})</h3>"
                         f"<p>{e(v.vector.description)}</p><p>{e(c.message)}</p>")
            if _worst_text(c):
                parts.append(f"<p>where: {e(_worst_text(c))}</p>")
            parts.append(f"<p>rule: {e(statement)}</p>")
            if (v.vector.id, c.name) in plots:
                parts.append(f"<img src='{e(plots[(v.vector.id, c.name)])}' alt='{e(v.vector.id)}'>")
    parts.append("<h2>All vectors</h2><table><tr><th>vector</th><th>confidence</th>"
                 + "".join(f"<th>{n}</th>" for n in ("checks", "status", "seconds")) + "</tr>")
    for v in suite.vectors:
        checks = ", ".join(f"{c.name} [{c.rule}]: {c.status}" for c in v.checks)
        parts.append(f"<tr><td>{e(v.vector.id)}</td><td>{e(v.vector.confidence)}</td><td>{e(checks)}</td>"
                     f"<td style='color:{colour.get(v.status, '#000')}'>{e(v.status)}</td><td>{v.seconds:.3f}</td></tr>")
    parts.append("</table></body></html>")
    return "\n".join(parts) + "\n"
