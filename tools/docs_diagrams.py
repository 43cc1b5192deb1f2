#!/usr/bin/env python3
"""The concepts page's diagrams, drawn from the real pipeline by this script (never by hand):

    .venv/bin/python tools/docs_diagrams.py [--out docs/media]

layers.png     one frame of a spoken sentence at each layer of the decoder's face: the action (the text and
               tags, the frame's viseme and expression as FAP 1/2 carry them), the FAP values the frame
               shows (resolved: FAP 1/2 expanded, unsent FAPs held), the 84 feature points moved on the head
               (neutral and moved, with the displacement drawn), the mesh as a wireframe, the pixels
               rendered. The sentence goes through text -> FAPs -> .fba bits -> decode first, as a
               receiver gets it.
bitstream.png  the same sentence's .fba stream, as ``mpeg4fa info --trace`` lists it (:func:`mpeg4fa.fba.trace.trace`):
               the whole stream with its frames, then the first intra frame and the predicted frames after
               it as a bit ruler, every syntax element a block (its colour its kind), sections labelled.

tools/docs_pictures.py runs it with the other pictures; ``tools/dev.sh docs`` runs that.
"""
from __future__ import annotations

import argparse
import json
import sys
import textwrap
from dataclasses import dataclass
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.collections import LineCollection  # noqa: E402
from matplotlib.patches import Rectangle  # noqa: E402

from mpeg4fa.face import FaceModel  # noqa: E402
from mpeg4fa.fba import decode, encode  # noqa: E402
from mpeg4fa.fba.trace import Element, trace  # noqa: E402
from mpeg4fa.render import Renderer, frame_points  # noqa: E402
from mpeg4fa.spec import EXPRESSIONS, FAPS, VISEMES  # noqa: E402

SENTENCE = "(joy, 40, 0.5) Hello! I am an MPEG-4 talking head."
KIND_COLOURS = {"start_code": "#4c72b0", "field": "#dd8452", "marker": "#c7c7c7", "segment": "#55a868",
                "stuffing": "#8172b3", "trailing": "#937860"}
PNG_META = {"Software": "mpeg4fa tools/docs_diagrams.py"}
"""Each picture also carries, as PNG text ``mpeg4fa-figures``, the numbers it draws (tests/docs compares them
with a fresh run, so a picture left behind by a change of the encoder is caught)."""


@dataclass(frozen=True)
class Spoken:
    """A sentence as a receiver gets it: the stream decoded from its bits, and those bits."""

    text: str
    bits: bytes
    stream: object  # FapStream


def spoken(text: str = SENTENCE) -> Spoken:
    from mpeg4fa.speech import encode_text

    bits = encode(encode_text(text).stream)
    return Spoken(text, bits, decode(bits))


# ---- the four layers -----------------------------------------------------------------------------------------
def busiest_frame(values: np.ndarray) -> int:
    """The frame whose resolved low-level FAPs move most (sum of |value|): the layers show most there."""
    return int(np.argmax(np.abs(values).sum(axis=1)))


def layer_data(face: FaceModel, said: Spoken, frame: int | None = None) -> dict:
    """Everything the layers figure draws, as numbers (also what tests/docs checks)."""
    from mpeg4fa.decoded import resolve

    values = resolve(said.stream)  # (n, 68): what the receiver shows, columns 0/1 (FAP 1/2) expanded away
    frame = busiest_frame(values) if frame is None else frame
    neutral = face.neutral()
    pose = face.deform(values[frame])
    return {"frame": frame, "values": values[frame], "neutral": neutral, "pose": pose,
            "viseme": _high_level(said.stream, frame, "viseme"),
            "expression": _high_level(said.stream, frame, "expression")}


def _high_level(stream, frame: int, kind: str) -> str:
    """FAP 1 or 2 of ``frame`` as text: 'select1 / select2 blend' or 'intensity' (held from the last frame sent)."""
    column = 0 if kind == "viseme" else 1
    sent = np.flatnonzero(stream.fap_mask[: frame + 1, column])
    if not len(sent):
        return "none sent"
    k = int(sent[-1])
    if kind == "viseme":
        select1, select2, blend = (int(x) for x in stream.viseme[k, :3])
        names = [x.name for x in VISEMES]
        return f"{names[select1]} / {names[select2]}, blend {blend}/63"
    select1, intensity1 = (int(x) for x in stream.expression[k, :2])
    return f"{EXPRESSIONS[select1].name} {intensity1}/63"


