"""Eye geometry for the parabolic eye model: eyeballs as spheres, lid contours as parabolas.

Kept apart from the deformer (:mod:`.deformers.parabolic`) because it is plain geometry
that tests and tools can check on their own:

* :func:`fit_sphere`: the least-squares sphere through an eye part's vertices (the
  eyeball's centre and radius, and how far the mesh is from being that sphere);
* :class:`EyeFrame`: an eye's own 2-D frame, origin midway between its corners,
  ``x`` along the corner-to-corner line and ``y`` the *vertical* height above that
  line (a shear of the face's x/y, not a rotation: a lid that moves vertically in
  the face moves along ``y`` in the frame, so the FAPU semantics, value x IRISD
  straight down, carry over unchanged);
* :class:`Parabola`: ``y = a (x - b)^2 + c`` through three points, and the lid
  closing: the middle point moves by ``d`` while both corners stay, which changes
  ``a`` and ``c`` and keeps ``b`` (in the eye frame both corners are at ``y = 0``, so
  ``b`` is their midpoint, 0).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mpeg4fa.face.errors import FaceError


@dataclass(frozen=True)
class Sphere:
    """A fitted sphere and how well the points fit it (mm)."""

    centre: np.ndarray  # (3,)
    radius: float
    rms_residual: float  # root mean square of |p - centre| - radius
    max_residual: float  # largest |(|p - centre| - radius)|


def fit_sphere(points: np.ndarray, *, iterations: int = 3) -> Sphere:
    """The least-squares sphere through ``points`` (N >= 4, not coplanar).

    The algebraic fit (linear in centre and ``r^2 - |c|^2``) gives the start; a few
    Gauss-Newton steps on the geometric residuals ``|p - c| - r`` refine it, so that a
    mesh that is a sphere comes back to rounding (the algebraic fit alone is ~1e-10 mm off).
    """
    p = np.asarray(points, dtype=np.float64)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 4:
        raise FaceError(f"a sphere needs at least 4 points in 3-D, got an array of shape {p.shape}")
    origin = p.mean(axis=0)
    q = p - origin  # centred: better conditioned
    a = np.c_[2.0 * q, np.ones(len(q))]
    sol, *_ = np.linalg.lstsq(a, (q * q).sum(axis=1), rcond=None)
    centre = sol[:3]
    r2 = sol[3] + centre @ centre
    if not np.isfinite(r2) or r2 <= 0 or np.linalg.matrix_rank(a) < 4:
        raise FaceError("the points do not determine a sphere (coplanar or degenerate)",
                        hint="an eye part must be a closed ball-like mesh")
    radius = float(np.sqrt(r2))
    for _ in range(iterations):
        off = q - centre
        dist = np.linalg.norm(off, axis=1)
        jac = np.c_[-off / dist[:, None], -np.ones(len(q))]
        step, *_ = np.linalg.lstsq(jac, -(dist - radius), rcond=None)
        centre = centre + step[:3]
        radius += float(step[3])
    res = np.linalg.norm(q - centre, axis=1) - radius
    return Sphere(centre=centre + origin, radius=radius, rms_residual=float(np.sqrt(np.mean(res ** 2))),
                  max_residual=float(np.abs(res).max()))


@dataclass(frozen=True)
class EyeFrame:
    """An eye's 2-D frame: ``x`` along its corner line (face x), ``y`` height above that line (face y)."""

    origin: np.ndarray  # (3,) midway between the corners
    slope: float  # dy/dx of the corner-to-corner line in the face's x/y plane

    @classmethod
    def from_corners(cls, lateral: np.ndarray, medial: np.ndarray) -> "EyeFrame":
        lateral, medial = np.asarray(lateral, float), np.asarray(medial, float)
        dx = medial[0] - lateral[0]
        if abs(dx) < 1e-9:
            raise FaceError("the eye corners have the same x: no corner-to-corner line",
                            hint="check the eye corner feature points (3.7/3.11, 3.12/3.8)")
        return cls(origin=(lateral + medial) / 2.0, slope=float((medial[1] - lateral[1]) / dx))

    def to_frame(self, points: np.ndarray) -> np.ndarray:
        """``(..., 2)`` frame coordinates of ``(..., 3)`` face points."""
        p = np.asarray(points, dtype=np.float64)
        x = p[..., 0] - self.origin[0]
        return np.stack([x, p[..., 1] - self.origin[1] - self.slope * x], axis=-1)


