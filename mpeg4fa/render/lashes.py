"""Eyelashes as cards along the lid margins, rebuilt from the posed margin every frame.

Each lid margin (:func:`mpeg4fa.face.lids.lid_margins`) grows a strip of three rows of
GL vertices: the root on the margin, the middle and the tip. A lash leaves the margin
along the eyeball's outward direction turned away from the lid opening (``lash_lift``)
and bends further on its second half (``lash_curl``), about the margin's own tangent.
The margin vertices are the lid's own skin, and the lid turns about the eye centre, so
the lashes turn with the lid as it closes, whatever the deformer. Lengths taper to
nothing at both corners. The shader cuts the cards into strands (``v_detail``: mm along
the margin, 0 at the root to 1 at the tip; ``v_tints.x``: the lash's length, 1 the longest, for the
strand width) and drops the gaps, so no blending is needed.
Sizes are data (:func:`mpeg4fa.face.eyes.eye_looks`). Like the drawn brows, they are for the
untextured skin only: a photo texture has the person's own lashes on its lids (drawn over them, they
doubled the lashes, and the photo loop's landmark finder put the inner lower lip 3.9 % of the face
width off instead of 2.8 %).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.face.errors import FaceError
from mpeg4fa.face.eyes import eye_looks
from mpeg4fa.face.lids import front_edges, lid_margins
from mpeg4fa.face.mesh import HeadMesh
from mpeg4fa.render.shader_hash import shader_hash

LASH_MATERIAL = 6.0
"""The shader's material slot of the lash cards."""
ROOT_OFFSET_MM = 0.15  # roots sit this far out of the lid's front edge, so the skin does not hide them


@dataclass(frozen=True)
class LashLayout:
    rows: np.ndarray      # (K,) margin vertex of each lash, margin after margin
    roots: np.ndarray     # (K,) the skin vertex at the lid's front edge in front of it, where the lash grows
    before: np.ndarray    # (K,) the margin's previous vertex (for the tangent; itself at an end)
    after: np.ndarray     # (K,) the margin's next vertex
    joint: np.ndarray     # (K,) the eye centre joint's vertex
    sign: np.ndarray      # (K,) +1 or -1: the turn about the tangent that leads away from the opening
    length: np.ndarray    # (K,) mm
    lift: np.ndarray      # (K,) radians, first half
    bend: np.ndarray      # (K,) radians, second half (lift + curl)
    static: np.ndarray    # (3K, 9) float32: uv, material, tints, detail, nose (the face's static layout)
    indices: np.ndarray   # (T, 3) uint32 into the 3K GL vertices (roots, middles, tips)

    @property
    def n_vertices(self) -> int:
        return 3 * len(self.rows)


