"""Closed loop of the video tracker (issue 27 item 3): a known FAP stream played on a head textured from a real
photo, rendered to MP4, tracked back, and compared per FAP group.

    .venv/bin/python tools/track_loop.py [--seconds 12] [--size 384] [--fps 25] [--out out/track_loop] [--still-head]

The stream sent: English speech with expression tags (the low-level visemes and expressions of
``encode_text``, engine ``estimate``: no audio needed), blinks every 1.1-1.7 s, eye gaze, and head turns
(yaw up to 30 degrees, pitch 12, roll 10). The head: the generic head wearing scikit-image's astronaut,
baked through her landmarks (``mpeg4fa.tracking.find_landmarks`` -> feature points ->
``render.texture.bake_texture``). What was sent is the stream *decoded* (quantised, as a player shows it).

Per group: correlation of tracked with sent, RMS error as a share of the range the sent values use, and
the thresholds of the issue (correlation >= 0.9, RMS <= 15 %); blinks: sent blink peaks found in the
tracked lids within a frame (>= 95 %). Writes OUT/track_loop.json, OUT/track_loop.png (sent vs tracked, per
group), the video OUT/loop.mp4 and OUT/loop.fba (the tracked stream); prints a table.

Two more rows say where a shortfall comes from. ``engine``: the tracker's FAP rules
(:func:`mpeg4fa.tracking.faps.fap_values`) on the head's own feature points as the face engine poses them
(no picture, no landmark model, no head turn): what is lost there is the rules' fault. ``gain``: per FAP,
the least-squares slope of tracked on sent (1 when the tracked motion has the sent size; the landmark
model's under-reading of a rendered face shows here). ``--still-head`` sends the same stream without the
head turns, so comparing the two runs separates what the turns cost from what the landmarks cost.
``fapu``: the FAPU measured on the tracked neutral over the head's own (as shares of ES0).
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

GROUPS = {  # the groups: FAP numbers compared together
    "jaw (3)": (3,),
    "lip corners (12/13)": (12, 13),
    "outer lip corners (53/54)": (53, 54),
    "inner lips (4/5)": (4, 5),
    "brows (31-36)": (31, 32, 33, 34, 35, 36),
    "lids (19/20)": (19, 20),
    "head rotation (48-50)": (48, 49, 50),
}
REPORTED = {"gaze (23-26)": (23, 24, 25, 26), "outer lips (51/52)": (51, 52)}
MIN_CORRELATION, MAX_RMS_SHARE, MIN_BLINKS = 0.9, 0.15, 0.95
TEXT = ("(joy, 50, 0.6) Hello there, my friend! How are you today? (surprise, 45, 0.5) Oh, really? "
        "(sadness, 35, 0.6) That is a pity. (joy, 40, 0.5) But we will make it work, I promise. "
        "(anger, 30, 0.5) Never again! (joy, 30, 0.5) Good bye, and see you soon.")
STILL_SECONDS = 1.0  # the face holds still first: the neutral is found there
BLINK_PEAK = 1000  # FAP 19/20 at a blink's peak: the upper lid at the lower one (IRISD0 = 1024)
BLINK_SHAPE = (0.35, 0.85, 1.0, 0.7, 0.3)


def sent_values(seconds: float, fps: float, seed: int = 1, *,
                still_head: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(n, 68) FAP values to send and the frames of the blink peaks (``still_head``: no head turns)."""
    from mpeg4fa.speech.encoder import encode_text

    n = int(round(seconds * fps))
    speech = encode_text(TEXT, engine="estimate", fps=fps, level="low", fold=False).values
    values = np.zeros((n, 68))
    still = int(round(STILL_SECONDS * fps))  # the first second still: the neutral is found there
    values[still:still + len(speech)] = speech[:max(n - still, 0)]
    t = np.arange(n) / fps
    rng = np.random.default_rng(seed)
    blinks, k = [], int((STILL_SECONDS + 0.3) * fps)
    while k + len(BLINK_SHAPE) < n:
        blinks.append(k + 2)
        for j, share in enumerate(BLINK_SHAPE):
            values[k + j, 18:20] = np.maximum(values[k + j, 18:20], share * BLINK_PEAK)
        k += int(rng.uniform(1.1, 1.7) * fps)
    ramp = np.clip(t - STILL_SECONDS, 0, 1)  # motion fades in after the still start
    values[:, 22] = values[:, 23] = 12000 * np.sin(2 * np.pi * 0.23 * t) * ramp       # gaze yaw, AU
    values[:, 24] = values[:, 25] = 8000 * np.sin(2 * np.pi * 0.31 * t + 1.0) * ramp   # gaze pitch
    values[:, 47] = np.radians(12) / 1e-5 * np.sin(2 * np.pi * 0.17 * t + 0.5) * ramp  # head pitch
    values[:, 48] = np.radians(30) / 1e-5 * np.sin(2 * np.pi * 0.11 * t) * ramp        # head yaw
    values[:, 49] = np.radians(10) / 1e-5 * np.sin(2 * np.pi * 0.21 * t + 2.0) * ramp  # head roll
    if still_head:
        values[:, 47:50] = 0.0
    return values, np.array(blinks)


