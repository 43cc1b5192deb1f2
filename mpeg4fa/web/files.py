"""Reading meshes (trimesh) and writing the edited model inside the output folder only."""
from __future__ import annotations

import io
import json
import os
import re
from pathlib import Path

import numpy as np
import trimesh

from mpeg4fa.atomic import atomic_outputs
from mpeg4fa.web.edits import EditError, EditMesh, make_mesh, validate

FORMATS = ("obj", "glb", "gltf", "off", "ply", "stl")
"""What trimesh reads here. VRML97 (.wrl) is not among them: trimesh has no VRML reader."""
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")


def read_mesh(data: bytes, filename: str) -> EditMesh:
    """A mesh file's bytes as an :class:`EditMesh`: one part per geometry (a single one is ``skin``).
    Nothing outside the bytes is read (no resolver: a glTF must embed its buffers)."""
    ext = filename.rsplit(".", 1)[-1].lower() if "." in filename else ""
    if ext not in FORMATS:
        hint = "VRML97 is not read yet (trimesh has none); convert to OBJ or GLB" if ext in ("wrl", "vrml") else ""
        raise EditError(f"cannot read .{ext or '?'} files", where=filename, hint=hint or f"formats: {', '.join(FORMATS)}")
    try:
        scene = trimesh.load(io.BytesIO(data), file_type=ext, force="scene", process=False, maintain_order=True)
        geoms = [(name, g) for name, g in scene.geometry.items() if isinstance(g, trimesh.Trimesh) and len(g.faces)]
        if not geoms:
            raise EditError("the file holds no triangles", where=filename)
        if len(geoms) > 1:  # scene graph transforms applied, one part per geometry
            geoms = [(name, scene.geometry[name].copy().apply_transform(scene.graph.get(node)[0]))
                     for node in scene.graph.nodes_geometry
                     for name in [scene.graph[node][1]] if name in dict(geoms)]
    except EditError:
        raise
    except Exception as exc:  # any reader fault is the file's
        raise EditError(f"cannot read the mesh: {exc}", where=filename) from None
    verts, tris, parts, base = [], [], [], 0
    for name, g in geoms:
        part = re.sub(r"[^a-z0-9_]", "_", str(name).lower()).strip("_") or "part"
        part = part if part[0].isalpha() else f"part_{part}"
        verts.append(np.asarray(g.vertices, np.float64))
        tris.append(np.asarray(g.faces, np.int64) + base)
        parts += ["skin" if len(geoms) == 1 else part[:40]] * len(g.faces)
        base += len(g.vertices)
    return make_mesh(np.concatenate(verts), np.concatenate(tris), parts, source=filename)


def output_path(out_dir: str | os.PathLike, name: str) -> Path:
    """``out_dir/name``, refused unless ``name`` is a plain file name that stays inside ``out_dir``
    (no folders, no absolute path, no ``..``, no link leading out)."""
    root = Path(out_dir).resolve()
    if not _NAME.match(name) or ".." in name:
        raise EditError(f"bad file name {name!r}", where="name",
                        hint="letters, digits, '.', '_' and '-' only; no folders, no '..'")
    target = (root / name).resolve()
    if target.parent != root:
        raise EditError(f"{name!r} leads outside the output folder", where="name")
    return target


def save_model(mesh: EditMesh, out_dir: str | os.PathLike, name: str, required_points=None) -> list[Path]:
    """Write ``NAME.obj`` (vertex order kept), ``NAME.points.json`` (label -> vertex index, as
    :func:`mpeg4fa.fdp.build.read_points_json` reads) and ``NAME.parts.json`` (part -> triangle indices
    in the OBJ), all or none, after :func:`validate`."""
    problems = validate(mesh, required_points)
    if problems:
        raise EditError("cannot save: " + "; ".join(problems), where="validation")
    Path(out_dir).mkdir(parents=True, exist_ok=True)
    paths = [output_path(out_dir, f"{name}{s}") for s in (".obj", ".points.json", ".parts.json")]
    obj = trimesh.exchange.obj.export_obj(trimesh.Trimesh(mesh.vertices, mesh.triangles, process=False),
                                          include_normals=False, include_texture=False)
    points = {k: mesh.points[k] for k in sorted(mesh.points, key=lambda s: tuple(map(int, s.split("."))))}
    parts = {n: np.flatnonzero(mesh.tri_part == i).tolist() for i, n in enumerate(mesh.part_names)}
    with atomic_outputs(*paths) as tmps:
        tmps[0].write_text(obj)
        tmps[1].write_text(json.dumps(points, indent=1) + "\n")
        tmps[2].write_text(json.dumps({"parts": parts}) + "\n")
    return paths
