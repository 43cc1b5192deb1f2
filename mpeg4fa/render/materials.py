"""Surface looks per head part: base colour, shininess, and the eye's iris and pupil.

Colours are linear RGB in [0, 1]. The skin's back faces are the mouth interior
(seen through the lips when the jaw opens), so it has its own material.
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace


@dataclass(frozen=True)
class Material:
    colour: tuple[float, float, float]
    specular: float = 0.1
    shininess: float = 20.0


@dataclass(frozen=True)
class Materials:
    skin: Material = Material((0.80, 0.56, 0.45), 0.12, 18.0)
    mouth: Material = Material((0.33, 0.07, 0.08), 0.05, 8.0)
    sclera: Material = Material((0.93, 0.91, 0.88), 0.45, 60.0)
    iris: tuple[float, float, float] = (0.30, 0.20, 0.11)
    pupil: tuple[float, float, float] = (0.02, 0.02, 0.02)
    teeth: Material = Material((0.93, 0.90, 0.82), 0.35, 40.0)
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
