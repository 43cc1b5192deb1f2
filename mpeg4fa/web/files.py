"""Reading meshes (trimesh; VTK for VRML) and writing the edited model inside the output folder only."""
from __future__ import annotations

import io
import json
import os
import re
from pathlib import Path

import numpy as np
import trimesh

from mpeg4fa.atomic import atomic_outputs
from mpeg4fa.fdp.build import read_points_json
from mpeg4fa.fdp.obj import mesh_and_groups_from_obj
from mpeg4fa.web.edits import EditError, EditMesh, make_mesh, validate
from mpeg4fa.web.vrml import read_vrml

FORMATS = ("obj", "wrl", "vrml", "glb", "gltf", "off", "ply", "stl")
"""What the editor reads: OBJ with the FDP reader (trimesh, the file's own vertex indices), VRML 97 with VTK
(:mod:`mpeg4fa.web.vrml`), the rest with trimesh."""
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")
SIDECARS = (".points.json", ".parts.json")
"""What :func:`save_model` writes beside ``NAME.obj`` and :func:`read_model` reads back."""


def read_mesh(data: bytes, filename: str, resolver=None) -> EditMesh:
    """A mesh file's bytes as an :class:`EditMesh`: one part per Shape (VRML) or scene node (glTF...),
    node transforms applied; a single one is ``skin``. An OBJ keeps its vertex indices; its parts are its
    ``g`` groups (or ``o`` objects).
    Nothing outside the bytes is read unless ``resolver`` (a trimesh resolver) is given, so an uploaded
    ``.gltf`` must embed its buffers (data: URIs); a ``.glb`` always does."""
    ext = filename.rsplit(".", 1)[-1].lower() if "." in filename else ""
    if ext not in FORMATS:
        raise EditError(f"cannot read .{ext or '?'} files", where=filename, hint=f"formats: {', '.join(FORMATS)}")
    if ext == "obj":  # one part per g group (or o object), the vertices in the file's order
        mesh, groups = mesh_and_groups_from_obj(data, filename)
        several = len(set(groups)) > 1
        return make_mesh(mesh.vertices, mesh.triangles, [_part_name(g) if several and g else "skin" for g in groups],
                         source=filename)
    shapes = read_vrml(data, filename) if ext in ("wrl", "vrml") else _read_scene(data, filename, ext, resolver)
    verts, tris, parts, base = [], [], [], 0
    for name, v, t in shapes:
        verts.append(v)
        tris.append(t + base)
        parts += ["skin" if len(shapes) == 1 else _part_name(name)] * len(t)
        base += len(v)
    return make_mesh(np.concatenate(verts), np.concatenate(tris), parts, source=filename)


def _read_scene(data: bytes, filename: str, ext: str, resolver) -> list[tuple[str, np.ndarray, np.ndarray]]:
    """``[(node name, world vertices, triangles)]`` of every scene node with triangles, as trimesh reads them
    (glTF node names are the objects' names in the modelling tool; the mesh names are often ``Cube.001``)."""
    if ext == "gltf" and resolver is None:
        _refuse_external(data, filename)
    try:
        scene = trimesh.load(io.BytesIO(data), file_type=ext, force="scene", process=False, maintain_order=True,
                             resolver=resolver)
        nodes = [(node, *scene.graph[node]) for node in sorted(scene.graph.nodes_geometry)]
        nodes = [(n, m, g) for n, m, g in nodes if isinstance(scene.geometry.get(g), trimesh.Trimesh)
                 and len(scene.geometry[g].faces)]
    except EditError:
        raise
    except Exception as exc:  # any reader fault is the file's
        raise EditError(f"cannot read the mesh: {exc}", where=filename) from None
    if not nodes:
        raise EditError("the file holds no triangles", where=filename)
    out = []
    for node, matrix, geom in nodes:
        g = scene.geometry[geom]
        v = trimesh.transform_points(np.asarray(g.vertices, np.float64), np.asarray(matrix, np.float64))
        out.append((node, v, np.asarray(g.faces, np.int64)))
    return out


def _refuse_external(data: bytes, filename: str) -> None:
    """An uploaded .gltf comes alone: refuse one whose buffers or images are files beside it."""
    try:
        doc = json.loads(data)
    except (ValueError, UnicodeDecodeError) as exc:
        raise EditError(f"a .gltf file is JSON: {exc}", where=filename) from None
    items = [item for key in ("buffers", "images") for item in (doc.get(key) or [] if isinstance(doc, dict) else [])]
    uris = [item.get("uri") for item in items if isinstance(item, dict)]
    external = [u for u in uris if isinstance(u, str) and not u.startswith("data:")]
    if external:
        raise EditError(f"the .gltf needs {', '.join(external[:3])} beside it, which an upload cannot bring",
                        where=filename, hint="upload a .glb, or a .gltf with its buffers embedded (data: URIs), "
                        "or start 'mpeg4fa edit FILE.gltf' to read the files beside it")


