"""Animation sequencing (thesis §5.3): one clip per segment, retimed, placed on the path,
joined by blended transitions, into one motion on one timeline.

* A non-cyclic clip is retimed to last as long as its segment (``t' = t0 + T_P/T_A (t − t0)``).
* A cyclic clip (Walk) plays as many cycles as the path's length over the clip's cycle
  length, the cycles retimed to fill the segment, so the steps match the distance; the
  last cycle is a partial one (the thesis scales it down; here it is cut).
* The root: horizontal position from the transferred path, height from the clip, yaw from
  the path's heading composed with the clip's own root rotation.
* Transitions: a non-cyclic clip is entered and left at the transition points chosen on
  frame-distance maps by the stage policies (§5.3.1, :mod:`retarget.transitions`), so it
  plays only that range; neighbouring clips are then cross-faded over ``blend`` seconds
  around each boundary (rotations by normalised interpolation, root linearly, smoothstep
  weights).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doodle.core import quat
from doodle.core.filters import gaussian_filter1d
from retarget.analysis import pelvis_of
from retarget.qa import Limits, planted_moves
from retarget.skeleton import Motion, Skeleton, body_points, end_site_positions, forward_kinematics, per_motion
from retarget.trajectory import Span


@dataclass(frozen=True, eq=False)
class Placed:
    """A clip assigned to a span: ``cycles`` > 0 for cyclic playback; a travelling cyclic
    clip is driven by distance instead (``progress``: arc length along the path at the
    output times, ``times``), so its planted foot stays planted."""

    span: Span
    motion: Motion
    pelvis: int
    cycles: float = 0.0
    times: np.ndarray | None = None
    progress: np.ndarray | None = None
    travels: bool = False  # the clip moves the character (walks, jumps); else it acts on the spot
    clip_in: float = 0.0  # clip time (s) played at the segment's start (a transition point)
    clip_out: float | None = None  # clip time (s) played at its end (None: the clip's end)
    gesture: tuple | None = None  # (times, fraction): gesture-based retiming, §5.3.3
    contacts: np.ndarray | None = None  # (clip frames, feet) bool: where the clip's feet stand
    rolls: np.ndarray | None = None  # (clip frames, feet) bool: a jump's feet on their toes (timing.push_off_rolls)
    pace: tuple | None = None  # (fraction of the span, clip time): a one-shot's retiming (:func:`paced`)
    phase: float = 0.0  # m of the clip's travel a distance-driven cycle starts at (:func:`entry_phase`)

    @property
    def fitted(self) -> bool:
        """A one-shot clip played to fit its span (:func:`paced`): not a cycle, not driven
        by the distance walked, not following the hand's own timing."""
        return self.cycles == 0 and self.progress is None and self.gesture is None


def travel_curve(motion: Motion, pelvis: int) -> np.ndarray:
    """Distance (m) the pelvis has travelled at each frame of a cyclic clip, along its net
    direction of travel, made non-decreasing (worked out once per clip; read-only)."""
    return _travel_curve(motion, int(pelvis))


@per_motion
def _travel_curve(motion: Motion, pelvis: int) -> np.ndarray:
    xz = forward_kinematics(motion)[0][:, pelvis][:, [0, 2]]
    net = xz[-1] - xz[0]
    norm = np.linalg.norm(net)
    if norm < 1e-6:
        return np.zeros(motion.frames)
    return np.maximum.accumulate((xz - xz[0]) @ (net / norm))


@per_motion
def pelvis_travel(motion: Motion, pelvis: int) -> np.ndarray:
    """(2,) the pelvis's travel over the ground (x, z) from a clip's first frame to its last
    (worked out once per clip; read-only)."""
    hips = forward_kinematics(motion)[0][:, pelvis][:, [0, 2]]
    return hips[-1] - hips[0]