def sent_stream(values: np.ndarray, fps: float):
    """The values as an encoded-then-decoded stream (what a player shows), and its bytes."""
    from mpeg4fa.decoded import resolve
    from mpeg4fa.fba import EncodeOptions, decode, encode
    from mpeg4fa.tracking.tracker import fap_stream

    stream = fap_stream(values, fps)
    used = np.flatnonzero(np.abs(values).max(axis=0) > 0)
    stream.fap_mask[:] = False
    stream.fap_mask[:, used] = True
    stream.fap_values[:, used] = np.rint(values[:, used]).astype(np.int32)
    data = encode(stream, EncodeOptions(fap_quant=1, fps=fps))
    decoded = decode(data)
    return decoded, resolve(decoded)


def textured_head(size: int = 512):
    """The generic head wearing the astronaut (baked through her landmarks), and the baked texture."""
    from skimage import data

    from mpeg4fa.face import FaceModel
    from mpeg4fa.render.texture import PhotoView, bake_texture
    from mpeg4fa.tracking import feature_points, find_landmarks
    from mpeg4fa.tracking.segment import close_openings

    photo = data.astronaut()
    found = find_landmarks(photo, "astronaut")
    points = {k: (float(v[0]), float(v[1])) for k, v in feature_points(found).items()}
    photo = close_openings(photo, found.points)  # her eyes and teeth would show on closed lids and lips
    face = FaceModel.default()
    return face, bake_texture(face.mesh, PhotoView(photo, points, "front"), size=size).image


def render_video(stream, target: Path, size: int, face, texture) -> float:
    from mpeg4fa.render import play

    started = time.perf_counter()
    play(stream, target, face=face, texture=texture, width=size, height=size, samples=2)
    return time.perf_counter() - started


def track_video(path: Path, fps: float | None = None):
    """Track a video file: (values (n, 68), summary)."""
    from mpeg4fa.tracking.tracker import FaceTracker, sendable
    from mpeg4fa.tracking.video import probe_video, read_frames

    info = probe_video(path)
    with FaceTracker(fps or info.fps, where=str(path)) as tracker:
        for rgb in read_frames(path):
            tracker.push(rgb)
        summary = tracker.finish()
        return sendable(tracker.values()), summary  # what the stream sends (no negative jaw)


def engine_values(shown: np.ndarray, face=None) -> np.ndarray:
    """The tracker's FAP rules on the head's own feature points, posed by the face engine from ``shown`` with the
    head held still (head rotation copied from what was sent): the rules' share of any error, without picture
    or landmark model."""
    from mpeg4fa.face import FaceModel
    from mpeg4fa.tracking import faps as rules

    face = face if face is not None else FaceModel.default()
    labels = list(face.mesh.fp_labels)
    index = [labels.index(label) for label in rules.LABELS]
    held = np.array(shown, dtype=np.float64)
    held[:, 47:50] = 0.0
    points = np.stack([face.pose_values(row).feature_points[index] for row in held])
    neutral = rules.Neutral.from_points(face.neutral().feature_points[index])
    out = rules.fap_values(points, neutral, np.zeros((len(points), 3)), rules.receiver(face))
    out[:, 47:50] = shown[:, 47:50]
    return out


