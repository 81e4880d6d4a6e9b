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
   point during follow-through and transition (§5.2 "Retiming Jump trajectory"); it
   gathers its speed over the ground during the push-off before the flight and sheds it
   during the landing after (:func:`travel_share`), never starting or stopping in the air;
   the next segment starts where it landed (as in step 3);
5. the heading follows the path's direction while the character travels — turned by the
   clip's own direction of travel, so a side-step moves sideways and a walk back backwards
   — and is held while it acts in place;
6. a walking character travels no faster than its span's ``most_speed`` (:func:`limited`):
   where the doodle runs ahead faster than any walk cycle can be played, the character keeps
   to the same path but falls behind, catches up where the doodle slows, and the offset
   takes whatever it is still behind at the span's end (as in step 3); a jump's flight
   carries it no faster than :data:`JUMP_SPEED_MOST`, the way the doodle jumps.

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
    most_speed: float = np.inf  # m/s: the fastest the character travels here (:func:`limited`)
    ramps: tuple[float, float] = (0.0, 0.0)  # a jump: how long (fractions of the span) before
    # its flight it gathers its speed over the ground (the push-off) and after it sheds it
    # (the landing) — :func:`travel_share`


JUMP_ALPHA = 2.5
# How fast a walking character may travel (step 6). Faster than TRAVEL_MOST the built-in Walk,
# played 3.4 times its own pace, swings a foot past the animation check's joint limit (15 m/s):
# the main example compiled at larger scales passes with its walks at 4.0 m/s and pops at 4.7.
# A clip that travels faster at its own pace (a run) may go up to OWN_PACE_MOST times that.
TRAVEL_MOST = 4.0  # m/s
OWN_PACE_MOST = 2.0
# How fast a jump carries the character over the ground in its flight: the built-in Jump in
# the main example (a 0.5 s flight) passes the check at 9.4 m/s and pops at 12.6 (the flight's
# root speed taken off its joints' limit); a long jumper takes off at 9-10 m/s.
JUMP_SPEED_MOST = 9.0  # m/s


def travel_most(own_speed: float) -> float:
    """The fastest (m/s) a character travels playing a clip that travels at ``own_speed``
    (m/s) at its own pace."""
    return max(TRAVEL_MOST, OWN_PACE_MOST * own_speed)


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
            # the rest starts where it landed — short of the doodle, or where the doodle came
            # down a sample before the next segment starts (no step between samples: the hand
            # moving on, that one sample's step was a one-frame jolt of the root)
            offset = path[s.i1 - 1] - ground[min(s.i1, len(ground) - 1)]
        else:
            laid = path[seg]
            held = limited(t[seg], laid, s.most_speed)
            if held is not laid:  # fell behind: the rest starts from where it got to (no step between samples)
                path[seg] = held
                offset = held[-1] - ground[min(s.i1, len(ground) - 1)]
    heading = _heading(t, path, spans, facing or 0.0)
    if terrain is not None:
        path[:, 1] = terrain.height(path[:, [0, 2]])
        for s in spans:  # in the air the body does not follow the ground's bumps: from take-off to landing height
            if s.jumping and s.i1 - s.i0 > 1:
                w = travel_share((t[s.i0:s.i1] - t[s.i0]) / max(t[s.i1 - 1] - t[s.i0], 1e-9), s)
                path[s.i0:s.i1, 1] = path[s.i0, 1] + w * (path[s.i1 - 1, 1] - path[s.i0, 1])
    if jump_arc not in ("clip", "hermite", "apex"):
        raise ValueError(f"jump_arc must be clip, hermite or apex, not {jump_arc!r}")
    if jump_arc != "clip":
        for s in spans:
            if s.jumping and s.i1 - s.i0 > 2:
                path[s.i0:s.i1, 1] += _arc_lift(t[s.i0:s.i1], path[s.i0:s.i1], p[s.i0:s.i1], s, scale, jump_arc)
    return path, heading


def limited(t: np.ndarray, path: np.ndarray, most: float) -> np.ndarray:
    """A travelling span's ground path (n, 3) followed no faster than ``most`` m/s along the
    ground: the same way, the character falling behind where the doodle runs ahead faster than
    that, and catching up (never passing it) where the doodle slows. ``path`` itself (the same
    object) where it is never too fast.

    The distance covered ``u`` keeps to the doodle's ``s`` where it can: ``u_i = min(s_i,
    u_{i-1} + most·Δt_i)``, a running minimum once the distance ``most`` allows is taken off."""
    n = len(path)
    if n < 2 or not np.isfinite(most):
        return path
    step = np.hypot(*np.diff(path[:, [0, 2]], axis=0).T)
    allowed = most * np.maximum(np.diff(t), 0.0)
    if np.all(step <= allowed * (1 + 1e-9)):
        return path
    s = np.concatenate([[0.0], np.cumsum(step)])
    c = np.concatenate([[0.0], np.cumsum(allowed)])
    u = c + np.minimum.accumulate(s - c)
    k = np.clip(np.searchsorted(s, u, side="right") - 1, 0, n - 2)  # the doodle step each distance falls in
    w = np.clip((u - s[k]) / np.maximum(step[k], 1e-12), 0.0, 1.0)
    out = path[k] + w[:, None] * (path[k + 1] - path[k])
    out[0] = path[0]
    return out


