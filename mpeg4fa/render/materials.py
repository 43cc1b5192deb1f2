"""Surface looks per head part: base colour, shininess, and the eye's iris and pupil.

Colours are linear RGB in [0, 1]. Three colours are mixed into the skin by
per-vertex weights (:mod:`.details`): ``lips`` and ``brows`` into the untextured
skin only (a photo texture has its own), ``cavity`` always (the inside of the
mouth bag, dark, also on a textured face, whose photo never saw it). ``mouth``
is the skin's back faces (the inside of the head, seen only from below the neck
cut), ``gums`` the teeth above their gum line.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
from scipy.interpolate import CubicSpline


@dataclass(frozen=True)
class Material:
    colour: tuple[float, float, float]
    specular: float = 0.1
    shininess: float = 20.0


@dataclass(frozen=True)
class Materials:
    skin: Material = Material((0.80, 0.56, 0.45), 0.12, 18.0)
    lips: tuple[float, float, float] = (0.68, 0.33, 0.33)   # mixed into the untextured skin on the lips
    mouth: Material = Material((0.16, 0.08, 0.07), 0.02, 8.0)
    cavity: tuple[float, float, float] = (0.10, 0.025, 0.03)  # deep in the mouth, mixed into the skin
    brows: tuple[float, float, float] = (0.16, 0.10, 0.065)  # mixed into the untextured skin on the brows
    sclera: Material = Material((0.93, 0.91, 0.88), 0.45, 60.0)
    iris: tuple[float, float, float] = (0.30, 0.20, 0.11)
    pupil: tuple[float, float, float] = (0.02, 0.02, 0.02)
    lashes: tuple[float, float, float] = (0.045, 0.032, 0.026)  # the lash cards (render/lashes.py)
    teeth: Material = Material((0.93, 0.90, 0.82), 0.35, 40.0)
    gums: Material = Material((0.72, 0.36, 0.36), 0.2, 25.0)
    tongue: Material = Material((0.72, 0.30, 0.30), 0.25, 30.0)
    background: tuple[float, float, float] = (0.16, 0.18, 0.22)
    extra: dict = field(default_factory=dict)

    def with_colours(self, **colours) -> "Materials":
        """A copy with some base colours changed, e.g. ``skin=(0.6, 0.4, 0.3)``, ``iris=(0.2, 0.3, 0.5)``."""
        changes = {}
        for name, colour in colours.items():
            current = getattr(self, name)
            changes[name] = replace(current, colour=tuple(colour)) if isinstance(current, Material) else tuple(colour)
        return replace(self, **changes)


PART_MATERIAL = {"skin": 0, "eye_l": 1, "eye_r": 2, "teeth_upper": 3, "teeth_lower": 3, "tongue": 4}
"""Material slot of each drawn part (the shader's ``material`` attribute); ``joints`` is not drawn."""
TEETH = ("teeth_upper", "teeth_lower")
"""The parts that are the teeth (one material, one baked image)."""


LIP_OUTLINE = ("8.4", "8.6", "8.9", "8.1", "8.10", "8.5", "8.3", "8.7", "8.2", "8.8")
"""The outer lip contour (vermilion border) as feature points, going round from the right corner."""


def lip_weights(vertices: np.ndarray, outline: np.ndarray, *, edge: float = 1.2, depth: float = 8.0) -> np.ndarray:
    """0..1 per vertex: how much it lies on the lips, seen from the front.

    The outline points are joined by a closed spline; vertices inside it (in x-y) and
    no deeper than ``depth`` mm behind its rearmost point weigh 1, fading to 0 over
    ``edge`` mm outside, so the lip colour follows the lips as they move.
    """
    loop = np.vstack([outline, outline[:1]])
    chord = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(loop[:, :2], axis=0), axis=1))]
    curve = CubicSpline(chord, loop, bc_type="periodic")(np.linspace(0.0, chord[-1], 161))
    a, b = curve[:-1, :2], curve[1:, :2]
    p = vertices[:, None, :2]
    # inside: crossings of a ray toward +x
    straddle = (a[None, :, 1] > p[..., 1]) != (b[None, :, 1] > p[..., 1])
    with np.errstate(divide="ignore", invalid="ignore"):
        x_cross = a[None, :, 0] + (p[..., 1] - a[None, :, 1]) * (b - a)[None, :, 0] / (b - a)[None, :, 1]
    inside = (straddle & (x_cross > p[..., 0])).sum(axis=1) % 2 == 1
    # distance to the outline, for a soft edge outside
    ab = b - a
    t = np.clip(((p - a[None]) * ab[None]).sum(-1) / np.maximum((ab * ab).sum(-1), 1e-12)[None], 0.0, 1.0)
    dist = np.linalg.norm(p - (a[None] + t[..., None] * ab[None]), axis=-1).min(axis=1)
    w = np.where(inside, 1.0, np.clip(1.0 - dist / edge, 0.0, 1.0))
    w = w * w * (3.0 - 2.0 * w)
    front = vertices[:, 2] >= outline[:, 2].min() - depth
    return np.where(front, w, 0.0)
