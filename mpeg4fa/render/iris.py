"""The iris's pattern as a small texture in polar coordinates, made once with numpy.

The shader used to compute it per fragment (a dozen sines and exponentials); Mesa's llvmpipe runs
every branch of a shader for every fragment, so that cost the whole image about half its render
time. Sampled from a texture it costs one fetch. Columns go round the iris (``theta`` from -pi to
pi, left to right, wrapping), rows go out from the pupil's edge (row 0, ``r`` = 0) to the limbus
(``r`` = 1). Values are RGB brightness factors about 1 that multiply the iris colour: radial fibres
that wave a little as they run out, a jagged collarette about a third of the way out with the
darker pupillary zone inside it, crypts just outside it, two contraction furrows, the dark limbal
ring and the pupil's dark rim; the light fibres paler and yellower.
"""
from __future__ import annotations

import numpy as np

from mpeg4fa.render.shader_hash import shader_hash

AROUND, OUT = 512, 64  # texels: 97 fibres around need at least 4 texels each
IRIS_SCALE = 2.0  # the factors reach 1.9: stored over this in 8 bits, the shader multiplies it back


def _smoothstep(a: float, b: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - a) / (b - a), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def iris_pattern(around: int = AROUND, out: int = OUT) -> np.ndarray:
    """(out, around, 3) float32 brightness factors of the iris (see the module docstring)."""
    theta = (np.arange(around) + 0.5) / around * 2.0 * np.pi - np.pi
    r = (np.arange(out) + 0.5) / out
    theta, r = np.meshgrid(theta, r)
    fibres = (0.5 + 0.3 * np.sin(97.0 * theta + 1.7 * np.sin(11.0 * theta + 4.0 * r))
              + 0.2 * np.sin(53.0 * theta - 2.3 * r + 1.3 * np.sin(7.0 * theta)))
    ruff_r = 0.3 + 0.04 * np.sin(11.0 * theta) + 0.02 * np.sin(23.0 * theta + 1.0)
    ruff = np.exp(-((r - ruff_r) / 0.05) ** 2)
    pupillary = 1.0 - _smoothstep(-0.03, 0.03, r - ruff_r)
    cells = 16.0 / (2.0 * np.pi)
    cell = np.floor(theta * cells)
    across_cell = np.abs(theta * cells - cell - 0.5)
    crypt = ((shader_hash(cell) > 0.55) * np.exp(-((r - ruff_r - 0.14 - 0.1 * shader_hash(cell + 5.0)) / 0.06) ** 2)
             * _smoothstep(0.2, 0.0, across_cell - 0.15))
    furrows = np.exp(-((r - 0.72) / 0.025) ** 2) + np.exp(-((r - 0.86) / 0.02) ** 2)
    b = (0.8 + 0.45 * fibres) * (1.0 - pupillary) + (0.7 + 0.2 * fibres) * pupillary
    b = b * (1.0 + 0.45 * ruff - 0.45 * crypt - 0.2 * furrows * (0.6 + 0.4 * np.sin(5.0 * theta)))
    b = b * (1.0 + (0.45 - 1.0) * _smoothstep(0.82, 1.0, r))   # the dark limbal ring
    b = b * (0.55 + 0.45 * _smoothstep(0.0, 0.06, r))         # the pupil's dark rim
    pale = 0.5 * fibres * (1.0 - pupillary)
    warm = 1.0 + pale[..., None] * (np.array([1.25, 1.1, 0.8]) - 1.0)
    return (b[..., None] * warm).astype(np.float32)
