"""Feature points annotated by eye on real photos, for the texture tests.

``ASTRONAUT`` is on scikit-image's ``skimage.data.astronaut()`` (512 x 512, public
domain: NASA's portrait of Eileen Collins), read off 10x enlargements with a
pixel grid. Coordinates are pixels, x right, y down. MPEG-4 left/right are the
face's own: her left eye (3.5, 3.7, 3.11) is on the image's right.

Left out on purpose: the hairline 11.1 (her fringe hides it), the ears 10.x
(under her hair), the nostrils 9.1/9.2 and the jaw corners 2.13/2.14 (no clear
edge). She smiles with her teeth showing, so the mouth corners sit wider and the
lip midpoints further apart than on the neutral head.
"""
from __future__ import annotations

ASTRONAUT: dict[str, tuple[float, float]] = {
    # eyes: pupils, then outer and inner corners
    "3.5": (246.5, 102.5),   # left pupil
    "3.6": (203.5, 100.5),   # right pupil
    "3.7": (259.0, 103.0),   # left eye, outer corner
    "3.11": (235.5, 102.5),  # left eye, inner corner
    "3.8": (213.5, 101.5),   # right eye, inner corner
    "3.12": (192.5, 100.0),  # right eye, outer corner
    # eyebrows: uppermost points
    "4.3": (249.0, 92.0),
    "4.4": (202.0, 91.0),
    # nose tip (the highlight)
    "9.3": (223.5, 126.5),
    # mouth: outer lip corners and midpoints
    "8.3": (243.0, 141.5),   # left corner
    "8.4": (204.5, 140.0),   # right corner
    "8.1": (224.0, 139.0),   # upper lip, outer contour
    "8.2": (224.0, 154.0),   # lower lip, outer contour
    # bottom of the chin
    "2.1": (222.0, 177.0),
}

ASTRONAUT_SKIN_PATCH = (slice(115, 127), slice(240, 252))
"""(rows, columns) of a plain skin patch on her left cheek, for reference colours."""
