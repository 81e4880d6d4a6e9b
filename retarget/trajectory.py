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
5. the heading follows the path's direction while the character travels — turned by the
   clip's own direction of travel, so a side-step moves sideways and a walk back backwards
   — and is held while it acts in place.

The ground is any :mod:`retarget.terrain` (flat, height field, mesh): the path's height is
the ground's under it (a ray cast along gravity).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doodle.core.filters import gaussian_filter1d


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
    travel_yaw: float = 0.0  # direction the clip travels, relative to where it faces (radians
    # about +y): 0 walking forward, π/2 side-stepping left, π walking back


JUMP_ALPHA = 2.5


def hermite_arc(start: np.ndarray, end: np.ndarray, w: np.ndarray, alpha: float = JUMP_ALPHA,
                apex: float | None = None) -> np.ndarray:
    """Points (m, 3) at ``w`` ∈ [0, 1] of the beautified jump from ``start`` to ``end``
    (§5.2): a cubic Hermite curve whose tangents are vertical — up at take-off, down at
    landing — of length ``α·‖end − start‖``. With ``apex`` (metres above the take-off), α is
    chosen so the curve's middle is that high: ``α = 4·apex / ‖end − start‖``."""
    length = float(np.linalg.norm(end - start))
    if apex is not None:
        alpha = 4.0 * apex / max(length, 1e-6)
    up = np.array([0.0, 1.0, 0.0]) * alpha * length
    w = np.asarray(w, dtype=float)[:, None]
    h00, h10 = 2 * w**3 - 3 * w**2 + 1, w**3 - 2 * w**2 + w
    h01, h11 = -2 * w**3 + 3 * w**2, w**3 - w**2
    return h00 * start + h10 * up + h01 * end + h11 * (-up)


def world_path(t: np.ndarray, p: np.ndarray, spans: list[Span], scale: float,
               terrain=None, jump_arc: str = "clip", origin=None, facing: float | None = None
               ) -> tuple[np.ndarray, np.ndarray]:
    """Ground path (n, 3) of the root — on ``terrain`` (flat y = 0 when None), cast along
    gravity — and heading (n,) in radians about +y (0 faces +z). The doodle point
    ``origin`` (default: the track's first point) lands on the world origin: give every
    track of a scene the same one so the characters keep their places relative to each other.
    ``facing``: the heading (rad) a character that never travels keeps — the figurine's own
    (default 0, facing +z); one that travels faces its first travel direction from the start.

    ``jump_arc``: ``"clip"`` leaves a jump's height to its clip; ``"hermite"`` adds the
    beautified arc (α = 2.5) above the ground during the execution stage; ``"apex"`` the
    arc whose apex keeps the doodle's own (scaled) height above take-off."""
    ground = (p - (p[0] if origin is None else np.asarray(origin, dtype=float))) * scale
    ground[:, 1] = 0.0
    path = ground.copy()
    offset = np.zeros(3)
    for s in spans:
        seg = slice(s.i0, s.i1)
        path[seg] = ground[seg] + offset
        if s.in_place:  # the next segment starts where this one stands (no step between samples)
            path[seg] = path[s.i0]
            offset = path[s.i0] - ground[min(s.i1, len(ground) - 1)]
        elif s.jumping:
            path[seg] = _retimed_jump(t[seg], path[seg], s)
    heading = _heading(t, path, spans, facing or 0.0)
    if terrain is not None:
        path[:, 1] = terrain.height(path[:, [0, 2]])
        for s in spans:  # in the air the body does not follow the ground's bumps: from take-off to landing height
            if s.jumping and s.i1 - s.i0 > 1:
                u = (t[s.i0:s.i1] - t[s.i0]) / max(t[s.i1 - 1] - t[s.i0], 1e-9)
                w = np.clip((u - s.execution[0]) / max(s.execution[1] - s.execution[0], 1e-6), 0.0, 1.0)
                path[s.i0:s.i1, 1] = path[s.i0, 1] + w * (path[s.i1 - 1, 1] - path[s.i0, 1])
    if jump_arc not in ("clip", "hermite", "apex"):
        raise ValueError(f"jump_arc must be clip, hermite or apex, not {jump_arc!r}")
    if jump_arc != "clip":
        for s in spans:
            if s.jumping and s.i1 - s.i0 > 2:
                path[s.i0:s.i1, 1] += _arc_lift(t[s.i0:s.i1], path[s.i0:s.i1], p[s.i0:s.i1], s, scale, jump_arc)
    return path, heading


def _arc_lift(t: np.ndarray, points: np.ndarray, doodle: np.ndarray, span: Span, scale: float, mode: str) -> np.ndarray:
    """Height of the beautified arc above the straight ground line, over the execution."""
    u = (t - t[0]) / max(t[-1] - t[0], 1e-9)
    a, b = span.execution
    w = np.clip((u - a) / max(b - a, 1e-6), 0.0, 1.0)
    start, end = points[0].copy(), points[-1].copy()
    start[1] = end[1] = 0.0
    apex = None
    if mode == "apex":
        apex = max(float((doodle[:, 1] - doodle[0, 1]).max()) * scale, 0.0)
    arc = hermite_arc(start, end, w, apex=apex)
    return arc[:, 1]


def _retimed_jump(t: np.ndarray, points: np.ndarray, span: Span) -> np.ndarray:
    """Travel only during execution (the flight), from where the segment takes off to
    where it lands: in a straight line at an even speed, as a body in the air moves,
    whatever the hand's own pace and wobble on the way."""
    if len(t) < 2:
        return points
    u = (t - t[0]) / max(t[-1] - t[0], 1e-9)
    a, b = span.execution
    w = np.clip((u - a) / max(b - a, 1e-6), 0.0, 1.0)
    return points[0] + np.outer(w, points[-1] - points[0])


TURNING_SPEED = 0.3  # m/s: slower drift of the path (a hand at rest) does not turn the character


def _heading(t: np.ndarray, path: np.ndarray, spans: list[Span], still: float = 0.0) -> np.ndarray:
    n = len(path)
    if n < 2:
        return np.zeros(n)
    step = np.gradient(gaussian_filter1d(path, 3.0, axis=0, mode="nearest"), t, axis=0)
    speed = np.hypot(step[:, 0], step[:, 2])
    moving = speed > TURNING_SPEED
    yaw = np.arctan2(step[:, 0], step[:, 2])
    for s in spans:  # in place the heading is held; travelling, the clip's own direction counts
        if s.in_place:
            moving[s.i0:s.i1] = False
        yaw[s.i0:s.i1] -= s.travel_yaw
    heading = np.zeros(n)
    current = float(yaw[np.flatnonzero(moving)[0]]) if moving.any() else still
    for i in range(n):
        if moving[i]:
            current = float(yaw[i])
        heading[i] = current
    return np.unwrap(heading)
