"""The lid sheets' angle shares evened out where a blink would fold the skin at the eye corners.

Each lid vertex turns about the eye centre's x axis by its share (:attr:`.lids.LidSheet.ratios`) of
the lid point's angle. A margin vertex's share is what brings it onto the other lid at its x, so the
share rises from 0 at a corner (3.7/3.12, 3.8/3.11) to about 1 within a millimetre or two. At the
generic head's lateral corner the upper margin climbs 2.5 mm in 0.7 mm of x, so in the plane of the
turn its vertices passed the corner, then held fixed, as they closed: the corner's walls (which face sideways)
turned over, 42 triangles and 32 fold lines in a blink at 1000 IRISD (from about 369), 8 and 14 with
the lower lids at 300 (from about 215, so joy at 63 folded at its lower lids 260).

A triangle whose vertices share one angle turns rigidly and cannot fold, so where a closing lid
(the stages of :data:`UPPER_STAGES`, :data:`LOWER_STAGES` and both together, :data:`BOTH`) would fold
the skin, the shares are evened out (:func:`.fold_relief.even_out`). Feature points keep theirs (the lid
point its 1, every other point 0, the other lid's margin 0; the corners and that margin's ends excepted, below), so
each lid point still moves value x IRISD, and so does the margin but within :data:`CORNER_FREE_MM` of a corner (a
shut eye stays shut); the skin round the corners, some outside the sheet before, follows a little.
Measured on the generic head (folded / fold lines, both deformers): a blink at 1000 42 / 32 -> 14 / 14,
the lower lids at 300 8 / 14 -> 2 / 0, joy at 63 (lower lids 260) 6 / 14 -> 0 / 2 on the feature-point
deformer (the 2 left are the cheeks'). The folds left sit at the corners, where the margin must still
reach the other lid; with the whole margin free there were none, but the eye no longer shut.
Seen along the turn's axis the folds are the corner's sideways walls turned inside out: a margin vertex
0.5 mm above the fixed corner 3.7, at its distance from the axis, turns 2.8 deg past it. Capping every share
near a corner so that no vertex turns past the corner's own polar angle (fading out between R0 and R1 mm)
trades the folds for eyeball: R0 5 mm, blink 1000 0 folded / 8 fold lines but 48 eyeball pixels shut (the
lower margin lies below the corners); 3 mm, 14 / 14 and 2-16 pixels. Projecting the shares onto "no wall
inverted" constraints (per triangle, linear in the shares) did not converge: held margin vertices leave them
infeasible. Evening out never settles here and runs all :data:`.fold_relief.MAX_ROUNDS` (stopping at the
round that folded least gave more folds at a blink), so its result is kept in the user cache (:func:`.kept.kept`).

**The eye corners ride the lids.** 3.7/3.12 and 3.11/3.8, which no FAP names, are not held in the evening out, nor
is the other lid's margin within :data:`OTHER_FREE_MM` of them: they take the share of each lid's turn that their
neighbours give them, as a real eye's corners give a little as it shuts. On the generic head a blink at 1000 lowers
them 1.0 mm (lateral) and 1.4 mm (medial), the lower lids at 260 raise them 0.4 mm, shut 1.4-1.7 mm; as the lids
ride the eyes' pitch (:func:`.lids.lid_drops`) they move with them too (0.57 mm at 20 degrees up or down with the
corners alone free; real corners barely follow the gaze: not separated yet). Held, the margin beside a fixed corner
passed it; now (folded / fold lines, both deformers) a blink at 400-700 folds nothing (was 2 / 2 to 6 / 8), at 800 0
/ 2 (8 / 10), at 900 2 / 4 (8 / 14), at 1000 4 / 4 (14 / 14); the lower lids at 300-520 nothing (2 / 0); a blink at
500 over the lower lids at 260 nothing (4 / 2), at 1000 4 / 4 (10 / 10); the lower lids' strain 2.28 x its floor
(3.61). Steps on the way: the corners alone free (the other margin held) left the lower lids at 400 and 520 2 / 2
and 4 / 4, since a corner rising with the lower lid passed the upper margin's next vertex 0.5 mm above it; the other
margin freed within 2.5 mm folded nothing at all but the lower margin dipped with a blink and the eyeball showed
(tests/render/test_lid_pixels.py); freed for the upper lids alone, a smile's lower lids drew 2 fold lines on ARKit;
600 rounds of evening out instead of 200 did no better. With the corners free, :data:`CORNER_FREE_MM` went from 1.0
to 0.6 mm (at 1.0 the lower lids shut left 4 eyeball pixels); on this mesh 0.6 frees the lower margins' corners
alone (their next vertex is 0.8 mm in) and the upper margins' two nearest vertices (0.41 and 0.49 mm): any value
from 0.5 to 0.8 mm gives the same shares.
"""
from __future__ import annotations

import sys