def gains(sent: np.ndarray, tracked: np.ndarray) -> dict[str, float]:
    """Per FAP of the compared groups: the least-squares slope of tracked on sent (1: the sent size)."""
    out = {}
    for faps in GROUPS.values():
        for fap in faps:
            a, b = sent[:, fap - 1], tracked[:, fap - 1]
            if float(np.dot(a, a)) > 0:
                out[str(fap)] = round(float(np.dot(a, b) / np.dot(a, a)), 3)
    return out


def fapu_ratios(neutral_points: np.ndarray, face) -> dict[str, float]:
    """Each FAPU the tracker measured on the neutral face over the head's own, both as a share of ES0 (1: the
    same proportions; MNS0 above 1 reads every jaw and lip FAP short by as much)."""
    from mpeg4fa.tracking import faps as rules

    seen = rules.Neutral.from_points(neutral_points[:len(rules.LABELS)]).fapu
    head = face.fapu
    return {name: round((getattr(seen, name) / seen.ES0) / (getattr(head, name) / head.ES0), 3)
            for name in ("IRISD0", "ENS0", "MNS0", "MW0")}


def blink_peaks(lids: np.ndarray, threshold: float) -> np.ndarray:
    """Frames where the mean of FAP 19/20 peaks above ``threshold`` (local maxima of each run above it)."""
    above = lids > threshold
    peaks, k = [], 0
    while k < len(lids):
        if above[k]:
            j = k
            while j < len(lids) and above[j]:
                j += 1
            peaks.append(k + int(np.argmax(lids[k:j])))
            k = j
        else:
            k += 1
    return np.array(peaks, dtype=int)


def compare(sent: np.ndarray, tracked: np.ndarray, blinks: np.ndarray, skip: int = 0) -> dict:
    """Per group: correlation, RMS as a share of the sent range, pass/fail; blinks found within a frame."""
    report = {"groups": {}, "reported": {}}
    s, tr = sent[skip:], tracked[skip:]
    for table, key in ((GROUPS, "groups"), (REPORTED, "reported")):
        for name, faps in table.items():
            cols = [f - 1 for f in faps]
            a, b = s[:, cols].ravel(), tr[:, cols].ravel()
            span = float(np.ptp(a))
            corr = float(np.corrcoef(a, b)[0, 1]) if np.std(a) > 0 and np.std(b) > 0 else 0.0
            rms = float(np.sqrt(np.mean((a - b) ** 2)))
            entry = {"faps": list(faps), "correlation": round(corr, 4), "rms": round(rms, 1),
                     "range": round(span, 1), "rms_share": round(rms / span, 4) if span else None}
            if key == "groups":
                entry["pass"] = bool(corr >= MIN_CORRELATION and span and rms / span <= MAX_RMS_SHARE)
            report[key][name] = entry
    lids = tracked[:, 18:20].mean(axis=1)
    found_peaks = blink_peaks(lids, 0.5 * BLINK_PEAK)
    found = [int(b) for b in blinks if len(found_peaks) and np.abs(found_peaks - b).min() <= 1]
    report["blinks"] = {"sent": len(blinks), "found_within_a_frame": len(found),
                        "share": round(len(found) / max(len(blinks), 1), 4),
                        "extra_peaks": int(max(len(found_peaks) - len(found), 0)),
                        "pass": bool(len(found) >= MIN_BLINKS * len(blinks))}
    report["pass"] = bool(all(g["pass"] for g in report["groups"].values()) and report["blinks"]["pass"])
    return report