def layers_picture(face: FaceModel, said: Spoken, out: Path, size: int = 420) -> dict:
    data = layer_data(face, said)
    pose, neutral, values = data["pose"], data["neutral"], data["values"]
    camera = frame_points(face.mesh.feature_points(), size, size, margin=0.25)
    renderer = Renderer(face, width=size, height=size, samples=4, camera=camera)
    pixels = renderer.render(pose)
    fig = plt.figure(figsize=(11, 9.6), dpi=100)
    rows = fig.add_gridspec(2, 1, height_ratios=[1.15, 1], hspace=0.18)
    top = rows[0].subgridspec(1, 3, width_ratios=[0.9, 0.42, 1.5], wspace=0.05)  # [1]: room for the FAP names
    bottom = rows[1].subgridspec(1, 3, wspace=0.06)
    grid = [top[0], top[1], top[2], bottom[0], bottom[1], bottom[2]]

    ax = fig.add_subplot(grid[0])
    ax.axis("off")
    ax.set_title("1. action\nwhat the sender says", loc="left", fontsize=11)
    text = "\n".join([*textwrap.wrap(f'text and tags: "{said.text}"', 30), "",
                      f"-> {len(said.stream)} frames, {len(said.bits)} bytes;", f"this is frame {data['frame']}:", "",
                      "FAP 1 viseme:", f"  {data['viseme']}", "FAP 2 expression:", f"  {data['expression']}"])
    ax.text(0, 0.95, text, va="top", fontsize=9, family="monospace", transform=ax.transAxes)

    ax = fig.add_subplot(grid[2])
    moving = np.flatnonzero(np.abs(values) > 0.5)
    labels = [f"{k + 1} {FAPS[k].name}" for k in moving]
    ax.barh(np.arange(len(moving)), values[moving], color="#dd8452")
    ax.set_yticks(np.arange(len(moving)), labels, fontsize=6.5)
    ax.invert_yaxis()
    ax.axvline(0, color="k", lw=0.6)
    ax.set_xlabel("value (FAPU / 1024 or 1e-5 rad)", fontsize=8)
    ax.tick_params(axis="x", labelsize=7)
    ax.set_title(f"2. FAPs\n{len(moving)} of 66 low-level values move", loc="left", fontsize=11)

    xy0 = camera.project(neutral.feature_points, size, size)[:, :2]
    xy1 = camera.project(pose.feature_points, size, size)[:, :2]
    ax = fig.add_subplot(grid[3])
    ax.imshow(renderer.render(neutral), alpha=0.35)
    ax.add_collection(LineCollection(np.stack([xy0, xy1], axis=1), colors="#c00000", lw=1.2))
    ax.scatter(*xy0.T, s=7, c="#777777", label="neutral")
    ax.scatter(*xy1.T, s=9, c="#c00000", label="moved")
    ax.legend(loc="lower right", fontsize=7, framealpha=0.8)
    moved_mm = np.linalg.norm(pose.feature_points - neutral.feature_points, axis=1)
    moved_count = int((moved_mm > 0.05).sum())
    ax.set_title(f"3. feature points\n{moved_count} of 84 moved (by value x FAPU)", loc="left", fontsize=11)
    _frame_axes(ax, size)

    ax = fig.add_subplot(grid[4])
    skin = face.mesh.all_triangles(("skin",))
    xyz = camera.project(pose.vertices, size, size)
    front = _front_facing(xyz, skin)
    tri = skin[front]
    edges = np.unique(np.sort(np.concatenate([tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]), axis=1), axis=0)
    ax.add_collection(LineCollection(xyz[edges][:, :, :2], colors="#4c72b0", lw=0.25))
    ax.set_title(f"4. mesh\n{len(face.mesh.vertices):,} vertices follow the points", loc="left", fontsize=11)
    _frame_axes(ax, size)

    ax = fig.add_subplot(grid[5])
    ax.imshow(pixels)
    ax.set_title(f"5. pixels\nrendered by OpenGL, {size}x{size}", loc="left", fontsize=11)
    _frame_axes(ax, size)
    figures = {"bytes": len(said.bits), "frame": data["frame"], "values": [round(float(v), 3) for v in values]}
    fig.savefig(out / "layers.png", bbox_inches="tight", metadata={**PNG_META, "mpeg4fa-figures": json.dumps(figures)})
    plt.close(fig)
    data.update(moving=moving, moved_mm=moved_mm, edges=len(edges))
    return data


