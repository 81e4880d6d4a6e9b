"""Clip analysis: skeleton roles and partition, animation stages, cycles, foot contacts.

* Roles (pelvis, chest, head, feet, hands) are guessed from joint names of the common
  conventions (Mixamo ``LeftFoot``, Bandai ``Foot_L``, DeepMimic ``left_ankle``…); a library
  manifest can name them instead.
* Partition (§5.4.1): *spine* joints lie on the chains pelvis→chest and pelvis→head,
  *primary* joints are the other children of spine joints (shoulders, hips), *secondary*
  are the rest.
* Stages (§5.3.2), by default from the speed profile of the most-moving end effector (hand,
  foot or head, relative to the pelvis): the execution is its main burst, the anticipation
  ends where that burst starts, the preparation where the effector first moves, the
  follow-through where it moves again after the execution (the return from a hold); each end
  is then moved to the nearest valley of speed (an extreme pose, where speed and
  acceleration vanish) within 0.27 s. A clip holding several repetitions of one action (the
  Bandai punch jabs five times) is split by :func:`repetitions`, and its stages are those of
  the first repetition, the transition running to the clip's end. Measured against
  hand-labelled real clips and the keyed built-in clips (``bench/stages_accuracy.py``) this
  beats the alternatives kept here: optimal keyframe reduction by dynamic programming
  (``"keyframes"``) and the thesis's extreme poses (``"extremes"``: speed and acceleration
  minima under ``min + p·(max − min)`` of the body speed, p = 0.15, labelled in the fixed
  order of Fig. 2.2, with two poses split by whether the main direction reverses).
* Cycles: a cyclic clip's *cycle length* is one stride — a full gait cycle, both feet
  stepping once — measured from the feet's contacts: the distance between two successive
  footprints of the same foot (median over both feet); in a clip too short for two
  footprints of one foot, twice a step (one foot's footprint to the other's, along the
  direction of travel). Only a clip without footprints falls back to the period: the lag of
  greatest self-similarity of its root-relative pose, which can lock on a step or on two
  strides, and the distance the root travels in it.
* Facing and travel: a clip faces where its hips' left-to-right axis turned a quarter turn
  points (+z when the left hip is at +x); its *travel direction* is where the pelvis goes
  relative to that facing (0 forwards, +π/2 leftwards, π backwards).
* Foot contacts: a foot joint is in contact while it is near its lowest height in the clip
  and nearly still.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from doodle.core.filters import gaussian_filter1d
from doodle.core.peaks import find_peaks
from retarget.skeleton import Motion, Skeleton, end_site_positions, forward_kinematics

ROLE_PATTERNS = {
    "pelvis": [r"^(mixamorig:)?hips$", r"^pelvis$", r"^root$", r"^hip$"],
    "chest": [r"^(mixamorig:)?spine2$", r"^chest$", r"^spine1$", r"^upperchest$", r"^spine$"],
    "head": [r"^(mixamorig:)?head$", r"^neck$"],
    "left_foot": [r"^(mixamorig:)?leftfoot$", r"^foot_l$", r"^left_ankle$", r"^l_?foot$", r"^lfoot$"],
    "right_foot": [r"^(mixamorig:)?rightfoot$", r"^foot_r$", r"^right_ankle$", r"^r_?foot$", r"^rfoot$"],
    "left_hand": [r"^(mixamorig:)?lefthand$", r"^hand_l$", r"^left_wrist$", r"^l_?hand$", r"^lhand$"],
    "right_hand": [r"^(mixamorig:)?righthand$", r"^hand_r$", r"^right_wrist$", r"^r_?hand$", r"^rhand$"],
}


def guess_roles(skeleton: Skeleton) -> dict[str, int]:
    """Role → joint index for the roles whose joint name follows a known convention."""
    return dict(_roles_of(tuple(skeleton.names)))


@lru_cache(maxsize=256)
def _roles_of(names: tuple[str, ...]) -> tuple[tuple[str, int], ...]:
    roles = []
    lowered = [n.lower() for n in names]
    for role, patterns in ROLE_PATTERNS.items():
        for pattern in patterns:
            hits = [i for i, n in enumerate(lowered) if re.match(pattern, n)]
            if hits:
                roles.append((role, hits[0]))
                break
    return tuple(roles)


def _chain(skeleton: Skeleton, ancestor: int, joint: int) -> list[int]:
    path = [joint]
    while path[-1] != ancestor:
        parent = int(skeleton.parents[path[-1]])
        if parent < 0:
            raise ValueError(f"{skeleton.names[ancestor]} is not an ancestor of {skeleton.names[joint]}")
        path.append(parent)
    return path


def partition(skeleton: Skeleton, pelvis: int, chest: int, head: int) -> dict[str, list[int]]:
    """Spine, primary and secondary joints (§5.4.1)."""
    spine = sorted(set(_chain(skeleton, pelvis, chest)) | set(_chain(skeleton, pelvis, head)))
    primary = sorted(c for s in spine for c in skeleton.children(s) if c not in spine)
    secondary = sorted(set(range(len(skeleton))) - set(spine) - set(primary))
    return {"spine": spine, "primary": primary, "secondary": secondary}


# --- stages --------------------------------------------------------------------------------

STAGE_NAMES = ("preparation", "anticipation", "execution", "follow_through", "transition")


@dataclass(frozen=True)
class Stages:
    """Frame at which each stage ends (the last ends with the clip); equal ends mean an
    absent stage."""

    preparation: int
    anticipation: int
    execution: int
    follow_through: int
    transition: int

    def bounds(self) -> dict[str, tuple[int, int]]:
        ends = [self.preparation, self.anticipation, self.execution, self.follow_through, self.transition]
        starts = [0] + ends[:-1]
        return {name: (s, e) for name, s, e in zip(STAGE_NAMES, starts, ends)}


def pelvis_of(skeleton: Skeleton) -> int:
    """The pelvis joint (guessed from names), else the root."""
    return guess_roles(skeleton).get("pelvis", 0)


def body_joints(skeleton: Skeleton) -> np.ndarray:
    """The pelvis and its descendants: the body, without helper roots above it."""
    pelvis = pelvis_of(skeleton)
    inside = np.zeros(len(skeleton), dtype=bool)
    inside[pelvis] = True
    for j in range(pelvis + 1, len(skeleton)):
        inside[j] = inside[skeleton.parents[j]]
    return np.flatnonzero(inside)


def _relative(motion: Motion, positions: np.ndarray) -> np.ndarray:
    """Body joint positions relative to the pelvis, (F, B, 3)."""
    pelvis = pelvis_of(motion.skeleton)
    return positions[:, body_joints(motion.skeleton)] - positions[:, pelvis : pelvis + 1]


def body_speed(motion: Motion, world: np.ndarray | None = None, sigma: float = 1.5):
    """Smoothed mean joint speed (pelvis-relative, m/s) and acceleration magnitude per frame."""
    positions = forward_kinematics(motion)[0] if world is None else world
    rel = _relative(motion, positions)
    rel = gaussian_filter1d(rel, sigma, axis=0, mode="nearest") if motion.frames > 3 else rel
    vel = np.gradient(rel, motion.frame_time, axis=0)
    acc = np.gradient(vel, motion.frame_time, axis=0)
    return np.linalg.norm(vel, axis=2).mean(axis=1), np.linalg.norm(acc, axis=2).mean(axis=1)


def extreme_poses(motion: Motion, p: float = 0.15, world: np.ndarray | None = None,
                  prominence: float = 0.1) -> list[int]:
    """Frames of the extreme poses between the clip's first and last movement: valleys of
    the body speed (flat ones included, as at a held key) whose speed is in the lowest
    ``p`` of the clip's range and whose depth is at least ``prominence`` of that range;
    acceleration is low there too, by construction of a valley of speed."""
    speed, _ = body_speed(motion, world)
    n = len(speed)
    if n < 5:
        return []
    span = speed.max() - speed.min()
    if not span > 0:
        return []
    low = speed.min() + p * span
    moving = np.flatnonzero(speed > low)
    if len(moving) == 0:
        return []
    first, last = moving[0], moving[-1]
    valleys, props = find_peaks(-speed, height=-low, prominence=prominence * span, plateau_size=1)
    keep = [(int(v), float(pr)) for v, pr in zip(valleys, props["prominences"]) if first < v < last]
    return [v for v, _ in keep]


def _ranked(motion: Motion, poses: list[int], world: np.ndarray, count: int) -> list[int]:
    """The ``count`` most pronounced extreme poses (deepest valleys), in time order."""
    speed, _ = body_speed(motion, world)
    valleys, props = find_peaks(-speed, prominence=0.0, plateau_size=1)
    depth = {int(v): float(pr) for v, pr in zip(valleys, props["prominences"])}
    return sorted(sorted(poses, key=lambda i: -depth.get(i, 0.0))[:count])


def _main_direction(motion: Motion, world: np.ndarray, a: int, b: int) -> np.ndarray:
    rel = _relative(motion, world)
    moved = rel[b] - rel[a]
    k = int(np.argmax(np.linalg.norm(moved, axis=1)))
    return moved[k]


def keyframe_stages(motion: Motion, most_frames: int = 90) -> Stages:
    """Stages by optimal keyframe reduction (the alternative §5.3.2 proposes, after Roberts
    et al. 2019): the four interior key poses that, with the first and last frame, best
    reconstruct the clip's pelvis-relative pose by linear interpolation — dynamic
    programming over frames (subsampled to at most ``most_frames``)."""
    world = forward_kinematics(motion)[0]
    x = _relative(motion, world).reshape(motion.frames, -1)
    n = motion.frames
    if n < 6:
        return Stages(0, 0, n, n, n)
    step = max(1, int(np.ceil(n / most_frames)))
    idx = np.unique(np.concatenate([np.arange(0, n, step), [n - 1]]))
    xs = x[idx]
    m = len(xs)
    err = np.full((m, m), np.inf)
    for a in range(m - 1):
        for b in range(a + 1, m):
            w = np.linspace(0.0, 1.0, b - a + 1)[:, None]
            err[a, b] = float(((xs[a : b + 1] - (xs[a] * (1 - w) + xs[b] * w)) ** 2).sum())
    segments = 5
    best = np.full((segments + 1, m), np.inf)
    back = np.zeros((segments + 1, m), dtype=int)
    best[0, 0] = 0.0
    for j in range(1, segments + 1):
        for b in range(1, m):
            cost = best[j - 1, :b] + err[:b, b]
            back[j, b] = int(np.argmin(cost))
            best[j, b] = cost[back[j, b]]
    keys, b = [], m - 1
    for j in range(segments, 1, -1):
        b = back[j, b]
        keys.append(int(idx[b]))
    return Stages(*sorted(keys), n)


def extreme_stages(motion: Motion, p: float = 0.15) -> Stages:
    """Stages by the thesis's extreme poses (§5.3.2, :func:`extreme_poses`); stages they do
    not delimit are bounded by the clip's first and last movement: the preparation ends
    where the body starts to move, the follow-through where it stops."""
    world = forward_kinematics(motion)[0]
    n = motion.frames
    speed, _ = body_speed(motion, world)
    span = speed.max() - speed.min()
    moving = np.flatnonzero(speed > speed.min() + p * span) if span > 0 else np.empty(0, int)
    start, end = (int(moving[0]), int(moving[-1]) + 1) if len(moving) else (0, n)
    poses = extreme_poses(motion, p, world)
    if len(poses) > 4:  # keep the four most pronounced, in order
        poses = _ranked(motion, poses, world, 4)
    if len(poses) == 4:
        ends = poses
    elif len(poses) == 3:
        ends = [start] + poses
    elif len(poses) == 2:
        a, b = poses
        reverses = float(_main_direction(motion, world, start, a) @ _main_direction(motion, world, a, b)) < 0
        ends = [start, a, b, end] if reverses else [start, start, a, b]
    elif len(poses) == 1:
        ends = [start, start, poses[0], end]
    else:
        ends = [start, start, end, end]
    return Stages(*ends, n)


# Chosen on the "tune" clips of bench/stage_labels.toml (dataset-1), among the settings no
# worse than keyframe reduction on the keyed built-in clips; the held-out clips chose nothing.
REST = 0.15  # of the speed's range: below it the effector is at rest
VALLEY = 0.5  # of the speed's range: the burst of the execution ends at a valley below it
SNAP = 0.27  # s: a stage end moves to the nearest valley of speed (an extreme pose) this close
REPEAT = 0.6  # cosine of the pose velocities at two peaks of speed: the same movement repeated
EFFECTORS = ("left_hand", "right_hand", "left_foot", "right_foot", "head")


def effector_speed(motion: Motion, world: np.ndarray | None = None, sigma: float = 1.5) -> np.ndarray:
    """(F,) smoothed speed (m/s) of the most-moving end effector — hand, foot or head, the
    one travelling farthest relative to the pelvis over the clip (the pelvis when none is
    known)."""
    positions = forward_kinematics(motion)[0] if world is None else world
    roles = guess_roles(motion.skeleton)
    joints = [roles[r] for r in EFFECTORS if r in roles]
    if not joints or motion.frames < 2:
        return body_speed(motion, positions, sigma)[0]
    rel = positions[:, joints] - positions[:, pelvis_of(motion.skeleton)][:, None]
    rel = gaussian_filter1d(rel, sigma, axis=0, mode="nearest") if motion.frames > 3 else rel
    speed = np.linalg.norm(np.gradient(rel, motion.frame_time, axis=0), axis=2)
    return speed[:, int(np.argmax(speed.sum(axis=0)))]


def snap_to_valleys(ends, speed: np.ndarray, radius: int) -> tuple[int, ...]:
    """Each end moved to the nearest local minimum of ``speed`` within ``radius`` frames
    (kept where there is none), still in order."""
    inner = np.flatnonzero((speed[1:-1] <= speed[:-2]) & (speed[1:-1] <= speed[2:])) + 1
    out = []
    for e in ends:
        near = inner[np.abs(inner - e) <= radius]
        out.append(int(near[np.argmin(np.abs(near - e))]) if len(near) else int(e))
    return tuple(int(x) for x in np.maximum.accumulate(out))


def burst_ends(speed: np.ndarray, rest: float = REST, valley: float = VALLEY) -> tuple[int, int, int, int]:
    """The four stage ends of one action from its speed profile (frames into ``speed``).

    The execution is the main burst — the run of frames around the highest speed, bounded
    on each side by the first valley lower than ``valley`` of the range; the anticipation ends
    where it starts, the execution where it ends. The preparation ends where the body first
    moves (speed above ``rest`` of the range; 0 for a clip that starts moving); the
    follow-through ends where, after the execution, the body moves again (the return towards
    rest after a hold), else at the last movement."""
    n = len(speed)
    span = float(speed.max() - speed.min()) if n else 0.0
    if n < 5 or not span > 0:
        return 0, 0, n, n
    low = speed.min() + rest * span
    level = speed.min() + valley * span
    peak = int(np.argmax(speed))
    a = peak
    while a > 0 and not (speed[a] <= level and speed[a - 1] >= speed[a]):
        a -= 1
    b = peak
    while b < n - 1 and not (speed[b] <= level and speed[b + 1] >= speed[b]):
        b += 1
    moving = np.flatnonzero(speed > low)
    prep = min(int(moving[0]), a) if len(moving) else a
    after = [j for j in range(b, n - 1) if speed[j] > low and speed[j + 1] >= speed[j]]
    follow = after[0] if after else max(b, int(moving[-1]) + 1 if len(moving) else b)
    return prep, a, b, min(follow, n)


def _pose_velocity(motion: Motion, world: np.ndarray, sigma: float = 1.5) -> np.ndarray:
    rel = gaussian_filter1d(_relative(motion, world), sigma, axis=0, mode="nearest")
    return np.gradient(rel, motion.frame_time, axis=0).reshape(motion.frames, -1)


def repetitions(motion: Motion, world: np.ndarray | None = None, repeat: float = REPEAT) -> list[tuple[int, int]]:
    """(start, end) frame ranges of the repetitions of one action a clip holds (the Bandai
    punch jabs five times): the clip's main peaks of body speed — at least half its range
    high, a third of it prominent, a second apart — whose pose velocity points the way the
    highest one's does (cosine above ``repeat``; a raise and the lowering after it do not
    repeat each other; the best match within 0.4 s of each peak, as a kick's peak of speed
    may come on the way up or on the way down) are one repetition each, cut between two at the frame closest to the
    clip's first pose (the rest it starts from). One range, the whole clip, when it holds
    one action."""
    world = forward_kinematics(motion)[0] if world is None else world
    n = motion.frames
    speed, _ = body_speed(motion, world)
    span = float(speed.max() - speed.min()) if n else 0.0
    if n < 10 or not span > 0:
        return [(0, n)]
    peaks, _ = find_peaks(speed, height=speed.min() + 0.5 * span, prominence=span / 3,
                          distance=max(1, int(round(1.0 / motion.frame_time))))
    if len(peaks) < 2:
        return [(0, n)]
    vel = _pose_velocity(motion, world)
    main = vel[peaks[int(np.argmax(speed[peaks]))]]
    unit = vel / (np.linalg.norm(vel, axis=1, keepdims=True) + 1e-12)
    main = main / (np.linalg.norm(main) + 1e-12)
    reach = max(1, int(round(0.4 / motion.frame_time)))
    cos = [float(np.max(unit[max(0, p - reach) : p + reach + 1] @ main)) for p in peaks]
    same = peaks[np.array(cos) > repeat]
    if len(same) < 2:
        return [(0, n)]
    pose = _relative(motion, world).reshape(n, -1)
    away = np.linalg.norm(pose - pose[0], axis=1)
    cuts = [int(p + 1 + np.argmin(away[p + 1 : q])) for p, q in zip(same, same[1:])]
    bounds = [0] + cuts + [n]
    return list(zip(bounds, bounds[1:]))


def action_ends(motion: Motion, world: np.ndarray | None = None) -> tuple[int, int, int, int]:
    """The four stage ends of a clip holding one action: :func:`burst_ends` of its most-moving
    effector's speed (:func:`effector_speed`), each snapped to a valley of that speed (an
    extreme pose) within :data:`SNAP`."""
    speed = effector_speed(motion, world)
    radius = max(0, int(round(SNAP / motion.frame_time)))
    return snap_to_valleys(burst_ends(speed), speed, radius)


def speed_stages(motion: Motion, world: np.ndarray | None = None) -> Stages:
    """Stages of the clip's first repetition (:func:`repetitions`, :func:`action_ends`); the
    transition runs to the end of the clip (through any further repetitions)."""
    world = forward_kinematics(motion)[0] if world is None else world
    start, end = repetitions(motion, world)[0]
    ends = [start + e for e in action_ends(section(motion, start, end), world[start:end])]
    return Stages(*ends, motion.frames)


def section(motion: Motion, start: int, end: int) -> Motion:
    """Frames [start, end) of a motion."""
    return Motion(motion.skeleton, motion.translations[start:end], motion.rotations[start:end], motion.frame_time)


def stages(motion: Motion, p: float = 0.15, method: str = "speed") -> Stages:
    """The five animation stages of a clip (§5.3.2): from the speed profile of its first
    repetition (default, :func:`speed_stages`), by optimal keyframe reduction
    (``"keyframes"``, :func:`keyframe_stages`) or by the thesis's extreme poses
    (``"extremes"``, :func:`extreme_stages`, threshold ``p``)."""
    if method == "speed":
        return speed_stages(motion)
    if method == "keyframes":
        return keyframe_stages(motion)
    if method == "extremes":
        return extreme_stages(motion, p)
    raise ValueError(f"unknown stage extraction method {method!r}")


# --- cycles and contacts -------------------------------------------------------------------

def cycle_period(motion: Motion, shortest: float = 0.4, longest: float = 2.0, world: np.ndarray | None = None) -> int:
    """Frames per cycle: the lag at which the pelvis-relative pose best repeats."""
    positions = forward_kinematics(motion)[0] if world is None else world
    rel = _relative(motion, positions).reshape(motion.frames, -1)
    lo = max(1, int(round(shortest / motion.frame_time)))
    hi = min(motion.frames // 2, int(round(longest / motion.frame_time)))
    if hi <= lo:
        return motion.frames
    lags = np.arange(lo, hi + 1)
    cost = np.array([np.mean(np.sum((rel[lag:] - rel[:-lag]) ** 2, axis=1)) for lag in lags])
    interior = [i for i in range(1, len(cost) - 1) if cost[i] <= cost[i - 1] and cost[i] < cost[i + 1]]
    if not interior:
        return int(lags[int(np.argmin(cost))])
    best = min(cost[i] for i in interior)
    return int(lags[next(i for i in interior if cost[i] <= best * 1.1 + 1e-12)])


def cycle_length(motion: Motion, period: int | None = None) -> float:
    """Horizontal distance (m) of one stride (:func:`stride_length`); without footprints, or
    with ``period`` given, the distance the pelvis travels per period, averaged over the clip."""
    world = forward_kinematics(motion)[0]
    if period is None:
        stride = stride_length(motion, world)
        if stride is not None:
            return stride
        period = cycle_period(motion, world=world)
    root = world[:, pelvis_of(motion.skeleton)][:, [0, 2]]
    if period >= motion.frames:
        return float(np.linalg.norm(root[-1] - root[0]))
    steps = np.linalg.norm(root[period:] - root[:-period], axis=1)
    return float(steps.mean())


FOOTPRINT = 0.15  # m: two stances of one foot closer than this are the same footprint (a foot rolling)


@dataclass(frozen=True)
class Footprint:
    """One stance of one foot: which foot (0 left, 1 right), its frames and where it stood."""

    foot: int
    start: int
    end: int  # exclusive
    at: np.ndarray  # (2,) horizontal (x, z) position, metres


def footprints(motion: Motion, world: np.ndarray | None = None) -> list[Footprint]:
    """The stances of both feet in time order (:func:`foot_contacts` runs; runs of one
    foot less than :data:`FOOTPRINT` apart merged)."""
    positions = forward_kinematics(motion)[0] if world is None else world
    roles = guess_roles(motion.skeleton)
    if "left_foot" not in roles or "right_foot" not in roles:
        return []
    feet = [roles["left_foot"], roles["right_foot"]]
    contacts = foot_contacts(motion, feet, world=positions)
    prints = []
    for k, joint in enumerate(feet):
        runs: list[Footprint] = []
        on = np.concatenate([[False], contacts[:, k], [False]])
        starts, ends = np.flatnonzero(on[1:] & ~on[:-1]), np.flatnonzero(~on[1:] & on[:-1])
        for a, b in zip(starts, ends):
            at = np.median(positions[a:b, joint][:, [0, 2]], axis=0)
            if runs and np.linalg.norm(at - runs[-1].at) < FOOTPRINT:
                last = runs.pop()
                a, at = last.start, np.median(positions[last.start:b, joint][:, [0, 2]], axis=0)
            runs.append(Footprint(k, int(a), int(b), at))
        prints += runs
    return sorted(prints, key=lambda p: p.start)


def stride_length(motion: Motion, world: np.ndarray | None = None) -> float | None:
    """One stride (m): the median distance between successive footprints of the same foot;
    with none, twice the median step between footprints of alternate feet, along the
    direction of travel; None without two footprints."""
    prints = footprints(motion, world)
    by_foot = [[p for p in prints if p.foot == k] for k in (0, 1)]
    strides = [float(np.linalg.norm(b.at - a.at)) for one in by_foot for a, b in zip(one, one[1:])]
    if strides:
        return float(np.median(strides))
    net = prints[-1].at - prints[0].at if len(prints) > 1 else np.zeros(2)
    if len(prints) < 2 or not np.linalg.norm(net) > 1e-6:
        return None
    along = net / np.linalg.norm(net)
    steps = [float((b.at - a.at) @ along) for a, b in zip(prints, prints[1:]) if a.foot != b.foot]
    return 2.0 * float(np.median(steps)) if steps else None


def hips_of(skeleton: Skeleton) -> tuple[int, int] | None:
    """The left and right hip joints: the pelvis's children on the way to each foot."""
    roles = guess_roles(skeleton)
    if not {"pelvis", "left_foot", "right_foot"} <= set(roles):
        return None
    try:
        left, right = (_chain(skeleton, roles["pelvis"], roles[f"{s}_foot"])[-2] for s in ("left", "right"))
    except (ValueError, IndexError):
        return None
    return (left, right) if left != right else None


