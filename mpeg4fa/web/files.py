"""Reading meshes (trimesh; VTK for VRML) and writing the edited model inside the output folder only."""
from __future__ import annotations

import io
import json
import os
import re
from collections.abc import Sequence
from pathlib import Path
from urllib.parse import unquote

import numpy as np
import trimesh

from mpeg4fa.atomic import atomic_outputs
from mpeg4fa.fdp.build import parse_points_json
from mpeg4fa.fdp.obj import mesh_and_groups_from_obj
from mpeg4fa.jsonio import loads
from mpeg4fa.web.edits import EditError, EditMesh, make_mesh, validate
from mpeg4fa.web.vrml import read_vrml

FORMATS = ("obj", "wrl", "vrml", "glb", "gltf", "off", "ply", "stl")
"""What the editor reads: OBJ with the FDP reader (trimesh, the file's own vertex indices), VRML 97 with VTK
(:mod:`mpeg4fa.web.vrml`), the rest with trimesh."""
_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,63}$")
GLTF_JSON_BYTES = 64 << 20
"""The largest .gltf read (its buffers may be embedded as data: URIs; the editor's upload limit is the same)."""
SIDECARS = (".points.json", ".parts.json")
"""What :func:`save_model` writes beside ``NAME.obj`` and :func:`read_model` reads back."""


def read_mesh(data: bytes, filename: str, resolver=None) -> EditMesh:
    """A mesh file's bytes as an :class:`EditMesh`: one part per Shape (VRML) or scene node (glTF...),
    node transforms applied; a single one is ``skin``. An OBJ keeps its vertex indices; its parts are its
    ``g`` groups (or ``o`` objects).
    Nothing outside the bytes is read unless ``resolver`` (a trimesh resolver) is given: a ``.gltf`` without
    one must embed its buffers (data: URIs); :func:`read_upload` gives it the uploaded files."""
    ext = filename.rsplit(".", 1)[-1].lower() if "." in filename else ""
    if ext not in FORMATS:
        raise EditError(f"cannot read .{ext or '?'} files", where=filename, hint=f"formats: {', '.join(FORMATS)}")
    try:
        return _read_mesh(data, filename, ext, resolver)
    except EditError as exc:
        if exc.where:
            raise
        raise EditError(exc.message, where=filename, hint=exc.hint or "the file is damaged") from None


def _read_mesh(data: bytes, filename: str, ext: str, resolver) -> EditMesh:
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
    if ext == "gltf":  # read by the package's JSON reader first (nesting, size), then by trimesh
        external = _gltf_external(data, filename)
        if resolver is None and external:
            _refuse_external(external, filename)
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


def _gltf_external(data: bytes, filename: str) -> list[str]:
    """The URIs of a .gltf's buffers and images that are files (not data: URIs), as written in its JSON."""
    doc = loads(data, filename, max_bytes=GLTF_JSON_BYTES, what="a .gltf file")
    items = [item for key in ("buffers", "images") for item in (doc.get(key) or [] if isinstance(doc, dict) else [])]
    uris = [item.get("uri") for item in items if isinstance(item, dict)]
    return list(dict.fromkeys(u for u in uris if isinstance(u, str) and not u.startswith("data:")))


def _refuse_external(external: list[str], filename: str) -> None:
    """A .gltf read from bytes alone: refuse one whose buffers or images (``external``) are other files."""
    if external:
        raise EditError(f"the .gltf needs {', '.join(external[:3])}, which were not given with it",
                        where=filename, hint="upload it together with the files it names (several files at once), "
                        "or a .glb, or start 'mpeg4fa edit FILE.gltf' to read the files beside it")


# ---- an upload: one model file and the files it names, looked up among the uploaded ones only ----------------

def _plain_name(name: str) -> str:
    """An uploaded file's name without any folders (browsers send none; a client might): a key, never a path."""
    return re.split(r"[/\\]", str(name))[-1].strip() or "upload"


def _ext(name: str) -> str:
    return name.rsplit(".", 1)[-1].lower() if "." in name else ""


class _UploadResolver(trimesh.resolvers.Resolver):
    """trimesh's resolver over the uploaded files: a URI is looked up by its (percent-decoded) last name among
    them; nothing is opened on disk, so ``../`` or an absolute URI finds at most an uploaded file of that name."""

    def __init__(self, files: dict[str, bytes]):
        self.files = files

    def get(self, key: str) -> bytes:
        name = _plain_name(unquote(key))
        if name not in self.files:
            raise KeyError(key)
        return self.files[name]

    def keys(self):
        return self.files.keys()

    def write(self, name, data):
        raise EditError("an upload is read only", where=name)

    def namespaced(self, namespace):
        return self


