"""What every deformer returns: the posed vertices of one frame, and what is not geometry."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Pose:
    """A deformed face: all vertices, plus what is not geometry (pupil sizes)."""

    vertices: np.ndarray  # (V, 3)
    parts: dict[str, slice]
    pupil_diameter: dict[str, float]  # mm, per eye part
    fp_vertex: np.ndarray

    def part(self, name: str) -> np.ndarray:
        return self.vertices[self.parts[name]]

    def by_part(self) -> dict[str, np.ndarray]:
        """Vertex positions per part (views, no copy)."""
        return {name: self.vertices[s] for name, s in self.parts.items()}

    @property
    def feature_points(self) -> np.ndarray:
        """``(84, 3)`` feature point positions in this pose."""
        return self.vertices[self.fp_vertex]