import numpy as np

from mpeg4fa.face import fold_relief, motion
from mpeg4fa.face.fold_relief import even_out, skin_triangles
from mpeg4fa.face.kept import kept
from mpeg4fa.face.mesh import HeadMesh

UPPER_STAGES = (0.25, 0.5, 0.75, 1.0)
"""Shares of the eye's opening an upper lid closes in the check: a blink goes all the way (1000 IRISD of 1024)."""
LOWER_STAGES = (0.125, 0.25, 0.375, 0.5)
"""Shares of the opening a lower lid rises: joy at 63 asks 260 IRISD, twice that 520, about half the opening."""
BOTH = ((0.5, 0.25), (0.5, 0.5), (1.0, 0.25), (1.0, 0.5))
"""(upper, lower) shares together: a blink over the lower lids of a smile."""
CORNER_FREE_MM = 0.6
"""Margin vertices this close to a corner (straight line) may be evened out; the others keep the share that shuts
the eye on the other lid (freed all along, the evening out reached 3-5 mm in from the corners and a shut eye
showed 76 eyeball pixels at 320 x 160, tests/render/test_lid_pixels.py; freed within 2 mm, 2 with the lower lids
closed; within 1 mm, none while the corners were held, 4 once they rode the lids; within 0.6 mm, none)."""
OTHER_FREE_MM = 1.0
"""The other lid's margin vertices this close to a corner may be evened out too (held, a corner giving with one lid
passed the other margin's next vertex: the lower lids at 520 folded 4 triangles; freed within 2.5 mm, the lower
margin dipped with a blink and the eyeball showed). A shut upper margin still closes to the lower margin's rest
height, so 1-2 mm from a corner it stops up to 0.6 mm above the lower margin's dropped end; the lids' front edges,
which close onto each other, cover it (no eyeball pixel, tests/render/test_lid_pixels.py)."""


def _turned(rest: np.ndarray, fields: list[np.ndarray], joints: list[int], angles: np.ndarray) -> np.ndarray:
    """``(C, V, 3)``: ``rest`` turned once per case, each vertex about its lid's eye centre (``joints``, per field)
    by its share times the lid point's angle in the case (``angles``, ``(C, len(fields))``); turns about one
    eye's axis add up (as :func:`.lids.turn_lid` one lid after the other), the eyes are turned one after the other."""
    stack = np.repeat(rest[None], len(angles), axis=0)
    for joint in dict.fromkeys(joints):
        k = [i for i, j in enumerate(joints) if j == joint]
        rows = np.flatnonzero(np.any([fields[i] != 0 for i in k], axis=0))
        if not len(rows):
            continue
        a = angles[:, k] @ np.stack([fields[i][rows] for i in k])  # (C, R)
        c, s = np.cos(a), np.sin(a)
        centre = rest[joint]
        dy, dz = stack[:, rows, 1] - centre[1], stack[:, rows, 2] - centre[2]
        stack[:, rows, 1] = centre[1] + c * dy - s * dz
        stack[:, rows, 2] = centre[2] + s * dy + c * dz
    return stack


def even_out_lids(mesh: HeadMesh, eyes: list[tuple[int, int, int]], fields: list[np.ndarray],
                  held: list[np.ndarray]) -> list[np.ndarray]:
    """The lid shares (per vertex), evened out where their closing folds the skin (module docstring,
    :func:`.fold_relief.even_out`), every eye in one go (they blink together, and a round costs what one eye's did).
    ``eyes``: per eye (its centre joint, its upper lid point, its lower lid point); ``fields`` and ``held`` (the
    vertices whose share stays): per eye its upper lid's then its lower lid's."""
    rest = mesh.vertices
    cases = [(u, 0.0) for u in UPPER_STAGES] + [(0.0, low) for low in LOWER_STAGES] + list(BOTH)
    joints = [joint for joint, _, _ in eyes for _ in range(2)]
    angles = []
    for u, low in cases:  # each lid closes by its share of its eye's opening (3.1 to 3.3): the upper down, lower up
        row = []
        for joint, pu, pl in eyes:
            opening = float(rest[pu, 1] - rest[pl, 1])
            row += [motion.arc_angle(rest[p, 1:] - rest[joint, 1:], d * opening) if d else 0.0
                    for p, d in ((pu, u), (pl, -low))]
        angles.append(row)
    angles = np.array(angles)
    tris = skin_triangles(mesh)
    # evening out never settles at the generic head's corners and runs all its rounds (0.33 s of a 0.8 s rig
    # build); read back from the user cache, it costs milliseconds
    evened = kept("lid-shares", (rest, tris, *fields, *(np.unique(k) for k in held), angles),
                  (fold_relief, sys.modules[__name__]),
                  lambda: np.stack(even_out(rest, tris, fields, lambda f: _turned(rest, f, joints, angles), held)))
    return list(evened)