def plot(sent: np.ndarray, tracked: np.ndarray, fps: float, target: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = {**GROUPS, **REPORTED}
    fig, axes = plt.subplots(len(panels), 1, figsize=(12, 2.0 * len(panels)), sharex=True)
    t = np.arange(len(sent)) / fps
    for ax, (name, faps) in zip(axes, panels.items()):
        for j, fap in enumerate(faps[:3]):
            colour = f"C{j}"
            ax.plot(t, sent[:, fap - 1], color=colour, lw=1.6, alpha=0.5, label=f"{fap} sent")
            ax.plot(t, tracked[:, fap - 1], color=colour, lw=0.9, ls="--", label=f"{fap} tracked")
        ax.set_ylabel(name, fontsize=8)
        ax.legend(fontsize=6, ncol=6, loc="upper right")
    axes[-1].set_xlabel("seconds")
    fig.tight_layout()
    fig.savefig(target, dpi=80)
    plt.close(fig)


def run(seconds: float, size: int, fps: float, out: Path, *, texture_size: int = 512,
        still_head: bool = False) -> dict:
    """The whole loop; the report (also written as OUT/track_loop.json with the plot beside it)."""
    from mpeg4fa.fba import encode
    from mpeg4fa.tracking.tracker import fap_stream

    out.mkdir(parents=True, exist_ok=True)
    values, blinks = sent_values(seconds, fps, still_head=still_head)
    stream, shown = sent_stream(values, fps)
    face, texture = textured_head(texture_size)
    engine = compare(shown, engine_values(shown, face), blinks)
    video = out / "loop.mp4"
    render_s = render_video(stream, video, size, face, texture)
    started = time.perf_counter()
    tracked, summary = track_video(video)
    track_s = time.perf_counter() - started
    n = min(len(shown), len(tracked))
    (out / "loop.fba").write_bytes(encode(fap_stream(tracked, fps)))
    report = compare(shown[:n], tracked[:n], blinks[blinks < n])
    report["fapu"] = fapu_ratios(summary.neutral.points, face)
    report.update(still_head=still_head, gain=gains(shown[:n], tracked[:n]),
                  engine={name: {k: g[k] for k in ("correlation", "rms_share", "pass")}
                          for name, g in engine["groups"].items()})
    report.update(seconds=seconds, size=size, fps=fps, frames=n, lost=summary.lost,
                  neutral=[summary.neutral.first, summary.neutral.last], render_s=round(render_s, 2),
                  track_s=round(track_s, 2), track_fps=round(n / track_s, 1))
    plot(shown[:n], tracked[:n], fps, out / "track_loop.png")
    (out / "track_loop.json").write_text(json.dumps(report, indent=1))
    return report


def table(report: dict) -> str:
    lines = [f"{'group':28} {'corr':>6} {'rms':>8} {'range':>8} {'rms/range':>9}  pass   gain    engine corr, rms"]
    for key in ("groups", "reported"):
        for name, g in report[key].items():
            share = f"{100 * g['rms_share']:.1f} %" if g["rms_share"] is not None else "-"
            gain = [report.get("gain", {}).get(str(f)) for f in g["faps"]]
            gain = "/".join(f"{x:.2f}" for x in gain[:2] if x is not None) if any(x is not None for x in gain) else ""
            engine = report.get("engine", {}).get(name)
            engine = (f"{engine['correlation']:.3f}, {100 * (engine['rms_share'] or 0):.1f} %" if engine else "")
            lines.append(f"{name:28} {g['correlation']:6.3f} {g['rms']:8.1f} {g['range']:8.1f} {share:>9}  "
                         f"{'yes' if g.get('pass') else ('no' if 'pass' in g else ''):4} {gain:>9}  {engine}")
    b = report["blinks"]
    lines.append(f"blinks: {b['found_within_a_frame']}/{b['sent']} within a frame ({100 * b['share']:.0f} %), "
                 f"{b['extra_peaks']} extra; lost frames {report['lost']}; neutral frames {report['neutral']}")
    if "fapu" in report:
        lines.append("FAPU measured / the head's (as shares of ES0): "
                     + ", ".join(f"{k} {v:.2f}" for k, v in report["fapu"].items()))
    lines.append(f"render {report['render_s']} s, track {report['track_s']} s ({report['track_fps']} frames/s); "
                 f"all pass: {report['pass']}")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seconds", type=float, default=12.0)
    parser.add_argument("--size", type=int, default=384)
    parser.add_argument("--fps", type=float, default=25.0)
    parser.add_argument("--out", type=Path, default=Path("out/track_loop"))
    parser.add_argument("--still-head", action="store_true", help="send no head turns (what the turns cost)")
    args = parser.parse_args(argv)
    report = run(args.seconds, args.size, args.fps, args.out, still_head=args.still_head)
    print(table(report))
    print(f"wrote {args.out / 'track_loop.json'}, {args.out / 'track_loop.png'}")
    return 0 if report["pass"] else 1


if __name__ == "__main__":
    sys.exit(main())
