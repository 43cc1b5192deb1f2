"""The face shader's hash (``hash`` in ``shaders/face.frag.glsl``) for the images made with numpy (iris, lash strands,
brow hairs): one rule, so that what a texture holds is placed as the shader would place it."""
from __future__ import annotations

import numpy as np


def shader_hash(x: np.ndarray) -> np.ndarray:
    """``fract(sin(x * 127.1 + 311.7) * 43758.5453)``: a pseudo-random value in [0, 1) per ``x``."""
    v = np.sin(np.asarray(x, np.float64) * 127.1 + 311.7) * 43758.5453
    return v - np.floor(v)