@dataclass(frozen=True)
class Parabola:
    """``y = a (x - b)^2 + c``."""

    a: float
    b: float
    c: float

    def __call__(self, x: np.ndarray) -> np.ndarray:
        return self.a * (np.asarray(x, dtype=np.float64) - self.b) ** 2 + self.c

    @classmethod
    def through(cls, p1: np.ndarray, p2: np.ndarray, p3: np.ndarray) -> "Parabola":
        """The parabola through three points ``(x, y)`` with distinct x, not on one line."""
        (x1, y1), (x2, y2), (x3, y3) = (np.asarray(p, dtype=np.float64)[:2] for p in (p1, p2, p3))
        d12, d13, d23 = x1 - x2, x1 - x3, x2 - x3
        if min(abs(d12), abs(d13), abs(d23)) < 1e-12:
            raise FaceError("a contour parabola needs three points with distinct x",
                            hint="the eye corners and the lid point must not be above one another")
        # y = A x^2 + B x + C by divided differences
        first12, first23 = (y1 - y2) / d12, (y2 - y3) / d23
        big_a = (first12 - first23) / d13
        if abs(big_a) < 1e-12:
            raise FaceError("the eye corners and the lid point are on one line: no lid parabola",
                            hint="the lid point must be above (upper) or below (lower) the corner line")
        big_b = first12 - big_a * (x1 + x2)
        b = -big_b / (2.0 * big_a)
        c = y2 - big_a * (x2 - b) ** 2  # the vertex form's c is the height at b
        return cls(a=float(big_a), b=float(b), c=float(c))


def lid_parabola(frame: EyeFrame, lateral: np.ndarray, middle: np.ndarray, medial: np.ndarray) -> Parabola:
    """A lid contour in its eye's frame: the parabola through both corners and the lid's middle point."""
    return Parabola.through(*frame.to_frame(np.array([lateral, middle, medial])))


def closed_by(parabola: Parabola, corners_x: tuple[float, float], middle_x: float, d: float) -> Parabola:
    """The contour after its middle point (at ``middle_x``) moved by ``d`` in y, both corners fixed.

    The change of height is ``d * L(x)``, ``L`` the parabola through ``(x1, 0)``, ``(x2, 0)``
    and ``(m, 1)`` (:func:`middle_share`): ``a`` gains ``d / ((m - x1)(m - x2))``; in the eye
    frame, where both corners are at ``y = 0``, ``b`` is their midpoint and stays, and ``c``
    gains ``d h^2 / (h^2 - (m - b)^2)`` (``h`` half the corner distance): ``d`` exactly when the
    middle point is at the apex, a fraction of a percent more on a real eye (whose lid point is
    a little off the corners' midpoint).
    """
    x1, x2 = corners_x
    da = d / ((middle_x - x1) * (middle_x - x2))
    # old + da (x - x1)(x - x2), in the form A x^2 + B x + C, back to the vertex form
    big_a = parabola.a + da
    big_b = -2.0 * parabola.a * parabola.b - da * (x1 + x2)
    big_c = parabola.a * parabola.b ** 2 + parabola.c + da * x1 * x2
    if abs(big_a) < 1e-15:  # the contour passes through flat: a line (b, the corners' midpoint, by convention)
        b = (x1 + x2) / 2.0
        return Parabola(a=0.0, b=float(b), c=float(big_c + big_b * b))
    b = -big_b / (2.0 * big_a)
    return Parabola(a=float(big_a), b=float(b), c=float(big_c - big_a * b * b))


def middle_share(x: np.ndarray, corners_x: tuple[float, float], middle_x: float) -> np.ndarray:
    """``L(x) = (x - x1)(x - x2) / ((m - x1)(m - x2))``: how much of the middle point's motion a
    contour point at ``x`` takes when the parabola changes with both corners fixed (0 at the
    corners, 1 at the middle point, exactly)."""
    x1, x2 = corners_x
    x = np.asarray(x, dtype=np.float64)
    return (x - x1) * (x - x2) / ((middle_x - x1) * (middle_x - x2))


@dataclass(frozen=True)
class EyeLooks:
    """Sizes of the living eye's details (``data/eyes.csv``): cornea, tear film, lashes."""

    cornea_radius: float
    wet_specular: float
    wet_shininess: float
    upper_lash_length: float
    lower_lash_length: float
    lash_peak: float
    lash_lift: float
    lash_curl: float
    lower_lash_lift: float
    lower_lash_curl: float
    lash_spacing: float
    lash_width: float


_LOOKS: EyeLooks | None = None


def eye_looks() -> EyeLooks:
    """The eye details' sizes, read once from ``data/eyes.csv`` (angles stay in degrees)."""
    global _LOOKS
    if _LOOKS is None:
        import csv
        from dataclasses import fields
        from importlib import resources

        with (resources.files("mpeg4fa.face") / "data" / "eyes.csv").open(encoding="utf-8") as f:
            rows = {r["name"]: float(r["value"]) for r in csv.DictReader(f)}
        names = [fld.name for fld in fields(EyeLooks)]
        missing = sorted(set(names) - set(rows))
        if missing:
            raise FaceError(f"data/eyes.csv lacks {', '.join(missing)}")
        _LOOKS = EyeLooks(**{n: rows[n] for n in names})
    return _LOOKS