def facing(motion: Motion, world: np.ndarray | None = None) -> np.ndarray:
    """(F,) the body's heading per frame (radians about +y, 0 facing +z): the hips'
    right-to-left axis turned a quarter turn (the character frame: +x left, +z front)."""
    positions = forward_kinematics(motion)[0] if world is None else world
    hips = hips_of(motion.skeleton)
    if hips is None:
        return np.zeros(motion.frames)
    left = positions[:, hips[0]] - positions[:, hips[1]]
    return np.arctan2(-left[:, 2], left[:, 0])  # front = left × up = (−left_z, 0, left_x)


def facing_yaw(motion: Motion, world: np.ndarray | None = None) -> float:
    """The clip's facing (radians about +y): the mean direction of :func:`facing`, or its
    first frame's when the clip turns so much the mean says little (a spin)."""
    yaw = facing(motion, world)
    mean = np.array([np.sin(yaw).mean(), np.cos(yaw).mean()])
    return float(np.arctan2(*mean)) if np.linalg.norm(mean) > 0.7 else float(yaw[0])


def travel_yaw(motion: Motion, world: np.ndarray | None = None, least: float = 0.2) -> float | None:
    """Where the pelvis travels, relative to where the clip faces (radians about +y, in
    (−π, π]: 0 forwards, +π/2 leftwards, π backwards); None when it travels less than
    ``least`` metres."""
    positions = forward_kinematics(motion)[0] if world is None else world
    hips = positions[:, pelvis_of(motion.skeleton)]
    net = hips[-1] - hips[0]
    if not np.hypot(net[0], net[2]) >= least:
        return None
    return float(np.angle(np.exp(1j * (np.arctan2(net[0], net[2]) - facing_yaw(motion, positions)))))