def _front_facing(xyz: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """Triangles facing the camera in screen space (y down: clockwise on screen is front)."""
    a, b, c = (xyz[tri[:, i], :2] for i in range(3))
    cross = (b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1]) - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0])
    facing = cross < 0
    return facing if facing.sum() >= (~facing).sum() * 0.5 else ~facing  # whichever way the mesh winds


def _frame_axes(ax, size: int) -> None:
    ax.set_xlim(0, size)
    ax.set_ylim(size, 0)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])


# ---- the bitstream ---------------------------------------------------------------------------------------------
SHORT = {"fba_object_start_code": "object start code", "FAP 1 (viseme) segment": "FAP 1 viseme",
         "FAP 2 (expression) segment": "FAP 2 expression", "FAP segment": "FAPs 3-68", "BAP segment": "BAPs",
         "fba_object_end_code": "end code"}


def section(e: Element) -> str:
    """The part of the syntax an element belongs to, for the ruler's brackets (runs of one section get one)."""
    if e.kind in ("start_code", "segment", "trailing", "stuffing"):
        return SHORT.get(e.name, e.name)
    name = e.name
    if "mask" in name and name != "fba_object_mask":
        return "group masks"
    if "range" in name or name.startswith(("is_i_", "is_p_")):
        return "coder ranges"
    if name.endswith("_def") or name == "init_face":
        return name
    return "header"


ROW_HEIGHT = 2.0  # ruler units a row takes: the block, then four staggered lines of labels


