"""Trajectory transfer (thesis §5.2): the doodle becomes the path the character's root follows.

For each action segment, in order:

1. the doodle is scaled to the world (a figurine of ``prop_size`` metres stands for a
   character of ``character_height`` metres: 0.2 m → 1.7 m by default) and projected on the
   ground along gravity;
2. a running spatial offset, kept over the whole doodle, is applied to the segment;
3. an in-place action's points are merged into its first point and the offset grows by
   the displacement that was removed, so the path stays continuous (§5.2);
4. a jumping action's horizontal travel is retimed to its execution stage: the root waits
   at the take-off point during preparation and anticipation and rests at the landing
   point during follow-through and transition (§5.2 "Retiming Jump trajectory");
5. the heading follows the path's direction while the character travels and is held
   while it acts in place.

The ground is any :mod:`retarget.terrain` (flat, height field, mesh): the path's height is
the ground's under it (a ray cast along gravity).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import gaussian_filter1d


@dataclass(frozen=True)
class Span:
    """One action segment in time, with what the transfer needs to know about it."""

    action: str
    t0: float
    t1: float
    i0: int  # doodle samples [i0, i1)
    i1: int
    in_place: bool
    jumping: bool
    cyclic: bool
    execution: tuple[float, float] = (0.0, 1.0)  # execution stage as fractions of the clip


def world_path(t: np.ndarray, p: np.ndarray, spans: list[Span], scale: float,
               terrain=None) -> tuple[np.ndarray, np.ndarray]:
    """Ground path (n, 3) of the root — on ``terrain`` (flat y = 0 when None), cast along
    gravity — and heading (n,) in radians about +y (0 faces +z)."""
    ground = (p - p[0]) * scale
    ground[:, 1] = 0.0
    path = ground.copy()
    offset = np.zeros(3)
    for s in spans:
        seg = slice(s.i0, s.i1)
        path[seg] = ground[seg] + offset
        if s.in_place:
            moved = path[s.i1 - 1] - path[s.i0]
            path[seg] = path[s.i0]
            offset -= moved
        elif s.jumping:
            path[seg] = _retimed_jump(t[seg], path[seg], s)
    heading = _heading(t, path, spans)
    if terrain is not None:
        path[:, 1] = terrain.height(path[:, [0, 2]])
    return path, heading


def _retimed_jump(t: np.ndarray, points: np.ndarray, span: Span) -> np.ndarray:
    """Travel only during execution: the segment's own path, squeezed into it."""
    if len(t) < 2:
        return points
    u = (t - t[0]) / max(t[-1] - t[0], 1e-9)
    a, b = span.execution
    w = np.clip((u - a) / max(b - a, 1e-6), 0.0, 1.0)
    src = w * (len(points) - 1)
    k = np.minimum(np.floor(src).astype(int), len(points) - 2)
    f = (src - k)[:, None]
    return points[k] * (1 - f) + points[k + 1] * f


TURNING_SPEED = 0.3  # m/s: slower drift of the path (a hand at rest) does not turn the character


def _heading(t: np.ndarray, path: np.ndarray, spans: list[Span]) -> np.ndarray:
    n = len(path)
    if n < 2:
        return np.zeros(n)
    step = np.gradient(gaussian_filter1d(path, 3.0, axis=0, mode="nearest"), t, axis=0)
    speed = np.hypot(step[:, 0], step[:, 2])
    moving = speed > TURNING_SPEED
    for s in spans:  # in place and sidesteps keep the heading; walking back faces away from travel
        if s.in_place or "Side Walk" in s.action:
            moving[s.i0:s.i1] = False
    yaw = np.arctan2(step[:, 0], step[:, 2])
    for s in spans:
        if "Walk Back" in s.action:
            yaw[s.i0:s.i1] += np.pi
    heading = np.zeros(n)
    current = float(yaw[np.flatnonzero(moving)[0]]) if moving.any() else 0.0
    for i in range(n):
        if moving[i]:
            current = float(yaw[i])
        heading[i] = current
    return np.unwrap(heading)
