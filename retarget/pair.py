"""Two-character clips (thesis §6.2.2, first transfer method): the relative placement of the
characters at an interaction's first frame, read from one BVH per character on one timeline
— the vector between their roots, in the first character's frame, and the turn between
their headings (``I¹₀I²₀`` and ``(q¹₀)⁻¹ q²₀``). Clips face +z in our frame (the sequencer
turns them by the path's heading), so a root's heading is its rotation applied to +z.
"""

from __future__ import annotations

import numpy as np

from doodle.core import quat

UP = np.array([0.0, 1.0, 0.0])


def heading(root_rotation) -> np.ndarray:
    """Unit ground-plane front of a root rotation (xyzw)."""
    f = quat.front(np.asarray(root_rotation, dtype=float)) * [1.0, 0.0, 1.0]
    return f / max(float(np.linalg.norm(f)), 1e-9)


def placement(first, second) -> tuple[float, float, float]:
    """``(x, z, turn)`` of the second character's root relative to the first at frame 0:
    metres to its right and in front of it, degrees its heading is turned from the first's —
    the manifest's ``placement`` (``doodle.app.placement``)."""
    a, b = first.translations[0, 0], second.translations[0, 0]
    front = heading(first.rotations[0, 0])
    right = np.cross(front, UP)
    d = (b - a) * [1.0, 0.0, 1.0]
    other = heading(second.rotations[0, 0])
    turn = np.degrees(np.arctan2(other[0], other[2]) - np.arctan2(front[0], front[2]))
    return float(d @ right), float(d @ front), float((turn + 180.0) % 360.0 - 180.0)
