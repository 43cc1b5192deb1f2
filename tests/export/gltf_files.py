"""Reading back what the glTF export wrote, independently of the writer: accessors (dense, sparse, absent),
the Khronos validator's report, and the test stream shared by the export tests and the browser test."""
from __future__ import annotations

import json
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pygltflib as gl
import pytest

from mpeg4fa.fba.stream import FapStream

ROOT = Path(__file__).resolve().parents[2]
VALIDATOR = ROOT / "tools" / "npm" / "validate_gltf.mjs"
VALIDATOR_PACKAGE = ROOT / "tools" / "npm" / "node_modules" / "gltf-validator"
FPS = 25.0
OPEN_FRAME = 6
"""The frame of :func:`talk_stream` where the jaw is open widest (frame 0 is neutral)."""

_DTYPES = {gl.FLOAT: np.float32, gl.UNSIGNED_INT: np.uint32, gl.UNSIGNED_SHORT: np.uint16, gl.UNSIGNED_BYTE: np.uint8}
_WIDTH = {gl.SCALAR: 1, gl.VEC2: 2, gl.VEC3: 3, gl.VEC4: 4}


def talk_stream(n: int = 13) -> FapStream:
    """A jaw that opens and closes (FAP 3 up to 700), lips parting with it (FAPs 4, 5) and the left inner brow
    raised late (FAP 31, one-sided)."""
    s = FapStream.empty(n)
    s.source_fps = FPS
    s.timestamps[:] = np.arange(n) / FPS
    jaw = np.round(700 * np.sin(np.pi * np.arange(n) / (2 * OPEN_FRAME)).clip(0)).astype(int)
    jaw[0] = 0
    for fap, column in ((3, jaw), (4, -jaw // 5), (5, -(jaw // 4)), (31, np.where(np.arange(n) > 8, 120, 0))):
        s.fap_mask[:, fap - 1] = True
        s.fap_values[:, fap - 1] = column
    return s


def load(path: Path) -> gl.GLTF2:
    return gl.GLTF2().load_binary(str(path))


def read_accessor(gltf: gl.GLTF2, index: int) -> np.ndarray:
    """The accessor's elements as (count, width) (or (count,) for scalars), sparse and absent views applied."""
    acc = gltf.accessors[index]
    blob = gltf.binary_blob()
    dtype, width = _DTYPES[acc.componentType], _WIDTH[acc.type]
    if acc.bufferView is None:
        out = np.zeros((acc.count, width), dtype)
    else:
        view = gltf.bufferViews[acc.bufferView]
        start = view.byteOffset + (acc.byteOffset or 0)
        assert not view.byteStride, "the export packs its arrays tightly"
        out = np.frombuffer(blob, dtype, acc.count * width, start).reshape(acc.count, width).copy()
    if acc.sparse is not None:
        sp = acc.sparse
        iv, vv = gltf.bufferViews[sp.indices.bufferView], gltf.bufferViews[sp.values.bufferView]
        idx = np.frombuffer(blob, _DTYPES[sp.indices.componentType], sp.count, iv.byteOffset + (sp.indices.byteOffset or 0))
        out[idx] = np.frombuffer(blob, dtype, sp.count * width, vv.byteOffset + (sp.values.byteOffset or 0)).reshape(-1, width)
    return out[:, 0] if width == 1 else out


def validate(path: Path) -> dict:
    """The Khronos glTF validator's report (skips when node or the pinned package is not installed)."""
    node = shutil.which("node")
    if node is None:
        pytest.skip("node not found: the glTF validator runs on Node.js (apt-get install nodejs)")
    if not VALIDATOR_PACKAGE.is_dir():
        pytest.skip("gltf-validator not installed: run tools/dev.sh test (npm ci in tools/npm)")
    done = subprocess.run([node, str(VALIDATOR), str(path)], capture_output=True, text=True, timeout=120, check=True)
    return json.loads(done.stdout)


def _local(node: gl.Node, overrides: dict) -> np.ndarray:
    """A node's 4x4 local matrix from translation, rotation (x, y, z, w) and scale (animated values win)."""
    from scipy.spatial.transform import Rotation

    m = np.eye(4)
    rotation = overrides.get("rotation", node.rotation)
    scale = node.scale or [1.0, 1.0, 1.0]
    m[:3, :3] = (Rotation.from_quat(rotation).as_matrix() if rotation else np.eye(3)) * np.asarray(scale)
    translation = overrides.get("translation", node.translation)
    if translation:
        m[:3, 3] = translation
    return m


def world_positions(gltf: gl.GLTF2, key: int) -> dict[str, np.ndarray]:
    """Part -> (n, 3) world positions (metres) of its primitive's vertices at key frame ``key`` of the first
    animation: its channels' values at that key (weights, rotations, translations) applied through the scene."""
    animated: dict[int, dict] = {}
    animation = gltf.animations[0]
    for channel in animation.channels:
        sampler = animation.samplers[channel.sampler]
        n_keys = gltf.accessors[sampler.input].count
        output = read_accessor(gltf, sampler.output)
        animated.setdefault(channel.target.node, {})[channel.target.path] = output.reshape(n_keys, -1)[key].tolist()
    out: dict[str, np.ndarray] = {}

    def visit(index: int, parent: np.ndarray) -> None:
        node = gltf.nodes[index]
        world = parent @ _local(node, animated.get(index, {}))
        if node.mesh is not None:
            mesh = gltf.meshes[node.mesh]
            weights = animated.get(index, {}).get("weights", mesh.weights or [])
            for prim in mesh.primitives:
                p = read_accessor(gltf, prim.attributes.POSITION).astype(np.float64)
                for w, target in zip(weights, prim.targets or []):
                    if w:
                        p = p + w * read_accessor(gltf, target["POSITION"])
                out[prim.extras["part"]] = p @ world[:3, :3].T + world[:3, 3]
        for child in node.children or []:
            visit(child, world)

    for root in gltf.scenes[gltf.scene].nodes:
        visit(root, np.eye(4))
    return out