def _sample(motion: Motion, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Translations and rotations at clip times ``u`` (seconds), by interpolation."""
    f = np.clip(u / motion.frame_time, 0, motion.frames - 1)
    k = np.minimum(np.floor(f).astype(int), max(motion.frames - 2, 0))
    w = (f - k)[:, None, None]
    k1 = np.minimum(k + 1, motion.frames - 1)
    trans = motion.translations[k] * (1 - w) + motion.translations[k1] * w
    rots = _nlerp(motion.rotations[k], motion.rotations[k1], w)
    return trans, rots


def _nlerp(a: np.ndarray, b: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Normalised linear interpolation of quaternions, shortest way (``w`` broadcasts)."""
    dot = np.sum(a * b, axis=-1, keepdims=True)
    b = np.where(dot < 0, -b, b)
    q = a * (1 - w) + b * w
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def clip_time(placed: Placed, t: np.ndarray) -> np.ndarray:
    """Clip time for doodle times ``t`` inside (or clamped to) the span."""
    s, m = placed.span, placed.motion
    u = np.clip((t - s.t0) / max(s.t1 - s.t0, 1e-9), 0.0, 1.0)
    if placed.gesture is not None and placed.cycles == 0:
        u = np.interp(t, *placed.gesture)
    if placed.progress is not None:
        curve = travel_curve(m, placed.pelvis)
        length = curve[-1]
        if length > 1e-6:
            s_t = np.interp(t, placed.times, placed.progress)
            rem = np.mod(s_t + placed.phase, length)
            clip_times = np.arange(m.frames) * m.frame_time
            return np.interp(rem, curve, clip_times)
    if placed.cycles > 0:
        cycle = (m.frames - 1) * m.frame_time
        phase = u * placed.cycles
        return np.where(u >= 1.0, cycle, (phase % 1.0) * cycle)
    if placed.pace is not None:
        return np.interp(u, *placed.pace)
    end = (m.frames - 1) * m.frame_time if placed.clip_out is None else placed.clip_out
    return placed.clip_in + u * (end - placed.clip_in)


def feet_around_pelvis(motion: Motion, pelvis: int, feet) -> np.ndarray:
    """(F, feet, 2): each foot's horizontal place relative to the pelvis, in the pelvis's own
    heading (so clips facing different ways compare); worked out once per clip, read-only."""
    return _feet_around_pelvis(motion, int(pelvis), tuple(int(f) for f in feet))


@per_motion
def _feet_around_pelvis(motion: Motion, pelvis: int, feet: tuple) -> np.ndarray:
    positions, rotations = forward_kinematics(motion)
    front = quat.rotate(rotations[:, pelvis], np.tile([0.0, 0.0, 1.0], (motion.frames, 1)))
    yaw = np.arctan2(front[:, 0], front[:, 2])
    rel = positions[:, list(feet)][:, :, [0, 2]] - positions[:, [pelvis]][:, :, [0, 2]]
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]
    return np.stack([c * rel[..., 0] - s * rel[..., 1], s * rel[..., 0] + c * rel[..., 1]], axis=-1)


def entry_phase(before: Motion, before_pelvis: int, before_feet: list[int], at: float, cycle: Motion,
                pelvis: int, feet: list[int]) -> float:
    """Where (m of its travel) a distance-driven cycle is entered after a clip that plays
    its time ``at`` last: at the cycle's frame whose feet stand most like the other clip's
    (feet together after a stand: a side step opens with its lead foot, a walk from
    mid-swing), so the blend between them does not cross or drag the feet."""
    frame = int(np.clip(round(at / before.frame_time), 0, before.frames - 1))
    last = feet_around_pelvis(before.slice(frame, frame + 1), before_pelvis, before_feet)[0]
    stances = feet_around_pelvis(cycle, pelvis, feet)
    best = int(np.argmin(np.linalg.norm(stances - last, axis=2).sum(axis=1)))
    return float(travel_curve(cycle, pelvis)[best])


STRIDE_RANGE = 1.4  # a cycle's strides are at most this much longer (or shorter) than the clip's


def stride_scale(motion: Motion, pelvis: int, speed: float) -> float:
    """How much longer than the clip's a travelling cycle's strides are at ``speed`` (m/s):
    people walking faster lengthen their strides as well as quickening them, about as the
    square root of the speed (so half the change is stride, half cadence), within
    :data:`STRIDE_RANGE`. The feet, pinned where they land, take the longer strides."""
    natural = travel_curve(motion, pelvis)[-1] / max(motion.duration, 1e-9)
    if natural < 1e-6 or speed <= 0:
        return 1.0
    return float(np.clip(np.sqrt(speed / natural), 1 / STRIDE_RANGE, STRIDE_RANGE))