def bitstream_picture(said: Spoken, out: Path, frames: int = 3, row_bits: int = 112) -> dict:
    elements = list(trace(said.bits))
    total = elements[-1].end
    per_frame: dict[int, list[Element]] = {}
    for e in elements:
        if e.frame is not None:
            per_frame.setdefault(e.frame, []).append(e)
    frame_bits = {f: sum(e.width for e in es) for f, es in per_frame.items()}
    intra = {f for f, es in per_frame.items() if any(e.name == "is_intra" and e.value == 1 for e in es)}
    shown = [e for e in elements if (e.frame is None and e.offset == 0) or (e.frame is not None and e.frame < frames)]
    end = shown[-1].end
    rows = -(-end // row_bits)
    fig = plt.figure(figsize=(16, 2.2 + 0.75 * rows * ROW_HEIGHT), dpi=100)
    grid = fig.add_gridspec(2, 1, height_ratios=[1.2, rows * ROW_HEIGHT * 0.75], hspace=0.5)

    ax = fig.add_subplot(grid[0])
    x0 = elements[0].width
    ax.add_patch(Rectangle((0, 0), x0, 1, color=KIND_COLOURS["start_code"]))
    for f in sorted(frame_bits):
        colour = KIND_COLOURS["field"] if f in intra else KIND_COLOURS["segment"]
        ax.add_patch(Rectangle((x0, 0), frame_bits[f], 1, facecolor=colour, edgecolor="white", lw=0.4))
        x0 += frame_bits[f]
    ax.add_patch(Rectangle((x0, 0), total - x0, 1, color=KIND_COLOURS["start_code"]))
    ax.add_patch(Rectangle((0, -0.12), end, 0.08, color="k", clip_on=False))
    ax.text(end + 8, -0.08, f"bits 0-{end}: below", va="center", fontsize=8)
    ax.set_xlim(0, total)
    ax.set_ylim(-0.15, 1)
    ax.set_yticks([])
    ax.set_xlabel("bit", fontsize=8)
    ax.tick_params(labelsize=7)
    p_bits = [b for f, b in frame_bits.items() if f not in intra]
    ax.set_title(f"The whole stream of \"{said.text}\": {len(said.bits)} bytes, {len(frame_bits)} frames at 25 fps.\n"
                 f"Intra frames (orange): {', '.join(str(frame_bits[f]) for f in sorted(intra))} bits; predicted "
                 f"frames (green): {min(p_bits)}-{max(p_bits)} bits, mean {np.mean(p_bits):.1f}; start and end "
                 "codes (blue).", loc="left", fontsize=10)

    ax = fig.add_subplot(grid[1])
    for e in shown:
        _ruler_block(ax, e, row_bits)
    runs: list[list] = []  # [section, first offset, end, frame]
    for e in shown:
        label = section(e)
        if runs and runs[-1][0] == label and runs[-1][3] == e.frame and runs[-1][2] == e.offset:
            runs[-1][2] = e.end
        else:
            runs.append([label, e.offset, e.end, e.frame])
    level_end: dict[tuple[int, int], float] = {}
    for label, a, b, frame in runs:
        _ruler_bracket(ax, label, a, b, row_bits, level_end)
    for f in range(frames):
        first = per_frame[f][0].offset
        row, x = divmod(first, row_bits)
        ax.annotate(f"frame {f} ({'intra' if f in intra else 'predicted'}, {frame_bits[f]} bits)",
                    (x, row * ROW_HEIGHT), (x, row * ROW_HEIGHT - 0.32), fontsize=8, fontweight="bold",
                    arrowprops={"arrowstyle": "-", "lw": 0.8})
    for r in range(rows):
        ax.text(-2, r * ROW_HEIGHT + 0.25, f"{r * row_bits}", ha="right", va="center", fontsize=7)
    ax.set_xlim(-10, row_bits + 1)
    ax.set_ylim(rows * ROW_HEIGHT, -0.7)
    ax.axis("off")
    ax.set_title(f"Frames 0-{frames - 1} as `mpeg4fa info --trace` lists them, {row_bits} bits a row, one block "
                 "per syntax element: start code (blue), header field (orange), marker bit (grey), "
                 "arithmetic-coded segment (green)", loc="left", fontsize=10)
    figures = {"bytes": len(said.bits), "frames": len(frame_bits),
               "frame_bits": [frame_bits[f] for f in sorted(frame_bits)]}
    fig.savefig(out / "bitstream.png", bbox_inches="tight",
                metadata={**PNG_META, "mpeg4fa-figures": json.dumps(figures)})
    plt.close(fig)
    return {"elements": elements, "frame_bits": frame_bits, "intra": intra, "shown_end": end, "runs": runs}


def _pieces(a: int, b: int, row_bits: int):
    """(row, start, stop) pieces of the bit span [a, b) wrapped at ``row_bits``."""
    while a < b:
        row, start = divmod(a, row_bits)
        stop = min(b, (row + 1) * row_bits)
        yield row, start, start + stop - a
        a = stop


def _ruler_block(ax, e: Element, row_bits: int) -> None:
    for row, x0, x1 in _pieces(e.offset, e.end, row_bits):
        ax.add_patch(Rectangle((x0, row * ROW_HEIGHT), x1 - x0, 0.5, facecolor=KIND_COLOURS[e.kind],
                               edgecolor="white", lw=0.5))


CHAR_BITS = 0.62  # how many bits of the ruler one character of a 7-point label takes, about


def _ruler_bracket(ax, label: str, a: int, b: int, row_bits: int, level_end: dict) -> None:
    """A bracket under the bits [a, b) and its label, on the first of three lines below the row where it fits."""
    for i, (row, x0, x1) in enumerate(_pieces(a, b, row_bits)):
        y = row * ROW_HEIGHT + 0.58
        ax.plot([x0 + 0.12, x0 + 0.12, x1 - 0.12, x1 - 0.12], [y, y + 0.06, y + 0.06, y], color="k", lw=0.7)
        text = f"{label} ({b - a})" if i == 0 else f"{label}, cont."
        width = len(text) * CHAR_BITS
        centre = (x0 + x1) / 2
        left = max(centre - width / 2, 0)
        level = next((k for k in range(4) if level_end.get((row, k), -1e9) < left), 3)
        level_end[(row, level)] = left + width + 1
        ty = y + 0.2 + 0.3 * level
        if level:
            ax.plot([centre, centre], [y + 0.06, ty - 0.05], color="#888888", lw=0.5)
        ax.text(left, ty, text, ha="left", va="top", fontsize=7)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "media")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    said = spoken()
    layers_picture(FaceModel.default(), said, args.out)
    bitstream_picture(said, args.out)
    for name in ("layers.png", "bitstream.png"):
        print(f"{(args.out / name)}  {(args.out / name).stat().st_size // 1024} KiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
