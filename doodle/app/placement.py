"""Interaction placement with implicit walks and temporal offsets (thesis §6.2.2, first
method, eq. 6.1–6.3).

An interaction may say where role 1 stands relative to role 0 when it begins — in the
thesis, read from a stored two-character clip (the vector between the characters' centres
and their relative orientation at its first frame); here the manifest's ``placement = [x, z,
turn]``: role 1's root ``x`` metres to role 0's right and ``z`` metres in front of it, its
heading turned ``turn`` degrees from role 0's (180: facing each other). Before the
interaction, role 1 walks there (eq. 6.2–6.3: ``d = P¹ + I¹I²``, ``v = d − P²``) and turns to
that heading while every other character waits; it plays its role there; afterwards it
walks back to where the doodle has it, turned back, while the others wait again. The walks
take time the doodle did not have, so — the thesis's choice of not shortening the
interaction — that time is *inserted* into every track (the temporal offset ``t_off``
grows by both walks), keeping all characters in step. The walks are written into the
doodle, so recognition reads them as the implicit Walks they are.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from doodle.core import quat
from doodle.core.model import Doodle, Track
from doodle.core.profiles import min_jerk
from grammar.contexter import InteractionSegment

WALK_SPEED = 1.0  # m/s in character space: an unhurried walk
MIN_WALK_S = 0.5  # s: the shortest inserted walk
MIN_SHIFT = 0.05  # m in character space: closer than this, no walk is needed
UP = np.array([0.0, 1.0, 0.0])


def interaction_pairs(recognised: dict) -> list[tuple[str, object, str, object]]:
    """(track of role 0, its segment, track of role 1, its segment) of each recognised
    two-character interaction."""
    roles = [(tr, s) for tr, (_, segs) in recognised.items() for s in segs if isinstance(s, InteractionSegment)]
    pairs = []
    for ta, a in (r for r in roles if r[1].role == 0):
        for tb, b in (r for r in roles if r[1].role == 1):
            if tb != ta and b.interaction == a.interaction and b.start < a.end and a.start < b.end:
                pairs.append((ta, a, tb, b))
                break
    return pairs


def place(doodle: Doodle, recognised: dict, scale: float, placements: dict) -> Doodle:
    """The doodle with each recognised two-character interaction that has a placement
    (``{interaction: (x, z, turn)}``) played at it: walks there and back inserted, time
    inserted into every track. ``recognised`` is :func:`grammar.recognizer.recognize`'s
    result; ``scale`` character metres per doodle metre. Interactions are placed from the
    last to the first, so the earlier ones' samples do not move."""

    pairs = [p for p in interaction_pairs(recognised) if p[1].interaction in placements]
    for ta, a, tb, b in sorted(pairs, key=lambda p: -doodle.track(p[2]).t[min(p[3].start, len(doodle.t) - 1)]):
        doodle = _place_one(doodle, ta, a, tb, b, scale, placements[a.interaction])
    return doodle


def _place_one(doodle: Doodle, ta: str, a, tb: str, b, scale: float, placement) -> Doodle:
    from grammar.constraints import ground_front

    A, B = doodle.track(ta), doodle.track(tb)
    i0 = min(min(a.start, b.start), len(B.t) - 1)
    i1 = min(max(a.end, b.end), len(B.t)) - 1
    front = ground_front(A.q[i0])
    if not np.any(front):  # a figurine pointing up: face the other character
        front = (B.p[i0] - A.p[i0]) * [1.0, 0.0, 1.0]
        front = front / max(np.linalg.norm(front), 1e-9)
    right = np.cross(front, UP)
    x, z, turn = placement
    target = A.p[i0] + (x * right + z * front) / scale
    target[1] = B.p[i0, 1]
    shift = target - B.p[i0]
    yaw_now = np.arctan2(*ground_front(B.q[i0])[[0, 2]])
    yaw_want = np.arctan2(front[0], front[2]) + np.radians(turn)
    twist = quat.exp(UP * _wrap(yaw_want - yaw_now))
    if np.linalg.norm(shift) * scale < MIN_SHIFT and abs(_wrap(yaw_want - yaw_now)) < np.radians(10):
        return doodle
    seconds = max(MIN_WALK_S, float(np.linalg.norm(shift)) * scale / WALK_SPEED)
    n = max(2, int(round(seconds * doodle.rate)))
    # role 1 during the interaction: moved and turned; then walks in before and out after
    q_role = quat.compose(twist, B.q[i0:i1 + 1])
    moved = replace(B, p=np.concatenate([B.p[:i0], B.p[i0:i1 + 1] + shift, B.p[i1 + 1:]]),
                    q=np.concatenate([B.q[:i0], q_role, B.q[i1 + 1:]]))
    u = min_jerk(np.linspace(0.0, 1.0, n))
    heading_in = _facing(B.q[i0], shift)  # walking forwards, turned to where it goes
    heading_out = _facing(q_role[-1], -shift)
    walk_in = (B.p[i0] + u[:, None] * shift, _turns(B.q[i0], heading_in, q_role[0], n))
    walk_out = (B.p[i1] + shift - u[:, None] * shift, _turns(q_role[-1], heading_out, B.q[i1], n))
    tracks = []
    for tr in doodle.tracks:
        src = moved if tr.name == tb else tr
        before = walk_in if tr.name == tb else _hold(src, i0, n)
        after = walk_out if tr.name == tb else _hold(src, i1, n)
        tracks.append(_insert(_insert(src, i1 + 1, after, doodle.rate), i0, before, doodle.rate))
    return replace(doodle, tracks=tuple(tracks))