FASTEST = 11.0  # m/s: a retimed clip's joints move no faster (real motion capture: ≤ 12.2 m/s)
QUICKEST = 2.0  # … and no part of it plays more than this much faster than the clip's own pace: a slow
# part is slow because of the body's weight too (standing up from a landing crouch), not only a hold
SLOWED_EASE = 0.25  # s of clip time over which a slowed clip's rate eases into its flight's or raised foot's own pace
RISE_MARGIN = 0.9  # both feet flat on the floor, the pelvis rises no faster than this share of the check's limit
BLEND = 0.2  # s: neighbouring clips are cross-faded over this, centred on their boundary …
BLEND_SPEED = 0.5 * FASTEST  # m/s: … or longer, so the cross-fade alone swings no point faster (the
# other half left to the clips' own motion) …
BLEND_MOST = 0.6  # s: … up to this
BLEND_STEP = 0.05  # s: a cross-fade lengthened for a rise (:func:`rising_blends`) tries lengths this far apart


def rise_least(flat: np.ndarray, pelvis_y: np.ndarray, frame_time: float) -> np.ndarray:
    """Per frame interval, the least time it may take so that, where both feet stand flat on
    the floor (``flat``: (F, feet), ``retarget.qa.planted_moves``), the pelvis (heights
    ``pelvis_y``) rises no faster than :data:`RISE_MARGIN` × the animation check's limit — or
    than over ``frame_time``, the interval's own time, if it rose faster (a jump's push-off):
    played faster, a body getting up out of a crouch with its feet down is jerked up, which no
    person does (``retarget.qa``, pops)."""
    if len(pelvis_y) < 2 or flat.ndim < 2 or flat.shape[1] < 2:
        return np.zeros(max(len(pelvis_y) - 1, 0))
    both = flat.all(axis=1)
    rise = np.maximum(np.diff(pelvis_y), 0.0)
    least = np.minimum(frame_time, rise / (RISE_MARGIN * Limits().rise))
    return np.where(both[1:] & both[:-1], least, 0.0)


def _limits(motion: Motion, clip_in: float, clip_out: float | None, limit: float, natural: tuple | None = None,
            quickest: float = QUICKEST):
    """The played range's clip-time knots, their steps and the shortest each step may last
    so that no joint or end site goes faster than ``limit`` (or than in the clip itself) and
    no step plays more than ``quickest`` times faster than in the clip."""
    end = (motion.frames - 1) * motion.frame_time if clip_out is None else clip_out
    f0 = int(np.floor(clip_in / motion.frame_time + 1e-9))
    f1 = int(np.ceil(end / motion.frame_time - 1e-9))
    knots = np.clip(np.arange(f0, f1 + 1) * motion.frame_time, clip_in, end)
    if len(knots) < 3:
        return knots, np.diff(knots), np.zeros(max(len(knots) - 1, 0))
    step = np.diff(knots)
    speed = _frame_speeds(motion)[f0:f1]
    least = step * np.clip(speed / limit, 1.0 / quickest, 1.0)  # never slower than the clip's own pace
    least = np.maximum(least, step * _rise_share(motion)[f0:f1])  # nor jerked up out of a crouch
    if natural is not None:  # a flight lasts as long as it does
        inside = _within(knots, natural)
        least[inside] = step[inside]
    return knots, step, least


def _within(knots: np.ndarray, interval: tuple) -> np.ndarray:
    """Per step between ``knots`` (clip times), whether it overlaps ``interval`` (clip times)."""
    return (knots[1:] > interval[0] + 1e-9) & (knots[:-1] < interval[1] - 1e-9)


@per_motion
def _frame_speeds(motion: Motion) -> np.ndarray:
    """(F − 1,) the fastest joint or end site (m/s) between each two frames of a clip (read
    many times while a clip is given room and paced: computed once per clip)."""
    return np.linalg.norm(np.diff(body_points(motion), axis=0), axis=2).max(axis=1) / motion.frame_time


@per_motion
def _rise_share(motion: Motion) -> np.ndarray:
    """(F − 1,) the least share of its own time each frame interval of a clip may be played
    in (:func:`rise_least`: the pelvis getting up with both feet flat; 0 elsewhere)."""
    world = forward_kinematics(motion)
    flat, _ = planted_moves(motion, world)
    return rise_least(flat, world[0][:, pelvis_of(motion.skeleton), 1], motion.frame_time) / motion.frame_time


def shortest(motion: Motion, clip_in: float = 0.0, clip_out: float | None = None, limit: float = FASTEST,
             natural: tuple | None = None) -> float:
    """The least time (s) a one-shot clip's range can be played in without any joint going
    faster than ``limit`` (its slow parts squeezed to nothing) and with the clip times
    ``natural`` (a jump's flight) played at their own pace."""
    return float(_limits(motion, clip_in, clip_out, limit, natural)[2].sum())