def _part_name(name: str) -> str:
    """A file's node or shape name as an editor part name (lower case, letters digits and _)."""
    part = re.sub(r"[^a-z0-9_]", "_", str(name).lower()).strip("_") or "part"
    return (part if part[0].isalpha() else f"part_{part}")[:40]


def read_model(path: str | os.PathLike) -> EditMesh:
    """The mesh file at ``path``; an OBJ saved by :func:`save_model` gets its parts and feature points back
    from ``NAME.parts.json`` and ``NAME.points.json`` beside it, and a ``.gltf`` reads the buffers beside it."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise EditError(f"cannot read the model: {exc.strerror or exc}", where=str(path)) from None
    resolver = trimesh.resolvers.FilePathResolver(str(path)) if path.suffix.lower() == ".gltf" else None
    mesh = read_mesh(data, path.name, resolver)
    if path.suffix.lower() != ".obj":
        return mesh
    points_path, parts_path = (path.with_name(path.stem + s) for s in SIDECARS)
    if parts_path.exists():
        mesh = make_mesh(mesh.vertices, mesh.triangles, _read_parts(parts_path, len(mesh.triangles)),
                         source=mesh.source)
    if points_path.exists():
        points = read_points_json(points_path)
        for label, vertex in points.items():
            if not isinstance(vertex, int):
                raise EditError(f"feature point {label} is a position, not a vertex index", where=str(points_path),
                                hint="the editor places feature points on vertices")
            if not 0 <= vertex < len(mesh.vertices):
                raise EditError(f"feature point {label} is vertex {vertex}, but {path.name} has "
                                f"{len(mesh.vertices)} vertices", where=str(points_path))
        mesh = make_mesh(mesh.vertices, mesh.triangles, mesh.parts, points, source=mesh.source)
    return mesh


def _read_parts(path: Path, n_triangles: int) -> list[str]:
    """Per-triangle part names from a ``{"parts": {name: [triangle, ...]}}`` file covering every triangle once."""
    where = str(path)
    try:
        doc = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError) as exc:
        raise EditError(f"cannot read the parts file: {exc}", where=where) from None
    except json.JSONDecodeError as exc:
        raise EditError(f"malformed JSON: {exc.msg}", where=f"{where}:{exc.lineno}:{exc.colno}") from None
    parts = doc.get("parts") if isinstance(doc, dict) else None
    if not isinstance(parts, dict):
        raise EditError('a parts file is {"parts": {name: [triangle indices]}}', where=where)
    names = np.full(n_triangles, -1, np.int64)
    order = list(parts)
    for i, (name, triangles) in enumerate(parts.items()):
        if not isinstance(triangles, list) or not all(type(t) is int for t in triangles):
            raise EditError(f"part {name!r} must list triangle indices", where=f"{where}: parts/{name}")
        idx = np.asarray(triangles, np.int64)
        if len(idx) and (idx.min() < 0 or idx.max() >= n_triangles):
            raise EditError(f"part {name!r} names a triangle outside 0..{n_triangles - 1}",
                            where=f"{where}: parts/{name}", hint="the parts file belongs to the OBJ beside it")
        if (names[idx] >= 0).any():
            raise EditError(f"part {name!r} repeats a triangle of another part", where=f"{where}: parts/{name}")
        names[idx] = i
    if (names < 0).any():
        raise EditError(f"triangle {int(np.argmax(names < 0))} is in no part", where=where,
                        hint="the parts file belongs to the OBJ beside it")
    return [order[i] for i in names]


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
    paths = [output_path(out_dir, f"{name}{s}") for s in (".obj", *SIDECARS)]
    obj = trimesh.exchange.obj.export_obj(trimesh.Trimesh(mesh.vertices, mesh.triangles, process=False),
                                          include_normals=False, include_texture=False)
    points = {k: mesh.points[k] for k in sorted(mesh.points, key=lambda s: tuple(map(int, s.split("."))))}
    parts = {n: np.flatnonzero(mesh.tri_part == i).tolist() for i, n in enumerate(mesh.part_names)}
    with atomic_outputs(*paths) as tmps:
        tmps[0].write_text(obj)
        tmps[1].write_text(json.dumps(points, indent=1) + "\n")
        tmps[2].write_text(json.dumps({"parts": parts}) + "\n")
    return paths