def _turn(v: np.ndarray, axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rodrigues: rotate unit vectors ``v`` about unit ``axis`` by ``angle`` (rows)."""
    c, s = np.cos(angle)[:, None], np.sin(angle)[:, None]
    return v * c + np.cross(axis, v) * s + axis * (axis * v).sum(1, keepdims=True) * (1.0 - c)


def _unit(v: np.ndarray) -> np.ndarray:
    n = np.linalg.norm(v, axis=1, keepdims=True)
    return v / np.where(n > 0, n, 1.0)


def _taper(t: np.ndarray, peak: float) -> np.ndarray:
    """0 at both corners, 1 at ``peak`` (0 lateral .. 1 medial)."""
    u = np.where(t < peak, 0.5 * t / peak, 0.5 + 0.5 * (t - peak) / (1.0 - peak))
    return np.sqrt(np.clip(np.sin(np.pi * u), 0.0, 1.0))


def _frames(vertices: np.ndarray, rows, before, after, joint, sign) -> np.ndarray:
    """(K, 3, 3) rows: each margin vertex's outward direction, its tangent, and their cross product."""
    radial = _unit(vertices[rows] - vertices[joint])
    tangent = _unit(vertices[after] - vertices[before]) * np.asarray(sign, float)[:, None]
    tangent = _unit(tangent - (tangent * radial).sum(1, keepdims=True) * radial)
    return np.stack([radial, tangent, np.cross(radial, tangent)], axis=1)


def build_lashes(mesh: HeadMesh) -> LashLayout | None:
    """The lash cards of a face, or None where its mesh has no lid margins to grow them on."""
    try:
        margins = lid_margins(mesh)
    except (FaceError, KeyError, ValueError):
        return None
    looks = eye_looks()
    rest = mesh.vertices
    parts = {k: [] for k in ("rows", "roots", "before", "after", "joint", "sign", "length", "lift", "bend", "s")}
    skin = mesh.part("skin")
    for m in margins:
        rows = m.rows
        n = len(rows)
        if n < 3:
            return None
        seg = np.linalg.norm(np.diff(rest[rows], axis=0), axis=1)
        s = np.r_[0.0, np.cumsum(seg)]
        upper = m.side == "upper"
        longest = looks.upper_lash_length if upper else looks.lower_lash_length
        lift = np.radians(looks.lash_lift if upper else looks.lower_lash_lift)
        curl = np.radians(looks.lash_curl if upper else looks.lower_lash_curl)
        idx = np.arange(n)
        before, after = rows[np.maximum(idx - 1, 0)], rows[np.minimum(idx + 1, n - 1)]
        # which way about the tangent leads away from the opening: decided once, at the middle
        k = n // 2
        radial = _unit((rest[rows[k]] - rest[m.joint])[None])
        tangent = _unit((rest[after[k]] - rest[before[k]])[None])
        up = _turn(radial, tangent, np.array([0.3]))[0, 1] > radial[0, 1]
        sign = 1.0 if up == upper else -1.0
        parts["rows"].append(rows)
        parts["before"].append(before)
        parts["after"].append(after)
        parts["joint"].append(np.full(n, m.joint))
        parts["sign"].append(np.full(n, sign))
        parts["roots"].append(front_edges(rest, skin, rows))
        parts["length"].append(longest * _taper(s / s[-1], looks.lash_peak))
        parts["lift"].append(np.full(n, lift))
        parts["bend"].append(np.full(n, lift + curl))
        # strands are counted from each margin's lateral corner, offset per margin so the four differ
        parts["s"].append(s + 100.0 * len(parts["s"]))
    cat = {k: np.concatenate(v) for k, v in parts.items()}
    n_roots = len(cat["rows"])
    static = np.zeros((3 * n_roots, 9), np.float32)
    static[:, 2] = LASH_MATERIAL
    static[:, 3] = np.tile(cat["length"] / max(cat["length"].max(), 1e-9), 3)  # tints.x: thinner where short
    static[:, 5] = np.tile(cat["s"], 3)
    static[:, 6] = np.repeat([0.0, 0.5, 1.0], n_roots)
    tris = []
    start = 0
    for m in margins:
        n = len(m.rows)
        a = np.arange(start, start + n - 1)
        for row in (0, 1):  # root-middle and middle-tip bands
            lo, hi = a + row * n_roots, a + (row + 1) * n_roots
            tris.append(np.c_[lo, lo + 1, hi + 1])
            tris.append(np.c_[lo, hi + 1, hi])
        start += n
    return LashLayout(rows=cat["rows"], before=cat["before"], after=cat["after"], joint=cat["joint"],
                      sign=cat["sign"], roots=cat["roots"], length=cat["length"], lift=cat["lift"], bend=cat["bend"],
                      static=static, indices=np.concatenate(tris).astype(np.uint32))


def lash_vertices(layout: LashLayout, vertices: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
    """Interleaved position + normal of the lash cards for posed ``vertices``, (3K, 6) float32."""
    k = len(layout.rows)
    if out is None:
        out = np.empty((3 * k, 6), np.float32)
    frame = _frames(vertices, layout.roots, layout.before, layout.after, layout.joint, layout.sign)
    radial, tangent = frame[:, 0], frame[:, 1]
    first = _turn(radial, tangent, layout.lift)
    second = _turn(radial, tangent, layout.bend)
    base = vertices[layout.roots] + ROOT_OFFSET_MM * radial
    middle = base + 0.5 * layout.length[:, None] * first
    tip = middle + 0.5 * layout.length[:, None] * second
    out[:k, :3], out[k:2 * k, :3], out[2 * k:, :3] = base, middle, tip
    out[:k, 3:] = out[k:2 * k, 3:] = _unit(np.cross(tangent, first))
    out[2 * k:, 3:] = _unit(np.cross(tangent, second))
    return out


STRANDS = 128
"""Strands in one repeat of :func:`strand_image` along the margin: 43.5 mm at the looks' spacing, so a margin (the
generic head's upper ones 29.6 mm, 87 strands) runs within one repeat and shows no strand twice (at 64 its last 8 mm
repeated its first). The first margin wears the shader's very strands; the others, laid 100 mm apart along u, wear
strands of the same rule numbered otherwise (the image numbers them round its repeat, the shader does not)."""


def strand_image(width: int = 16 * STRANDS, height: int = 64, supersample: int = 4) -> np.ndarray:
    """The shader's lash strands as coverage, for viewers that draw the cards from a texture (the GLB, the
    browser head): (height, width) uint8, :data:`STRANDS` strands across (u along the margin, repeating), the
    tips at row 0 and the roots at the bottom row; each strand a little off its place, of its own reach,
    leaning and thinning to its tip by the shader's rule, 16 texels a strand. The renderer's strands as far as a texture
    holds them: they repeat only past :data:`STRANDS` along a margin, but none is thinned for a short lash, and the
    far-off merging into a lash line is left to the viewer's mip levels."""
    looks = eye_looks()
    spacing, half_root = looks.lash_spacing, looks.lash_width
    n = supersample
    u = (np.arange(width * n) + 0.5) / (width * n) * STRANDS * spacing     # mm along the margin
    h = 1.0 - (np.arange(height * n) + 0.5) / (height * n)                  # 0 at the root .. 1 at the tip
    covered = np.zeros((height * n, width * n), bool)
    for shift in (-1, 0, 1):  # a strand's own place and its neighbours' (jitter and lean reach past one)
        ids = np.floor(u / spacing) + shift
        wrapped = np.mod(ids, STRANDS)
        reach = 0.7 + 0.3 * shader_hash(wrapped + 11.0)
        centre = (ids + 0.5 + 0.4 * (shader_hash(wrapped) - 0.5)) * spacing
        lean = 0.25 * (shader_hash(wrapped + 3.0) - 0.5) * h[:, None]
        half = half_root * (1.0 - 0.85 * h[:, None] / reach)
        covered |= (h[:, None] <= reach) & (np.abs(u - centre - lean) <= half)
    coverage = covered.reshape(height, n, width, n).mean(axis=(1, 3))
    return np.rint(coverage * 255).astype(np.uint8)


def strand_uv(layout: LashLayout) -> np.ndarray:
    """(3K, 2) texture coordinates of the cards on :func:`strand_image` (glTF's: v down): u the strand place
    along the margin, v 1 at the roots, 0.5 at the middles and 0 at the tips."""
    k = len(layout.rows)
    along = layout.static[:k, 5] / (STRANDS * eye_looks().lash_spacing)
    return np.c_[np.tile(along, 3), np.repeat([1.0, 0.5, 0.0], k)]
