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
from mpeg4fa.fdp.model import MAX_COORDINATE, first_unbounded
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
    (glTF node names are the objects' names in the modelling tool; the mesh names are often ``Cube.001``).
    A glTF's JSON is read by the package's reader and its nodes and references checked first
    (:func:`_check_gltf`); what trimesh gives back is checked (3D points, finite, within
    :data:`~mpeg4fa.fdp.model.MAX_COORDINATE`) before the node transforms are applied."""
    if ext in ("gltf", "glb"):  # read by the package's JSON reader first (nesting, size, shapes), then by trimesh
        doc = _gltf_json(data, filename, ext)
        if doc is not None:
            _check_gltf(doc, filename)
        if ext == "gltf" and resolver is None:
            _refuse_external(_gltf_external(doc), filename)
    try:
        with np.errstate(all="ignore"):  # overflow in trimesh's own arithmetic: its results are checked below
            scene = trimesh.load(io.BytesIO(data), file_type=ext, force="scene", process=False, maintain_order=True,
                                 resolver=resolver)
            nodes = [(node, *scene.graph[node]) for node in sorted(scene.graph.nodes_geometry)]
        nodes = [(n, m, g) for n, m, g in nodes if isinstance(scene.geometry.get(g), trimesh.Trimesh)
                 and len(scene.geometry[g].faces)]
    except EditError:
        raise
    except Exception as exc:  # any reader fault is the file's
        reason = str(exc).strip() or (f"the reader stopped with a bare {type(exc).__name__} (the file is damaged, "
                                      "e.g. a buffer claiming more bytes than it holds)")  # trimesh's asserts
        raise EditError(f"cannot read the mesh: {reason}", where=filename) from None
    if not nodes:
        raise EditError("the file holds no triangles", where=filename)
    out = []
    for node, matrix, geom in nodes:
        g = scene.geometry[geom]
        vertices, matrix = np.asarray(g.vertices, np.float64), np.asarray(matrix, np.float64)
        if vertices.ndim != 2 or vertices.shape[1] != 3:
            raise EditError(f"node {str(node)[:40]!r}: its positions are not 3D points (shape {vertices.shape})",
                            where=filename, hint="a mesh's POSITION accessor is a VEC3")
        _check_coordinates(vertices, f"node {str(node)[:40]!r}: vertex", filename)
        if matrix.shape != (4, 4):
            raise EditError(f"node {str(node)[:40]!r}: its transform is not a 4x4 matrix (shape {matrix.shape})",
                            where=filename)
        _check_coordinates(matrix, f"node {str(node)[:40]!r}: row of its world transform", filename)
        v = trimesh.transform_points(vertices, matrix)
        _check_coordinates(v, f"node {str(node)[:40]!r}: transformed vertex", filename)
        out.append((node, v, np.asarray(g.faces, np.int64)))
    return out


def _check_coordinates(values: np.ndarray, what: str, filename: str) -> None:
    """Refuse a row that is not finite or beyond MAX_COORDINATE (the mesh readers' one bound)."""
    row = first_unbounded(values)
    if row is not None:
        raise EditError(f"{what} {row} is ({', '.join(f'{x:.6g}' for x in values[row])}): its numbers must be "
                        f"finite and within +-{MAX_COORDINATE:g}", where=filename,
                        hint="check the values or the file's unit")


def _gltf_json(data: bytes, filename: str, ext: str):
    """The JSON document of a .gltf, or of a .glb's first chunk (read by the package's JSON reader); None for a
    .glb whose header is too damaged to find it (trimesh then says what it cannot read)."""
    if ext == "gltf":
        return loads(data, filename, max_bytes=GLTF_JSON_BYTES, what="a .gltf file")
    if len(data) < 20 or data[:4] != b"glTF" or data[16:20] != b"JSON":
        return None
    size = int.from_bytes(data[12:16], "little")
    if size > len(data) - 20:
        raise EditError(f"the GLB's JSON chunk (length at byte 12) claims {size:,} bytes, but the file has "
                        f"{len(data) - 20:,} after its header", where=filename, hint="the file is truncated or damaged")
    return loads(data[20:20 + size], f"{filename} (JSON chunk)", max_bytes=GLTF_JSON_BYTES, what="a .glb's JSON")


_NODE_SIZES = {"matrix": 16, "translation": 3, "rotation": 4, "scale": 3}
"""glTF 2.0 node transform properties and their number of components (column-major matrix, TRS quaternion)."""


def _check_gltf(doc, filename: str) -> None:
    """Refuse, naming the node or mesh, what trimesh reads wrong or with a bare traceback: a node transform of the
    wrong size or not finite (a 4-number matrix), and a node, child, attribute or index reference that is not an
    index into its array (-1 picked the last accessor)."""
    if not isinstance(doc, dict):
        raise EditError("a glTF document is a JSON object", where=filename)
    arrays = {key: doc.get(key, []) for key in ("nodes", "meshes", "accessors")}
    for key, items in arrays.items():
        if not isinstance(items, list):
            raise EditError(f"'{key}' is not an array", where=f"{filename}: {key}")
    for i, node in enumerate(arrays["nodes"]):
        where = f"{filename}: nodes/{i}"
        if not isinstance(node, dict):
            raise EditError(f"node {i} is not an object", where=where)
        label = f"node {i}" + (f" ({node['name'][:40]!r})" if isinstance(node.get("name"), str) else "")
        for key, size in _NODE_SIZES.items():
            if key not in node:
                continue
            value = node[key]
            if not (isinstance(value, list) and len(value) == size
                    and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in value)):
                raise EditError(f"{label}: '{key}' must be {size} numbers", where=f"{where}/{key}",
                                hint="glTF 2.0: matrix 16 numbers, translation 3, rotation 4 (a quaternion), scale 3")
            if first_unbounded(value) is not None:
                raise EditError(f"{label}: '{key}' holds a number beyond +-{MAX_COORDINATE:g}",
                                where=f"{where}/{key}", hint="check the values or the file's unit")
        _check_index(node.get("mesh"), arrays["meshes"], f"{label}: 'mesh'", f"{where}/mesh")
        children = node.get("children", [])
        for child in children if isinstance(children, list) else [children]:
            _check_index(child, arrays["nodes"], f"{label}: child", f"{where}/children")
    for i, mesh in enumerate(arrays["meshes"]):
        primitives = mesh.get("primitives", []) if isinstance(mesh, dict) else None
        if not isinstance(primitives, list):
            raise EditError(f"mesh {i} has no list of primitives", where=f"{filename}: meshes/{i}")
        for j, primitive in enumerate(primitives):
            where = f"{filename}: meshes/{i}/primitives/{j}"
            attributes = primitive.get("attributes", {}) if isinstance(primitive, dict) else None
            if not isinstance(attributes, dict):
                raise EditError(f"mesh {i} primitive {j} has no attributes object", where=where)
            for name, ref in attributes.items():
                _check_index(ref, arrays["accessors"], f"mesh {i} primitive {j}: attribute {name}",
                             f"{where}/attributes/{name}")
            _check_index(primitive.get("indices"), arrays["accessors"], f"mesh {i} primitive {j}: 'indices'",
                         f"{where}/indices")


def _check_index(ref, items: list, what: str, where: str) -> None:
    """A glTF reference (absent, or an index into ``items``)."""
    if ref is None:
        return
    if type(ref) is not int or not 0 <= ref < len(items):
        shown = repr(ref)[:30]
        raise EditError(f"{what} is {shown}, not an index into the {len(items)} there are", where=where,
                        hint="the file is damaged: glTF references count from 0")


def _gltf_external(doc) -> list[str]:
    """The URIs of a glTF's buffers and images that are files (not data: URIs), as written in its JSON."""
    lists = [doc.get(key) for key in ("buffers", "images")] if isinstance(doc, dict) else []
    items = [item for value in lists if isinstance(value, list) for item in value]  # other shapes: refused later
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
        external = _gltf_external(_gltf_json(data, model, ext))
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
        outside = next((t for t in triangles if not 0 <= t < n_triangles), None)  # before int64 (JSON has 100 digits)
        if outside is not None:
            shown = str(outside) if len(str(outside)) <= 20 else f"{str(outside)[:10]}...({len(str(outside)):,} digits)"
            raise EditError(f"part {name!r} names triangle {shown}, outside 0..{n_triangles - 1}",
                            where=f"{where}: parts/{name}", hint="the parts file belongs to the OBJ beside it")
        idx = np.asarray(triangles, np.int64)
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
