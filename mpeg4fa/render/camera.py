"""Cameras as plain matrices: where the viewer stands and how the head is framed.

Matrices are numpy (4, 4) float64, column-vector convention (``clip = P @ V @ p``);
they are handed to GL transposed. Units are the mesh's (millimetres).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

VIEWS = {"front": (0.0, 0.0), "left": (90.0, 0.0), "right": (-90.0, 0.0), "three-quarter": (30.0, 5.0)}
"""Named viewpoints as (yaw, pitch) degrees around the head: yaw 90 looks at the face's left side."""


@dataclass(frozen=True)
class Camera:
    view: np.ndarray        # (4, 4) world -> eye
    projection: np.ndarray  # (4, 4) eye -> clip
    position: np.ndarray    # (3,) eye position in world (for specular light)
    orthographic: bool = False

    @property
    def matrix(self) -> np.ndarray:
        """World -> clip."""
        return self.projection @ self.view

    def project(self, points: np.ndarray, width: int, height: int) -> np.ndarray:
        """Pixel coordinates (x right, y down, origin top-left, pixel centres at .5) and depth of points."""
        p = np.c_[np.asarray(points, float), np.ones(len(points))] @ self.matrix.T
        ndc = p[:, :3] / p[:, 3:4]
        x = (ndc[:, 0] + 1.0) * 0.5 * width
        y = (1.0 - ndc[:, 1]) * 0.5 * height
        return np.c_[x, y, ndc[:, 2]]


def look_at(eye: np.ndarray, target: np.ndarray, up=(0.0, 1.0, 0.0)) -> np.ndarray:
    eye, target, up = (np.asarray(a, float) for a in (eye, target, up))
    forward = target - eye
    forward /= np.linalg.norm(forward)
    side = np.cross(forward, up)
    side /= np.linalg.norm(side)
    true_up = np.cross(side, forward)
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = side, true_up, -forward
    m[:3, 3] = -m[:3, :3] @ eye
    return m


def perspective(fov_y_deg: float, aspect: float, near: float, far: float) -> np.ndarray:
    f = 1.0 / np.tan(np.radians(fov_y_deg) / 2.0)
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = f / aspect, f
    m[2, 2], m[2, 3] = (far + near) / (near - far), 2.0 * far * near / (near - far)
    m[3, 2] = -1.0
    return m


def ortho(half_width: float, half_height: float, near: float, far: float) -> np.ndarray:
    m = np.eye(4)
    m[0, 0], m[1, 1] = 1.0 / half_width, 1.0 / half_height
    m[2, 2], m[2, 3] = -2.0 / (far - near), -(far + near) / (far - near)
    return m


def _direction(yaw_deg: float, pitch_deg: float) -> np.ndarray:
    """Unit vector from the head toward the camera (yaw about y, pitch about x; 0,0 = +z)."""
    yaw, pitch = np.radians(yaw_deg), np.radians(pitch_deg)
    return np.array([np.sin(yaw) * np.cos(pitch), np.sin(pitch), np.cos(yaw) * np.cos(pitch)])


def frame_points(points: np.ndarray, width: int, height: int, *, view: str | tuple[float, float] = "front",
                 fov: float = 20.0, margin: float = 0.15, orthographic: bool = False) -> Camera:
    """A camera that fits ``points`` (e.g. the face's feature points) with ``margin`` to spare.

    The frame is sized from the points' bounding sphere so it does not change as the
    view turns; ``orthographic`` gives a parallel projection (for photos and texture work).
    """
    pts = np.asarray(points, float)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    centre = (lo + hi) / 2.0
    yaw, pitch = VIEWS[view] if isinstance(view, str) else view
    d = _direction(yaw, pitch)
    aspect = width / height
    # extent seen across the view direction, from the box corners
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    view_m = look_at(centre + d, centre)
    local = (corners - centre) @ view_m[:3, :3].T
    half_h = max(np.abs(local[:, 1]).max(), np.abs(local[:, 0]).max() / aspect) * (1.0 + margin)
    depth = np.abs(local[:, 2]).max()
    if orthographic:
        distance = 4.0 * depth + 4.0 * half_h + 10.0
        projection = ortho(half_h * aspect, half_h, 1.0, 2.0 * distance)
    else:
        distance = half_h / np.tan(np.radians(fov) / 2.0) + depth
        # generous clip planes: a close-up framed on a few points must not cut the rest of the head
        projection = perspective(fov, aspect, distance / 8.0, 4.0 * distance + 3.0 * depth)
    eye = centre + distance * d
    return Camera(view=look_at(eye, centre), projection=projection, position=eye, orthographic=orthographic)
