"""The brows' hairs as a small texture over the brow's own coordinates, made once with numpy.

The brow is drawn by the face shader from each skin point's (along, height) relative to the brow
(:func:`.details.brow_coordinates`: along 0 at the inner brow point to 1 at the outer one, height in mm above
the curve through the three brow points). Its hairs used to be one sawtooth across it, 27 even stripes that
read as hatching close up. Here they grow as hairs do: along a flow that rises steeply at the inner end and
lies nearly flat at the outer one, each of its own place, length, taper and darkness, in two layers turned a
little apart so that they cross. Mesa's llvmpipe runs every branch of a shader for every fragment: drawn in
the skin's program, two layers of hashed hairs cost the whole image a quarter more render time, and even one
lookup of this texture a third more. So the hairs are this mipmapped texture (the mipmaps give their mean cover
from afar), sampled only by the shader's BROWS variant, which draws the skin's triangles about the brows
(:func:`about_the_brows`): 1.04 x the render time without it (``tools/bench_render_brows.json``).

Columns run along the brow (``along`` from :data:`ALONG[0]` to :data:`ALONG[1]`), rows up it (``height``
from :data:`HEIGHT[0]` to :data:`HEIGHT[1]` mm, row 0 the lowest). Values are the hairs' cover, 0..1.
"""
from __future__ import annotations

import sys
from functools import lru_cache

import numpy as np

from mpeg4fa.face.kept import kept
from mpeg4fa.render.shader_hash import shader_hash

ALONG = (-0.06, 1.08)
"""The span of ``along`` the texture covers (the brow's shape, in the shader, lies within it)."""
HEIGHT = (-6.0, 6.0)
"""The span of ``height`` (mm) the texture covers: the shader's widest brow (3.3 mm each side of a line 0.4 mm below
the brow curve) with its soft edge (0.45) and stray hairs (``BROW_STRAY_MM``, 0.5) reaches 4.65 below and 3.85 above;
:func:`about_the_brows` picks the triangles by this span, so a brow drawn wider must widen it."""
SPAN_MM = 31.5
"""Mm of brow per unit of ``along`` the hairs are laid out for (the generic head's 4.1 to 4.5 in x; a head with
longer brows draws its hairs as much longer)."""
SIZE = (1024, 256)
"""Texels (along, up): about 0.035 x 0.047 mm, about four across a hair at its root."""
GAP_MM = 0.25
"""Mm between a layer's rows of hairs, across their flow."""
HAIR_MM = 3.6
"""The longest hair."""
HALF_WIDTH_MM = 0.09
"""A hair's half width at its root (it thins to a tenth of that at its tip)."""


def slope(t: np.ndarray) -> np.ndarray:
    """Tangent of the hairs' angle above the brow line at ``along`` ``t``: 66 degrees at the inner end (the second
    layer 69), level about four fifths of the way out, a little down at the outer end."""
    return 2.4 * (1.0 - t) ** 2 - 0.12


def rise(t: np.ndarray) -> np.ndarray:
    """Mm a flow line climbs from the inner end to ``along`` ``t`` (the integral of :func:`slope` over mm)."""
    return SPAN_MM * (0.8 * (1.0 - (1.0 - t) ** 3) - 0.12 * t)


def _layer(along: np.ndarray, height: np.ndarray, seed: float) -> np.ndarray:
    """One layer's cover at each point: the band between flow lines it lies in holds a row of hairs, staggered
    band to band, each with its own offset, length, taper and darkness."""
    t = np.clip(along, 0.0, 1.0)
    turn = 1.0 + 0.15 * seed  # the second layer a little steeper
    k = slope(t) * turn
    c = 1.0 / np.sqrt(1.0 + k * k)  # cos of the hairs' angle
    v = height - rise(t) * turn  # which flow line (mm of height where it leaves the inner end)
    u = (along * SPAN_MM + height * k) * c  # mm along the hairs (here)
    band = np.floor(v / GAP_MM + 0.5 * seed)
    u0 = u + shader_hash(band * 1.731 + 17.0 * seed) * HAIR_MM
    cell = np.floor(u0 / HAIR_MM)
    r2 = shader_hash(cell * 5.37 + band * 0.773 + 29.0 * seed)
    r3 = shader_hash(cell * 2.11 + band * 1.913 + 41.0 * seed)
    r4 = shader_hash(cell * 3.77 + band * 2.53 + 53.0 * seed)
    length = HAIR_MM * (0.45 + 0.5 * r2)
    along_hair = (u0 - cell * HAIR_MM - 0.1 * r3 * HAIR_MM) / length  # 0 at the root .. 1 at the tip
    lean = (r4 - 0.5) * 0.8 * GAP_MM * np.clip(along_hair, 0.0, 1.0)  # each hair a little off the flow
    centre = (band - 0.5 * seed + 0.5 + 0.8 * (r2 - 0.5)) * GAP_MM + lean
    across = np.abs(v - centre) * c  # mm across the hair
    half = HALF_WIDTH_MM * (1.0 - 0.9 * np.clip(along_hair, 0.0, 1.0))
    on = (across <= half) & (along_hair >= 0.0) & (along_hair <= 1.0)
    return on * (0.7 + 0.3 * r3)


@lru_cache(maxsize=1)
def brow_hair_image(size: tuple[int, int] = SIZE, supersample: int = 2) -> np.ndarray:
    """(rows, columns) uint8, read-only: the hairs' cover over the texture's span (module docstring), its edge texels
    bare. Made in 0.3-0.4 s, then read back from the user cache (:func:`mpeg4fa.face.kept.kept`)."""
    image = kept("brow-hairs", (np.array([*size, supersample]),), (sys.modules[__name__],),
                 lambda: _hair_image(size, supersample))
    image.flags.writeable = False  # shared by every renderer of the process
    return image


def _hair_image(size: tuple[int, int], supersample: int) -> np.ndarray:
    width, height = size
    n = supersample
    along = ALONG[0] + (np.arange(width * n) + 0.5) / (width * n) * (ALONG[1] - ALONG[0])
    up = HEIGHT[0] + (np.arange(height * n) + 0.5) / (height * n) * (HEIGHT[1] - HEIGHT[0])
    along, up = np.meshgrid(along, up)
    a, b = _layer(along, up, 0.0), _layer(along, up, 1.0)
    cover = 1.0 - (1.0 - a) * (1.0 - b)
    image = cover.reshape(height, n, width, n).mean(axis=(1, 3))
    image[[0, -1], :] = 0.0
    image[:, [0, -1]] = 0.0
    return np.rint(image * 255).astype(np.uint8)


def about_the_brows(detail: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """(T,) bool: the triangles whose brow coordinates (``detail``, per vertex: along, height) reach into the
    texture's span, where a brow or its stray hairs may show; the renderer draws them by the shader's BROWS variant,
    so that only they pay for the hairs' lookup."""
    d = np.asarray(detail, np.float64)[np.asarray(triangles)]  # (T, 3, 2)
    lo, hi = d.min(axis=1), d.max(axis=1)
    return (hi[:, 0] >= ALONG[0]) & (lo[:, 0] <= ALONG[1]) & (hi[:, 1] >= HEIGHT[0]) & (lo[:, 1] <= HEIGHT[1])