def paced(motion: Motion, clip_in: float, clip_out: float | None, duration: float,
          limit: float = FASTEST, natural: tuple | None = None,
          raised: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """A one-shot clip's range retimed to last ``duration`` seconds (§5.3: ``T_P/T_A``)
    without any joint going faster than ``limit``: where a uniform squeeze would, the slow
    parts of the clip (holds, wind-ups) are squeezed more and the fast ones less. Returns
    knots (fraction of the span, clip time) for :func:`clip_time`; uniform when it can be
    (or when even that cannot keep to the limit: give the clip room, :func:`shortest`).
    ``natural``: clip times (a jump's flight) played at their own pace where they can be. No
    part plays more than :data:`QUICKEST` times its own pace unless the clip cannot otherwise
    fit its span (no room was left around it): then only the joints' ``limit`` holds, and
    if even that leaves no time for the flight at its own pace, the flight plays quicker too
    (a hop performed in 0.6 s: squeezed evenly, the take-off swung the arms at 18 m/s).
    ``raised``: per clip frame, a foot off the ground (the clip's contacts): slowed to fill a
    long span, the clip plays those frames at its own pace too, and its stances take the
    time (:func:`_slowed_around`) — unless they would play slower than half their pace (the
    mirror of :data:`QUICKEST`): then all but the flight is slowed."""
    end = (motion.frames - 1) * motion.frame_time if clip_out is None else clip_out
    knots, step, least = _limits(motion, clip_in, clip_out, limit, natural)
    if least.sum() >= duration:
        knots, step, least = _limits(motion, clip_in, clip_out, limit, natural, quickest=np.inf)
    if least.sum() >= duration and natural is not None:  # a jump performed quicker than its flight takes:
        knots, step, least = _limits(motion, clip_in, clip_out, limit, None, quickest=np.inf)  # a quicker flight
    if len(knots) < 3 or duration <= 0:
        return np.array([0.0, 1.0]), np.array([clip_in, end])
    if duration > end - clip_in and (natural is not None or raised is not None):  # slowed: feet up at own pace
        flight = _within(knots, natural) if natural is not None else np.zeros(len(step), dtype=bool)
        up = flight.copy()
        if raised is not None and len(raised):
            f = np.clip(np.rint(knots / motion.frame_time).astype(int), 0, len(raised) - 1)
            up |= raised[f[:-1]] | raised[f[1:]]
        slowed = _slowed_around(knots, step, up, duration, slowest=1.0 / QUICKEST) if (up & ~flight).any() else None
        if slowed is None:  # no foot up but in the flight, or the stances too short to take it all
            slowed = _slowed_around(knots, step, flight, duration)
        if slowed is not None:
            return slowed, knots
    speed_max = float((least / np.maximum(step, 1e-12)).max()) * limit
    if (end - clip_in) / duration * speed_max <= limit or least.sum() >= duration:
        return np.array([0.0, 1.0]), np.array([clip_in, end])
    lo, hi = 0.0, duration / max(end - clip_in, 1e-9)  # the squeeze of the slow parts, by bisection
    for _ in range(50):
        c = (lo + hi) / 2
        lo, hi = (c, hi) if np.maximum(c * step, least).sum() < duration else (lo, c)
    out = np.maximum(hi * step, least)
    for _ in range(3):  # the rate eased from squeezed to not (no lurch where a hold meets a swing)
        out = np.maximum(gaussian_filter1d(out, 2.0, mode="nearest"), least)
        spare = out - least  # the time over the limit each step has: the excess comes out of it
        if spare.sum() > 1e-12:
            out = out - spare * min(1.0, (out.sum() - duration) / spare.sum())
    u = np.concatenate([[0.0], np.cumsum(out)]) / out.sum()
    return u, knots


def _slowed_around(knots: np.ndarray, step: np.ndarray, keep: np.ndarray, duration: float,
                   slowest: float = 0.0) -> np.ndarray | None:
    """Pacing knots (span fractions at ``knots``) for a clip range played slower than its own
    pace over ``duration``: the steps ``keep`` (a flight, a foot raised) at their own pace —
    slowed evenly, a performer's long-held jump hung in the air and a slow performer's Get
    Angry held its stamping foot 22 cm up, nearly still, for 0.57 s — and the rest
    slowed to fill the span, the rate eased into the kept steps' over :data:`SLOWED_EASE` of
    clip time. None when no step, or every step, is kept, or when the rest would play slower
    than ``slowest`` times its own pace (a kick whose foot is up nearly all the clip: its few
    standing frames would freeze)."""
    if not keep.any() or keep.all():
        return None
    mid = (knots[1:] + knots[:-1]) / 2
    away = np.abs(mid[:, None] - mid[keep][None, :]).min(axis=1)  # clip time to the nearest kept step
    w = np.where(keep, 0.0, _smoothstep(np.clip(away / SLOWED_EASE, 0.0, 1.0)))
    if not (w > 0).any():
        return None
    lo, hi = 1e-6, 1.0  # the rate away from the kept steps, by bisection: the clip fills the span
    for _ in range(60):
        r = (lo + hi) / 2
        lo, hi = (r, hi) if np.sum(step / (1.0 + (r - 1.0) * w)) > duration else (lo, r)
    if hi < slowest:
        return None
    out = step / (1.0 + (hi - 1.0) * w)
    return np.concatenate([[0.0], np.cumsum(out)]) / out.sum()


def pose_at(placed: Placed, t: np.ndarray, path_xz: np.ndarray, heading: np.ndarray,
            ground_y: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Local translations (F, J, 3) and rotations (F, J, 4) of the clip placed on the path."""
    trans, rots = _sample(placed.motion, clip_time(placed, t))
    p = placed.pelvis
    parents = placed.motion.skeleton.parents
    yaw = quat.exp(np.outer(heading, [0.0, 1.0, 0.0]))
    # the pelvis carries the character: its horizontal position follows the path, its
    # height and tilt come from the clip; the clip's own travel is replaced (in-place
    # actions keep their sway around the spot)
    rest_xz = placed.motion.translations[0, p, [0, 2]]
    local = trans[:, p]
    sway = local[:, [0, 2]] - rest_xz
    if placed.travels:  # travel along the clip's direction is the path's; sideways sway stays
        net = placed.motion.translations[-1, p, [0, 2]] - rest_xz
        along = net / max(np.linalg.norm(net), 1e-9)
        sway = sway - np.outer(sway @ along, along)
    sway3 = np.column_stack([sway[:, 0], np.zeros(len(t)), sway[:, 1]])
    lift = np.zeros(len(t)) if ground_y is None else ground_y
    ground = np.column_stack([path_xz[:, 0], lift, path_xz[:, 1]])
    if parents[p] < 0:  # the pelvis is the root: it takes the path and the heading
        moved = quat.rotate(yaw, sway3)
        trans[:, p, 0] = ground[:, 0] + moved[:, 0]
        trans[:, p, 1] += lift
        trans[:, p, 2] = ground[:, 2] + moved[:, 2]
        rots[:, p] = quat.compose(yaw, rots[:, p])
        return trans, rots
    # helper joints above the pelvis (Bandai's joint_Root): the top one takes the path and
    # the heading, the others are neutral, the pelvis keeps its height, tilt and sway
    a = parents[p]
    while a >= 0:
        trans[:, a] = 0.0
        rots[:, a] = (0.0, 0.0, 0.0, 1.0)
        a = parents[a]
    trans[:, 0] = ground
    rots[:, 0] = yaw
    trans[:, p, 0] = sway3[:, 0]
    trans[:, p, 2] = sway3[:, 2]
    return trans, rots


def sequence(placed: list[Placed], times: np.ndarray, path_xz: np.ndarray, heading: np.ndarray,
             skeleton: Skeleton, fps: float, blend=BLEND,
             ground_y: np.ndarray | None = None) -> tuple[Motion, list[float]]:
    """The whole timeline at ``fps``; returns the motion and the transition times.
    ``blend``: the cross-fades' length (s), one for all or one per transition
    (:func:`blend_lengths`)."""
    frames = len(times)
    j = len(skeleton)
    trans = np.zeros((frames, j, 3))
    rots = np.zeros((frames, j, 4))
    weight = np.zeros(frames)
    boundaries = [pl.span.t0 for pl in placed[1:]]
    for pl, idx, w in _blend_weights(placed, times, blend):
        idx = slice(int(idx[0]), int(idx[-1]) + 1)  # consecutive frames: views, not copies
        tt = times[idx]
        tr, ro = pose_at(pl, tt, path_xz[idx], heading[idx], None if ground_y is None else ground_y[idx])
        first = weight[idx] == 0
        trans[idx] += tr * w[:, None, None]
        prev = rots[idx]
        dot = np.sum(prev * ro, axis=-1, keepdims=True)
        ro = np.where(dot < 0, -ro, ro)
        rots[idx] = np.where(first[:, None, None], ro * w[:, None, None], prev + ro * w[:, None, None])
        weight[idx] += w
    weight = np.maximum(weight, 1e-9)
    trans /= weight[:, None, None]
    for a in range(0, frames, 4096):  # normalised in blocks: no whole-timeline temporaries
        rots[a:a + 4096] /= np.linalg.norm(rots[a:a + 4096], axis=-1, keepdims=True)
    return Motion(skeleton, trans, rots, 1.0 / fps), boundaries


def boundary_gaps(placed: list[Placed], times: np.ndarray, path_xz: np.ndarray, heading: np.ndarray,
                  skeleton: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Per transition (``len(placed) - 1`` each), how far apart (m) the two clips put the
    body's farthest point (joint or End Site) at the moment one hands over to the next, and
    how much higher (m) the next one puts the pelvis (0 where it is lower)."""
    if len(placed) < 2:
        return np.zeros(0), np.zeros(0)
    at = np.array([b.span.t0 for b in placed[1:]])
    xz = np.column_stack([np.interp(at, times, path_xz[:, 0]), np.interp(at, times, path_xz[:, 1])])
    h = np.interp(at, times, heading)
    n = len(at)
    trans = np.zeros((2 * n, len(skeleton), 3))
    rots = np.zeros((2 * n, len(skeleton), 4))
    for k, pl in enumerate(placed):  # each clip once: at the hand-over it starts with and the one it ends with
        ends = [i for i in (k - 1, k) if 0 <= i < n]
        rows = [2 * i + 1 if i == k - 1 else 2 * i for i in ends]
        trans[rows], rots[rows] = pose_at(pl, at[ends], xz[ends], h[ends])
    points = body_points(Motion(skeleton, trans, rots, 1.0))  # one pass for all
    pelvis = points[:, pelvis_of(skeleton), 1]
    gaps = np.linalg.norm(points[1::2] - points[0::2], axis=2).max(axis=1)
    return gaps, np.maximum(pelvis[1::2] - pelvis[0::2], 0.0)


def _pelvis_height(placed: Placed, t: np.ndarray) -> np.ndarray:
    """The pelvis's height (m, on flat ground) of the placed clip at times ``t``, as
    :func:`pose_at` puts it (its own height; helper joints above it zeroed), interpolated
    alone rather than with the whole pose."""
    m = placed.motion
    f = np.clip(clip_time(placed, t) / m.frame_time, 0, m.frames - 1)
    return np.interp(f, np.arange(m.frames), m.translations[:, placed.pelvis, 1])


def rising_blends(placed: list[Placed], times: np.ndarray, blends: np.ndarray, rises: np.ndarray) -> np.ndarray:
    """The cross-fades' lengths ``blends`` (:func:`blend_lengths`), lengthened up to
    :data:`BLEND_MOST` where a fade into a pose with the pelvis higher (``rises``,
    :func:`boundary_gaps`) would lift it, the two clips' own motion added, faster than
    :data:`RISE_MARGIN` × the animation check's limit (or than either clip lifts it itself;
    where no length does, the one that comes nearest): a quick Duck whose getting up was
    trimmed rose on its own at 2.2 m/s as the 0.36 s fade into a stand began, and the two
    together jerked the body up at 2.6 m/s with its feet on the floor. Evaluated on the
    output frames around the hand-over, one transition at a time."""
    out = np.array(blends, dtype=float)
    limit = RISE_MARGIN * Limits().rise
    for k in np.flatnonzero(np.asarray(rises) > 0.0):
        at = placed[k + 1].span.t0
        idx = np.arange(np.searchsorted(times, at - BLEND_MOST / 2),
                        np.searchsorted(times, at + BLEND_MOST / 2, "right"))
        if len(idx) < 3:
            continue
        tt = times[idx]
        ha, hb = (_pelvis_height(placed[j], tt) for j in (k, k + 1))
        dt = np.diff(tt)
        allowed = max(limit, float((np.diff(ha) / dt).max()), float((np.diff(hb) / dt).max()))
        best = (np.inf, out[k])
        for length in np.arange(out[k], BLEND_MOST + 1e-9, BLEND_STEP):
            w = _smoothstep((tt - (at - length / 2)) / length)
            best = min(best, (float((np.diff((1.0 - w) * ha + w * hb) / dt).max()), length))
            if best[0] <= allowed:
                break
        out[k] = best[1]  # the first length that keeps to it, else the one that comes nearest
    return out


def blend_lengths(gaps: np.ndarray, blend: float = BLEND) -> np.ndarray:
    """Per transition, how long its cross-fade lasts (s): ``blend``, or longer where the two
    clips put the body far apart (``gaps``, :func:`boundary_gaps`) — so that the cross-fade
    alone swings no point faster than :data:`BLEND_SPEED` (a smoothstep's steepest slope,
    1.5 / duration, over the arc a rotation takes, at most π/2 × the gap) — up to
    :data:`BLEND_MOST`: a raised arm whose return to rest was trimmed, cross-faded into a
    stand in 0.2 s, swung its hand down at 17 m/s."""
    return np.clip(1.5 * (np.pi / 2) * np.asarray(gaps, dtype=float) / BLEND_SPEED, blend, max(blend, BLEND_MOST))


def _blend_weights(placed: list[Placed], times: np.ndarray, blend):
    """Per placed clip: the output frames it plays in and its cross-fade weight there
    (``blend``: the cross-fades' length, one for all or one per transition)."""
    blends = np.broadcast_to(np.asarray(blend, dtype=float), (max(len(placed) - 1, 0),))
    out = []
    for k, pl in enumerate(placed):
        before = blends[k - 1] if k > 0 else 0.0
        after = blends[k] if k < len(placed) - 1 else 0.0
        lo = pl.span.t0 - before / 2
        hi = pl.span.t1 + after / 2
        first = int(np.searchsorted(times, lo - 1e-9, side="left"))  # times sorted: a span, not a mask
        stop = int(np.searchsorted(times, hi + 1e-9, side="right"))
        if k == 0:  # ... and every frame before the first span
            start = int(np.searchsorted(times, pl.span.t0, side="left"))
            if start > 0:
                first, stop = 0, max(stop, start)
        if k == len(placed) - 1:  # ... and every frame after the last
            end = int(np.searchsorted(times, pl.span.t1, side="right"))
            if end < len(times):
                first, stop = min(first, end), len(times)
        idx = np.arange(first, max(stop, first))
        if len(idx) == 0:
            continue
        w = np.ones(len(idx))
        tt = times[idx]
        if k > 0:
            w *= _smoothstep((tt - (pl.span.t0 - before / 2)) / before)
        if k < len(placed) - 1:
            w *= 1.0 - _smoothstep((tt - (pl.span.t1 - after / 2)) / after)
        out.append((pl, idx, w))
    return out


def contact_states(placed: list[Placed], times: np.ndarray, feet: int = 2, blend=BLEND) -> np.ndarray:
    """(F, feet) bool: where the sequenced clips mean each foot to stand on the ground —
    each clip's own contacts at the clip time it plays, voted with the cross-fade weights of
    :func:`sequence` (``blend`` as it had them; a clip without contacts counts as standing)."""
    return _voted(placed, times, feet, blend, "contacts", 1.0)


def roll_states(placed: list[Placed], times: np.ndarray, feet: int = 2, blend=BLEND) -> np.ndarray:
    """(F, feet) bool: where the sequenced clips mean a foot to turn on its toes in place (a
    jump's push-off and landing, ``Placed.rolls``), voted as :func:`contact_states` does."""
    return _voted(placed, times, feet, blend, "rolls", 0.0)


def _voted(placed: list[Placed], times: np.ndarray, feet: int, blend, what: str, missing: float) -> np.ndarray:
    vote = np.zeros((len(times), feet))
    total = np.zeros(len(times))
    for pl, idx, w in _blend_weights(placed, times, blend):
        states = getattr(pl, what)
        if states is None or len(states) == 0:
            c = np.full((len(idx), feet), missing)
        else:
            f = np.rint(clip_time(pl, times[idx]) / pl.motion.frame_time).astype(int)
            c = states[np.clip(f, 0, len(states) - 1)].astype(float)
        vote[idx] += c * w[:, None]
        total[idx] += w
    return vote / np.maximum(total, 1e-9)[:, None] >= 0.5


def _smoothstep(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)