BEHIND_SAID = 0.1  # m: falling less than this far behind the doodle is not worth a word


def overspeed(t: np.ndarray, p: np.ndarray, spans: list[Span], scale: float) -> list[tuple[Span, float, float, float]]:
    """The spans of the doodle ``(t, p)`` (``scale`` world metres per doodle metre) that the
    character cannot keep to, ending at least :data:`BEHIND_SAID` behind or short, each as
    ``(span, asked, most, behind)``: a walk faster than its span's ``most_speed``
    (:func:`limited`) — the fastest the doodle moves there and that most (m/s along the
    ground, from one sample to the next) —, a jump farther than its flight allows — the
    distance the doodle jumps and :func:`jump_reach` (m) —; and how far behind or short the
    character ends (m)."""
    out = []
    for s in spans:
        if s.in_place or s.i1 - s.i0 < 2:
            continue
        seg = slice(s.i0, s.i1)
        ground = (p[seg] - p[s.i0]) * scale
        ground[:, 1] = 0.0
        if s.jumping:
            far, most = float(np.hypot(*(ground[-1] - ground[0])[[0, 2]])), jump_reach(t[seg], s)
            if far - most >= BEHIND_SAID:
                out.append((s, far, most, far - most))
            continue
        held = limited(t[seg], ground, s.most_speed)
        behind = float(np.hypot(*(held[-1] - ground[-1])[[0, 2]]))
        if held is ground or behind < BEHIND_SAID:
            continue
        fastest = float(np.max(np.hypot(*np.diff(ground[:, [0, 2]], axis=0).T) / np.maximum(np.diff(t[seg]), 1e-9)))
        out.append((s, fastest, s.most_speed, behind))
    return out


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
    """Travel from where the segment takes off to where it lands, over the flight and the
    push-off and landing around it (:func:`travel_share`): in a straight line, at an even
    speed in the air, as a body in the air moves, whatever the hand's own pace and wobble on
    the way — and no farther than :func:`jump_reach` over the ground."""
    if len(t) < 2:
        return points
    w = travel_share((t - t[0]) / max(t[-1] - t[0], 1e-9), span)
    leap = points[-1] - points[0]
    far, most = float(np.hypot(leap[0], leap[2])), jump_reach(t, span)
    if far > most:
        leap = leap * np.array([most / far, 1.0, most / far])
    return points[0] + np.outer(w, leap)


def _ramps(span: Span) -> tuple[float, float, float, float]:
    """The jump's flight ``a, b`` and its push-off and landing ``r0, r1`` (fractions of the
    span), the ramps kept inside the span."""
    a, b = span.execution
    b = max(b, a)
    return a, b, float(np.clip(span.ramps[0], 0.0, a)), float(np.clip(span.ramps[1], 0.0, 1.0 - b))


def travel_share(u: np.ndarray, span: Span) -> np.ndarray:
    """The share (0 → 1) of a jump's travel over the ground covered at each fraction ``u`` of
    its span: at an even speed through the flight (``span.execution``: a body in the air
    keeps its horizontal speed), that speed gathered at an even rate over the push-off before
    it and shed over the landing after it (``span.ramps``: the feet push the body along, then
    brake it) — so the character neither starts nor stops moving while in the air, nor in one
    frame at touch-down. With no ramps, an even speed over the flight alone."""
    a, b, r0, r1 = _ramps(span)
    x = np.clip(np.asarray(u, dtype=float), a - r0, b + r1)
    covered = np.where(x < a, (x - a + r0) ** 2 / (2 * max(r0, 1e-12)), 0.5 * r0 + np.minimum(x, b) - a)
    after = np.maximum(x - b, 0.0)
    covered = covered + np.where(after > 0, after - after**2 / (2 * max(r1, 1e-12)), 0.0)
    return np.clip(covered / max(b - a + 0.5 * (r0 + r1), 1e-6), 0.0, 1.0)


def jump_reach(t: np.ndarray, span: Span) -> float:
    """How far (m) a jumping span — its flight at :data:`JUMP_SPEED_MOST`, over the samples'
    times ``t``, and that speed gathered and shed over its push-off and landing
    (:func:`travel_share`) — carries the character at most."""
    a, b, r0, r1 = _ramps(span)
    return JUMP_SPEED_MOST * max(float(t[-1] - t[0]) * (b - a + 0.5 * (r0 + r1)), 0.0)


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
