#!/usr/bin/env python3
"""Write the FBA player as one HTML file that opens from a folder, with no server (file://).

    .venv/bin/python tools/fbaplayer_static.py -o out/player/fbaplayer.html [--fdp face.fdp]

A browser refuses ES modules from file:// URLs, so every module of the page (fbaplayer.js, head.js,
facerig.js, lashes.js, fba.js, shown.js, spec.js, three.js and the two addons it uses) goes into the page's
import map as a data: URL under a bare name (their relative imports rewritten to those names), and the head (the
GLB and rig of :mod:`mpeg4fa.serve.fap_head`, of the generic head or of one calibrated to ``--fdp``) and its
key ride along in the page. Open the file and drop a .fba with its .wav on it (a URL cannot be
fetched from a file:// page). About 4 MB (the generic head, untextured).
"""
from __future__ import annotations

import argparse
import base64
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
STATIC = ROOT / "mpeg4fa" / "serve" / "static"
THREE = ROOT / "mpeg4fa" / "web" / "static" / "vendor" / "three"

MODULES = {  # bare name -> (file, {relative import as written: bare name})
    "three": (THREE / "three.module.js", {"./three.core.js": "three-core"}),
    "three-core": (THREE / "three.core.js", {}),
    "three/addons/controls/OrbitControls.js": (THREE / "addons/controls/OrbitControls.js", {}),
    "three/addons/loaders/GLTFLoader.js": (THREE / "addons/loaders/GLTFLoader.js", {
        "../utils/BufferGeometryUtils.js": "three/addons/utils/BufferGeometryUtils.js",
        "../utils/SkeletonUtils.js": "three/addons/utils/SkeletonUtils.js"}),
    "three/addons/utils/BufferGeometryUtils.js": (THREE / "addons/utils/BufferGeometryUtils.js", {}),
    "three/addons/utils/SkeletonUtils.js": (THREE / "addons/utils/SkeletonUtils.js", {}),
    "fba/spec.js": (STATIC / "js/fba/spec.js", {}),
    "fba/fba.js": (STATIC / "js/fba/fba.js", {"./spec.js": "fba/spec.js"}),
    "fba/shown.js": (STATIC / "js/fba/shown.js", {"./spec.js": "fba/spec.js"}),
    "facerig": (STATIC / "js/facerig.js", {}),
    "lashes": (STATIC / "js/lashes.js", {}),
    "head": (STATIC / "js/head.js", {"./facerig.js": "facerig", "./lashes.js": "lashes"}),
    "fbaplayer": (STATIC / "js/fbaplayer.js", {"./fba/fba.js": "fba/fba.js", "./fba/shown.js": "fba/shown.js",
                                               "./head.js": "head"}),
}


def data_url(text: str, kind: str = "text/javascript") -> str:
    return f"data:{kind};base64," + base64.b64encode(text.encode("utf-8")).decode("ascii")


def module_text(path: Path, rewrites: dict[str, str]) -> str:
    text = path.read_text(encoding="utf-8")
    for old, new in rewrites.items():
        pattern = re.compile(r"""(from\s*|import\s*)(['"])""" + re.escape(old) + r"""\2""")
        text, n = pattern.subn(lambda m: f"{m.group(1)}{m.group(2)}{new}{m.group(2)}", text)
        if not n:
            raise SystemExit(f"{path.name}: no import of {old} to rewrite (the vendored file changed?)")
    return text


def page(head_glb: bytes, key: dict) -> str:
    html = (STATIC / "fbaplayer.html").read_text(encoding="utf-8")
    imports = {name: data_url(module_text(path, rewrites)) for name, (path, rewrites) in MODULES.items()}
    head = ("<script>window.FBA_PLAYER_HEAD = {key: " + json.dumps(key) + ", glb: \"data:model/gltf-binary;base64,"
            + base64.b64encode(head_glb).decode("ascii") + "\"};</script>\n")
    html, n1 = re.subn(r'<script type="importmap">.*?</script>',
                       lambda _: '<script type="importmap">' + json.dumps({"imports": imports}) + "</script>",
                       html, flags=re.S)
    html, n2 = re.subn(r'<script type="module" src="js/fbaplayer.js"></script>',
                       lambda _: head + '<script type="module">import "fbaplayer";</script>', html)
    if (n1, n2) != (1, 1):
        raise SystemExit("fbaplayer.html changed: its import map or module script was not found")
    return html


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("-o", "--output", type=Path, required=True)
    parser.add_argument("--fdp", type=Path, help="calibrate the generic head to this FDP first (and wear its texture)")
    args = parser.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    from mpeg4fa.atomic import atomic_outputs
    from mpeg4fa.errors import MpegFaError
    from mpeg4fa.face import FaceModel
    from mpeg4fa.serve.fap_head import fap_head
    from mpeg4fa.serve.heads import calibrated_head

    try:
        if args.fdp:  # as `mpeg4fa play --fdp` shows it: calibrated, wearing the texture the FDP carries
            glb, key, made = calibrated_head(args.fdp.read_bytes(), str(args.fdp))
            print(f"head: calibrated to {args.fdp} ({made['points']} points"
                  + (f", texture {made['texture']})" if made["texture"] else ", no texture)"))
        else:
            glb, key = fap_head(FaceModel.default())
    except OSError as exc:
        print(f"error: {args.fdp}: {exc.strerror}", file=sys.stderr)
        return 1
    except MpegFaError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 1
    text = page(glb, key)
    args.output.parent.mkdir(parents=True, exist_ok=True)
    with atomic_outputs(args.output) as (tmp,):
        tmp.write_text(text, encoding="utf-8")
    print(f"wrote {args.output} ({len(text) / 1e6:.1f} MB): open it in a browser and drop a .fba (+ .wav) on it")
    return 0


if __name__ == "__main__":
    sys.exit(main())