def feet_low(motion: Motion, world=None, roles: dict | None = None) -> np.ndarray:
    """(F,) the height of the lowest foot point: ankles, toes and their end sites
    (``roles``: role → joint, default guessed from the joint names)."""
    world = forward_kinematics(motion) if world is None else world
    sk = motion.skeleton
    roles = guess_roles(sk) if roles is None else roles
    joints, stack = [], [roles["left_foot"], roles["right_foot"]]
    while stack:
        joints.append(stack.pop())
        stack += sk.children(joints[-1])
    ends = end_site_positions(motion, world)
    heights = [world[0][:, j, 1] for j in joints] + [ends[j][:, 1] for j in joints if j in ends]
    return np.min(heights, axis=0)


def foot_contacts(motion: Motion, joints: list[int], height: float = 0.03, speed: float = 0.25,
                  world: np.ndarray | None = None) -> np.ndarray:
    """(F, len(joints)) bool: each foot on the floor — the lowest of the joint and the joints
    below it (toes) within ``height`` m of the floor — and the joint slower than ``speed``
    m/s. The floor is where the clip's lower foot mostly stands (the 5th percentile of its
    height), not its very lowest point: a landing that bends an ankle through it once does
    not lift every stance off the floor."""
    positions = forward_kinematics(motion)[0] if world is None else world
    soles = np.stack([positions[:, motion.skeleton.subtree(j), 1].min(axis=1) for j in joints], axis=1)
    floor = float(np.percentile(soles.min(axis=1), 5))
    vel = np.linalg.norm(np.gradient(positions[:, joints], motion.frame_time, axis=0), axis=2)
    return (soles - floor <= height) & (vel <= speed)
