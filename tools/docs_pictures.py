#!/usr/bin/env python3
"""The documentation's pictures and animation, made from the real pipeline (never drawn by hand):

    .venv/bin/python tools/docs_pictures.py [--out docs/media] [--contact-sheets]

writes into docs/media/:
  say-hello.gif      the generic head saying an English sentence (text -> espeak-ng -> FAPs -> .fba bits
                     -> decoded -> posed -> rendered), every second frame at 12.5 fps
  say-frame.png      one frame of that sentence, larger
  say-zh-frame.png   one frame of a Mandarin sentence (Chinese visemes from pinyin)
  demo-frame40.png   frame 40 of the built-in demo stream (what `mpeg4fa snapshot demo.fba --frame 40` shows)
  feature-points.png the 84 feature points on the neutral head, coloured by group, with the four FAPU
                     distances measured on it drawn as lines
  layers.png         one spoken frame at each layer: action, FAPs, feature points, mesh, pixels
  bitstream.png      that sentence's .fba stream as a bit ruler from `mpeg4fa info --trace`
                     (both by tools/docs_diagrams.py)
``--contact-sheets`` also runs tools/contact_sheet.py --docs (the sheets in docs/pictures/, its own job).
"""
from __future__ import annotations

import argparse
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from mpeg4fa.face import FaceModel  # noqa: E402
from mpeg4fa.fba import decode, demo_stream, encode  # noqa: E402
from mpeg4fa.render import Renderer, frame_points, snapshot  # noqa: E402
from mpeg4fa.spec import FEATURE_POINTS  # noqa: E402

SENTENCE = "(joy, 40, 0.5) Hello! I am an MPEG-4 talking head."
CHINESE = "(joy, 30, 0.5)你好，世界！"
# FAPU distances drawn on the head as spec/fapu.csv measures them: (name, point a, point b, axis, offset in
# pixels of the measuring line from point a, across the axis: keeps the labels apart)
FAPU_LINES = (("IRISD0", "3.1", "3.3", "y", 0), ("ES0", "3.5", "3.6", "x", -40), ("ENS0", "3.5", "9.15", "y", 0),
              ("MNS0", "9.15", "2.2", "y", -70), ("MW0", "8.3", "8.4", "x", 45))
GROUP_NAMES = {2: "lips, jaw", 3: "eyes", 4: "brows", 5: "cheeks", 6: "tongue", 7: "head", 8: "outer lips",
               9: "nose", 10: "ears", 11: "hairline"}
GROUP_COLOURS = {2: "#e41a1c", 3: "#377eb8", 4: "#4daf4a", 5: "#984ea3", 6: "#ff7f00", 7: "#a65628",
                 8: "#f781bf", 9: "#ffd92f", 10: "#17becf", 11: "#999999"}


def spoken_frames(face: FaceModel, text: str) -> list:
    """Poses of ``text`` as a receiver shows them: encoded to bits and decoded again, not shortcut."""
    from mpeg4fa.speech import encode_text

    stream = decode(encode(encode_text(text).stream))
    return list(face.animate(stream))


def renderer(face: FaceModel, size: int) -> Renderer:
    camera = frame_points(face.mesh.feature_points(), size, size, margin=0.25)
    return Renderer(face, width=size, height=size, samples=4, camera=camera)


def say_pictures(face: FaceModel, out: Path) -> None:
    poses = spoken_frames(face, SENTENCE)
    small = renderer(face, 240)
    frames = [Image.fromarray(small.render(p)).convert("P", palette=Image.Palette.ADAPTIVE, colors=128)
              for p in poses[::2]]
    frames[0].save(out / "say-hello.gif", save_all=True, append_images=frames[1:], duration=80, loop=0,
                   optimize=True)
    big = renderer(face, 360)
    open_mouth = max(range(len(poses)), key=lambda i: _mouth_opening(face, poses[i]))
    Image.fromarray(big.render(poses[open_mouth])).save(out / "say-frame.png", optimize=True)
    zh = spoken_frames(face, CHINESE)
    open_mouth = max(range(len(zh)), key=lambda i: _mouth_opening(face, zh[i]))
    Image.fromarray(big.render(zh[open_mouth])).save(out / "say-zh-frame.png", optimize=True)