def _obj_companions(data: bytes, model: str, files: dict[str, bytes]) -> list[str]:
    """The names an OBJ may bring: its sidecars (``NAME.points.json``, ``NAME.parts.json``), the ``mtllib``
    files it names and the texture maps those name (accepted, not read: parts come from groups or the sidecar)."""
    stem = model[: -len(".obj")]
    names = [stem + s for s in SIDECARS]
    lines = re.findall(rb"^[ \t]*mtllib[ \t]+([^\r\n]+)", data, re.M)
    mtls = [_plain_name(n) for line in lines for n in line.decode("utf-8", "replace").split()]
    names += mtls
    for mtl in mtls:
        for line in files.get(mtl, b"").decode("utf-8", "replace").splitlines():
            words = line.split()
            if words and (words[0].lower().startswith("map_") or words[0].lower() in ("bump", "disp", "norm")):
                names.append(_plain_name(words[-1]))
    return names


def read_upload(files: Sequence[tuple[str, bytes]]) -> EditMesh:
    """One uploaded model file and its companions as an :class:`EditMesh`, as :func:`read_model` reads the same
    files from a folder: a ``.gltf`` gets the buffers and images its JSON names, an OBJ saved by
    :func:`save_model` its ``NAME.parts.json`` and ``NAME.points.json``. Names are keys among the uploaded
    files only, never paths (folders in a name are dropped). Refused, naming the files: no model file or several,
    two files of one name, a buffer or image the .gltf names but the upload lacks, and any file the model does
    not refer to (a stray file is more often a mistake, such as sidecars of another model, than a wish)."""
    by_name: dict[str, bytes] = {}
    for raw, data in files:
        name = _plain_name(raw)
        if name in by_name:
            raise EditError(f"two uploaded files are named {name}", where=name, hint="upload each file once")
        by_name[name] = data
    models = [n for n in by_name if _ext(n) in FORMATS]
    if len(models) != 1:
        problem = (f"{len(models)} model files ({', '.join(models)})" if models else "no model file")
        raise EditError(f"an upload holds one model file, here {problem}", where=", ".join(by_name) or "upload",
                        hint=f"choose one {'/'.join('.' + f for f in FORMATS)} file and the files it names "
                        "(.bin and images of a .gltf; NAME.points.json and NAME.parts.json of an OBJ)")
    model = models[0]
    data, ext = by_name[model], _ext(model)
    wanted: list[str] = []
    if ext == "gltf":
        external = _gltf_external(data, model)
        missing = [u for u in external if _plain_name(unquote(u)) not in by_name]
        if missing:
            raise EditError(f"{model} names {', '.join(missing)}, not among the uploaded files", where=model,
                            hint="choose the .gltf together with its buffers and images (several files at once), "
                            "or upload a .glb")
        wanted = [_plain_name(unquote(u)) for u in external]
    elif ext == "obj":
        wanted = _obj_companions(data, model, by_name)
    extra = [n for n in by_name if n != model and n not in wanted]
    if extra:
        uses = f"it takes {', '.join(dict.fromkeys(wanted))}" if wanted else "it takes no other files"
        raise EditError(f"{', '.join(extra)} not used by {model}", where=extra[0],
                        hint=f"upload only {model} and the files it names ({uses})")
    resolver = _UploadResolver(by_name) if ext == "gltf" else None
    mesh = read_mesh(data, model, resolver)
    if ext != "obj":
        return mesh
    stem = model[: -len(".obj")]
    return _with_sidecars(mesh, model, {s: (by_name[stem + s], stem + s) for s in SIDECARS if stem + s in by_name})


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
    sidecars = {}
    for suffix in SIDECARS:
        side = path.with_name(path.stem + suffix)
        if side.exists():
            try:
                sidecars[suffix] = (side.read_bytes(), str(side))
            except OSError as exc:
                raise EditError(f"cannot read the file: {exc.strerror or exc}", where=str(side)) from None
    return _with_sidecars(mesh, path.name, sidecars)


def _with_sidecars(mesh: EditMesh, model: str, sidecars: dict[str, tuple[bytes, str]]) -> EditMesh:
    """``mesh`` (read from the OBJ ``model``) with the parts and points of its sidecars: suffix -> (bytes, where),
    whether they came from the folder (:func:`read_model`) or the upload (:func:`read_upload`)."""
    if ".parts.json" in sidecars:
        data, where = sidecars[".parts.json"]
        mesh = make_mesh(mesh.vertices, mesh.triangles, _read_parts(data, where, len(mesh.triangles)),
                         source=mesh.source)
    if ".points.json" in sidecars:
        data, where = sidecars[".points.json"]
        points = parse_points_json(data, where)
        for label, vertex in points.items():
            if not isinstance(vertex, int):
                raise EditError(f"feature point {label} is a position, not a vertex index", where=where,
                                hint="the editor places feature points on vertices")
            if not 0 <= vertex < len(mesh.vertices):
                raise EditError(f"feature point {label} is vertex {vertex}, but {model} has "
                                f"{len(mesh.vertices)} vertices", where=where)
        mesh = make_mesh(mesh.vertices, mesh.triangles, mesh.parts, points, source=mesh.source)
    return mesh


def _read_parts(data: bytes, where: str, n_triangles: int) -> list[str]:
    """Per-triangle part names from a ``{"parts": {name: [triangle, ...]}}`` file covering every triangle once."""
    doc = loads(data, where, what="a parts file")
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