def _insert(track: Track, at: int, poses, rate: float) -> Track:
    """``poses`` (positions, quaternions) inserted before sample ``at``, the later samples
    moved later by as much time."""
    p, q = poses
    n = len(p)
    t0 = track.t[at - 1] if at > 0 else track.t[0] - 1.0 / rate
    t_new = t0 + np.arange(1, n + 1) / rate
    later = track.t[at:] + n / rate
    return replace(track, t=np.concatenate([track.t[:at], t_new, later]),
                   p=np.concatenate([track.p[:at], p, track.p[at:]]),
                   q=np.concatenate([track.q[:at], q, track.q[at:]]),
                   valid=np.concatenate([track.valid[:at], np.ones(n, dtype=bool), track.valid[at:]]))


def _hold(track: Track, i: int, n: int):
    return np.repeat(track.p[i][None], n, axis=0), np.repeat(track.q[i][None], n, axis=0)


def _facing(q, direction) -> np.ndarray:
    """q turned about the vertical so its ground front points along ``direction``."""
    from grammar.constraints import ground_front

    f, d = ground_front(q), np.asarray(direction, dtype=float) * [1.0, 0.0, 1.0]
    if not np.any(f) or np.linalg.norm(d) < 1e-9:
        return np.asarray(q, dtype=float)
    angle = np.arctan2(d[0], d[2]) - np.arctan2(f[0], f[2])
    return quat.compose(quat.exp(UP * _wrap(angle)), q)


def _turns(q_from, q_walk, q_to, n: int) -> np.ndarray:
    """Orientations over a walk of n samples: turn to the walking heading over its first
    fifth, walk, turn to the final heading over its last fifth (the thesis's π-rotated way
    back, §6.2.2)."""
    k = max(1, n // 5)
    u = np.clip(min_jerk(np.linspace(0.0, 1.0, k)), 0.0, 1.0)
    return np.concatenate([quat.slerp(q_from, q_walk, u), np.repeat(np.asarray(q_walk)[None], n - 2 * k, axis=0),
                           quat.slerp(q_walk, q_to, u)])


def _wrap(angle: float) -> float:
    return float((angle + np.pi) % (2 * np.pi) - np.pi)


def stand_in_front(track: Track, at: int, where, heading: float, here, facing: float, distance: float,
                   scale: float, still: bool, walk_s: float) -> Track:
    """Role 1's track moved so that at sample ``at`` its root stands ``distance`` metres in
    front of role 0 — at ``where`` (world metres) heading ``heading`` (radians about +y, 0
    facing +z) then — turned to face it. ``here`` and ``facing`` are where role 1 stands and
    how it is turned at ``at`` (world), after whatever it did before. A character that has
    not travelled before (``still``) is moved and turned from its first sample, the whole
    track turned rigidly about its place (its own gestures read as before); one that has
    steps there over the ``walk_s`` before ``at`` (an implicit walk), keeping its turn."""
    front = np.array([np.sin(heading), 0.0, np.cos(heading)])
    target = np.asarray(where, dtype=float) * [1.0, 0.0, 1.0] + distance * front
    shift = (target - np.asarray(here, dtype=float) * [1.0, 0.0, 1.0]) / scale
    p, q = track.p.copy(), track.q.copy()
    if still:
        turn = _wrap(heading + np.pi - facing)
        yaw = quat.exp(UP * turn)
        pivot = p[at] * [1.0, 0.0, 1.0]
        p = quat.rotate(yaw, p - pivot) + pivot + shift
        q = quat.compose(yaw, q)
        return replace(track, p=p, q=q)
    start = float(track.t[at]) - walk_s
    u = np.clip((track.t - start) / max(walk_s, 1e-9), 0.0, 1.0)
    return replace(track, p=p + min_jerk(u)[:, None] * shift)