def _mouth_opening(face: FaceModel, pose) -> float:
    """Distance between the inner lip midpoints 2.2 and 2.3 (mm): picks a frame where the mouth shows."""
    labels = [p.label for p in FEATURE_POINTS]
    return float(np.linalg.norm(pose.feature_points[labels.index("2.2")] - pose.feature_points[labels.index("2.3")]))


def demo_picture(face: FaceModel, out: Path) -> None:
    image = snapshot(demo_stream(), frame=40, face=face, width=360, height=360, samples=4)
    Image.fromarray(image).save(out / "demo-frame40.png", optimize=True)


def feature_point_picture(face: FaceModel, out: Path, size: int = 560) -> None:
    pose = face.deform({})
    draw_renderer = renderer(face, size)
    image = Image.fromarray(draw_renderer.render(pose)).convert("RGB")
    xy = draw_renderer.camera.project(pose.feature_points, size, size)[:, :2]
    labels = [p.label for p in FEATURE_POINTS]
    draw = ImageDraw.Draw(image)
    fapu = face.fapu
    for name, a, b, axis, offset in FAPU_LINES:
        pa, pb = xy[labels.index(a)], xy[labels.index(b)]
        if axis == "x":  # a horizontal distance, drawn at a's height moved by offset
            ends = [(pa[0], pa[1] + offset), (pb[0], pa[1] + offset)]
        else:  # a vertical distance, drawn at a's x moved by offset
            ends = [(pa[0] + offset, pa[1]), (pa[0] + offset, pb[1])]
        draw.line(ends, fill="#ffffff", width=2)
        for end in ends:
            draw.ellipse([end[0] - 2, end[1] - 2, end[0] + 2, end[1] + 2], fill="#ffffff")
        mid = np.mean(ends, axis=0)
        text = f"{name} {getattr(fapu, name):.1f} mm"
        if name == "IRISD0":  # a short line across the iris: its label goes up and out, with a leader
            label = (mid[0] + 34, mid[1] - 62)
            draw.line([tuple(mid), (label[0], label[1] + 12)], fill="#ffffff", width=1)
            draw.text(label, text, fill="#ffffff")
        elif axis == "y" and offset < 0:  # a line left of the face's middle: its label to its left
            draw.text((mid[0] - 6 - 6 * len(text), mid[1] - 6), text, fill="#ffffff")
        else:
            draw.text((mid[0] + 5, mid[1] - 14) if axis == "x" else (mid[0] + 5, mid[1] - 6), text, fill="#ffffff")
    for point, (x, y) in zip(FEATURE_POINTS, xy):
        colour = GROUP_COLOURS.get(point.group, "#000000")
        draw.ellipse([x - 3, y - 3, x + 3, y + 3], fill=colour, outline="#000000")
    for i, (group, colour) in enumerate(sorted(GROUP_COLOURS.items())):
        draw.rectangle([8, 8 + 16 * i, 18, 18 + 16 * i], fill=colour, outline="#000000")
        draw.text((24, 7 + 16 * i), f"group {group}: {GROUP_NAMES[group]}", fill="#ffffff")
    image.save(out / "feature-points.png", optimize=True)


def diagrams(face: FaceModel, out: Path) -> None:
    """The concepts page's layers and bitstream diagrams (tools/docs_diagrams.py)."""
    sys.path.insert(0, str(ROOT / "tools"))
    import docs_diagrams

    said = docs_diagrams.spoken(SENTENCE)
    docs_diagrams.layers_picture(face, said, out)
    docs_diagrams.bitstream_picture(said, out)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=Path, default=ROOT / "docs" / "media")
    parser.add_argument("--contact-sheets", action="store_true", help="also run tools/contact_sheet.py --docs")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    face = FaceModel.default()
    # the diagrams first: the speech layer's timing can shift by a blend step after a Chinese sentence was
    # spoken in the same process, and tests/docs compares them with a fresh process's
    for job in (diagrams, feature_point_picture, demo_picture, say_pictures):
        job(face, args.out)
        print(f"{job.__name__}: done", file=sys.stderr)
    if args.contact_sheets:
        subprocess.run([sys.executable, str(ROOT / "tools" / "contact_sheet.py"), "--docs"], check=True)
    for path in sorted(args.out.iterdir()):
        shown = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path  # --out may be anywhere
        print(f"{shown}  {path.stat().st_size // 1024} KiB")
    return 0


if __name__ == "__main__":
    sys.exit(main())
