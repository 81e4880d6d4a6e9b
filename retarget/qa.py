"""The animation check: what an animator sees in motion, measured frame by frame.

Each measure names the frames it happens in, so a failure can be looked at:

* **sliding** — a foot flat on the floor (every point of it within :attr:`Limits.flat` of
  its height when the character stands: a swinging foot passes 2–3 cm higher) of which no point — ankle,
  toes, toe tips — moves horizontally slower than :attr:`Limits.slide` (a foot rolling over
  its heel or toes is not sliding), flat for at least :attr:`Limits.stance` (a swinging foot
  skimming the floor is not standing on it); reported as frames per second of motion;
* **pops** — any joint or end site moving faster than :attr:`Limits.pop` between two frames;
* **one-frame turns** — the pelvis's heading changing by more than :attr:`Limits.turn` in one
  frame while the frames either side turn less than a third of that (a turn that is not
  eased);
* **hovering** — a foot held still for longer than :attr:`Limits.held` with its sole more
  than :attr:`Limits.hover` above the ground, or both feet above it for longer than
  :attr:`Limits.flight` (longer than any real jump's flight), and **sinking** —
  any point of the body below the ground by more than :attr:`Limits.sink`;
* **interpenetration** — two characters' bodies, as capsules around their bones
  (:attr:`Limits.limb` radius, :attr:`Limits.trunk` for the spine), overlapping.

Calibration (``python -m bench.animation_check``): the limits are the issue's targets,
checked against real motion capture under ``../shared/data/mocap`` — every Bandai
``*_normal_*`` clip and the DeepMimic clips must pass them, and the bench prints their
worst figures beside the limits. The ground of a mocap clip is its lowest sole height (its
2nd percentile over the clip); of a compiled scene, its terrain (flat y = 0 by default).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from retarget.analysis import guess_roles
from retarget.skeleton import Motion, end_site_positions, forward_kinematics


@dataclass(frozen=True)
class Limits:
    slide: float = 0.3  # m/s: a flat foot moving faster slides
    flat: float = 0.01  # m: every point of a foot within this of its standing height: flat on the floor
    stance: float = 0.1  # s: ... for at least this long
    still: float = 0.1  # m/s: a foot whose every point moves slower than this stands still ...
    held: float = 0.5  # s: ... and one held still above the ground longer than this stands in the air
    slides_per_s: float = 0.3  # sliding frames per second the check allows
    pop: float = 15.0  # m/s: no joint of a person moves faster
    turn: float = 6.0  # degrees of heading in one frame (real walks turn ≤ 6.4° a frame), the frames around it
    # turning under a third of that: a step, not a turn
    hover: float = 0.02  # m: soles above the ground ...
    flight: float = 0.8  # s: ... for longer than a real jump's flight
    sink: float = 0.01  # m below the ground
    limb: float = 0.05  # m: capsule radius of a limb bone
    trunk: float = 0.1  # m: capsule radius of a spine bone


@dataclass(frozen=True)
class Check:
    """One character's figures, each with the frames it happens in."""

    frames: int
    fps: float
    sliding: tuple = ()  # frames where a flat foot slides
    pops: tuple = ()  # frames (the later of the two) where some joint moves faster than the limit
    fastest: float = 0.0  # m/s, the fastest joint
    turns: tuple = ()  # frames of a one-frame turn
    hovering: tuple = ()  # frames hovering
    highest: float = 0.0  # m, the highest hover (lowest sole above the ground in those frames)
    sinking: tuple = ()  # frames sinking
    deepest: float = 0.0  # m below the ground
    touching: dict = field(default_factory=dict)  # other character -> frames interpenetrating
    limits: Limits = Limits()

    @property
    def sliding_per_s(self) -> float:
        return len(self.sliding) / max(self.frames / self.fps, 1e-9)

    @property
    def passes(self) -> bool:
        allowed = self.limits.slides_per_s * self.frames / self.fps + 1e-6  # frames, over the motion's length
        return (len(self.sliding) <= allowed and not self.pops and not self.turns
                and not self.hovering and not self.sinking and not any(self.touching.values()))

    def figures(self) -> dict:
        """The figures as report.json holds them (frames as lists; at most 50 listed)."""
        def listed(frames):
            return [int(f) for f in frames[:50]]

        return {"passes": self.passes, "sliding_frames_per_s": round(self.sliding_per_s, 3),
                "sliding_frames": listed(self.sliding), "pops": len(self.pops), "pop_frames": listed(self.pops),
                "fastest_joint_m_per_s": round(self.fastest, 3), "one_frame_turns": listed(self.turns),
                "hovering_frames": len(self.hovering), "hover_m": round(self.highest, 4),
                "sinking_frames": len(self.sinking), "sink_m": round(self.deepest, 4),
                "interpenetration_frames": {k: len(v) for k, v in self.touching.items()}}

    def summary(self) -> str:
        """One line: the figures and whether they pass."""
        touching = sum(len(v) for v in self.touching.values())
        return (f"sliding {self.sliding_per_s:.2f} frames/s, pops {len(self.pops)} (fastest joint "
                f"{self.fastest:.1f} m/s), one-frame turns {len(self.turns)}, hovering {len(self.hovering)} "
                f"frames (up to {self.highest * 100:.1f} cm), sinking {len(self.sinking)}, interpenetration "
                f"{touching} frames: {'passes' if self.passes else 'FAILS'}")


def _foot_points(motion: Motion, positions: np.ndarray, ends: dict, ankle: int) -> np.ndarray:
    """(F, k, 3): the ankle's descendants (toes) and their end sites — the sole's points."""
    parents = motion.skeleton.parents
    below = [j for j in range(len(parents)) if _descends(parents, j, ankle) and j != ankle]
    points = [positions[:, j] for j in below] + [ends[j] for j in [ankle, *below] if j in ends]
    return np.stack(points, axis=1) if points else positions[:, [ankle]]


def _descends(parents, j: int, ancestor: int) -> bool:
    while j >= 0:
        if j == ancestor:
            return True
        j = int(parents[j])
    return False


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def check(motion: Motion, terrain=None, limits: Limits = Limits(), ground: float | None = None,
          world=None) -> Check:
    """The check of one character. The ground is ``terrain`` (its height under each point),
    else the height ``ground``, else — motion capture — the clip's lowest sole height."""
    positions, rotations = world if world is not None else forward_kinematics(motion)
    ends = end_site_positions(motion, (positions, rotations))
    roles = guess_roles(motion.skeleton)
    dt = motion.frame_time
    pelvis = roles.get("pelvis", 0)
    body = [j for j in range(len(motion.skeleton)) if j != 0 or pelvis == 0]  # not a helper root on the floor
    every = np.concatenate([positions[:, body]] + [e[:, None] for e in ends.values()], axis=1)
    feet = [roles[k] for k in ("left_foot", "right_foot") if k in roles]
    soles = [_foot_points(motion, positions, ends, a) for a in feet]

    def height(points):
        if terrain is not None:
            return points[..., 1] - terrain.height(points[..., [0, 2]])
        return points[..., 1] - (0.0 if ground is None else ground)

    if terrain is None and ground is None and soles:
        ground = float(np.percentile(np.min([s[..., 1].min(axis=1) for s in soles], axis=0), 2))
    sliding = np.zeros(motion.frames, dtype=bool)
    standing = np.zeros(motion.frames, dtype=bool)  # a foot standing still above the ground
    lowest = np.full(motion.frames, np.inf)
    sole_heights = []
    for ankle, sole in zip(feet, soles):
        sole_h = height(sole).min(axis=1)
        sole_heights.append(sole_h)
        # flat: every point of the foot — ankle, toes, tips — as low as when the character stands
        # on it (its 10th percentile over the motion), so whatever the skeleton puts where
        foot_h = height(np.concatenate([positions[:, [ankle]], sole], axis=1))
        flat = (foot_h - np.percentile(foot_h, 10, axis=0) <= limits.flat).all(axis=1)
        for a, b in _runs(flat):  # a swinging foot skimming the floor for a moment is not standing on it
            if (b - a) * dt < limits.stance:
                flat[a:b] = False
        # a foot slides when no point of it stays put (a foot rolling over its toes or heel does not)
        points = np.concatenate([positions[:, [ankle]], sole], axis=1)[:, :, [0, 2]]
        speed = np.linalg.norm(np.gradient(points, dt, axis=0), axis=2).min(axis=1)
        sliding |= flat & (speed > limits.slide)
        # standing in the air: the foot still, every point of it, for longer than a foot is held up
        # in the air by people (:attr:`Limits.held`) — but its sole above the ground
        still = np.linalg.norm(np.gradient(points, dt, axis=0), axis=2).max(axis=1) <= limits.still
        for a, b in _runs(still & (sole_h > limits.hover)):
            if (b - a) * dt >= limits.held:
                standing[a:b] = True
        lowest = np.minimum(lowest, sole_h)
    speeds = np.linalg.norm(np.diff(every, axis=0), axis=2).max(axis=1) / dt if motion.frames > 1 else np.zeros(0)
    pops = np.flatnonzero(speeds > limits.pop) + 1
    hovering = standing.copy()
    if soles:
        for a, b in _runs(lowest > limits.hover):
            if (b - a) * dt > limits.flight:
                hovering[a:b] = True
    sole_top = np.max(sole_heights, axis=0) if soles else lowest
    body_h = height(every).min(axis=1)
    sinking = np.flatnonzero(body_h < -limits.sink)
    return Check(motion.frames, motion.fps, tuple(np.flatnonzero(sliding)), tuple(pops),
                 float(speeds.max()) if len(speeds) else 0.0, tuple(_one_frame_turns(rotations[:, pelvis], limits.turn)),
                 tuple(np.flatnonzero(hovering)),
                 float(np.where(standing, sole_top, lowest)[hovering].max()) if hovering.any() else 0.0,
                 tuple(sinking), float(max(0.0, -body_h.min())), {}, limits)


def _one_frame_turns(root_q: np.ndarray, limit_deg: float) -> list[int]:
    """Frames whose heading change exceeds the limit while both neighbouring frames turn
    under a third of it."""
    from doodle.core import quat

    front = quat.rotate(root_q, np.tile([0.0, 0.0, 1.0], (len(root_q), 1)))
    yaw = np.unwrap(np.arctan2(front[:, 0], front[:, 2]))
    step = np.degrees(np.abs(np.diff(yaw)))
    out = []
    for k in range(len(step)):
        before = step[k - 1] if k > 0 else 0.0
        after = step[k + 1] if k + 1 < len(step) else 0.0
        if step[k] > limit_deg and before < limit_deg / 3 and after < limit_deg / 3:
            out.append(k + 1)
    return out


def _capsules(motion: Motion, positions: np.ndarray, limits: Limits):
    """Bones as segments (F, B, 2, 3) with radii (B,): every joint to its parent."""
    sk = motion.skeleton
    roles = guess_roles(sk)
    trunk = set()
    for end in ("head", "chest"):
        j = roles.get(end)
        while j is not None and j >= 0:
            trunk.add(j)
            j = int(sk.parents[j])
    bones = [j for j in range(1, len(sk)) if np.linalg.norm(sk.offsets[j]) > 0.02]
    seg = np.stack([positions[:, [int(sk.parents[j]) for j in bones]], positions[:, bones]], axis=2)
    radii = np.array([limits.trunk if j in trunk else limits.limb for j in bones])
    return seg, radii


def _segment_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Closest distances between every segment of ``a`` (B1, 2, 3) and of ``b`` (B2, 2, 3)."""
    p, q = a[:, None, 0], b[None, :, 0]
    d1, d2 = a[:, None, 1] - p, b[None, :, 1] - q
    r = p - q
    aa, ee, ff = (d1 * d1).sum(-1), (d2 * d2).sum(-1), (d2 * r).sum(-1)
    c, bb = (d1 * r).sum(-1), (d1 * d2).sum(-1)
    denom = np.maximum(aa * ee - bb * bb, 1e-12)
    s = np.clip((bb * ff - c * ee) / denom, 0.0, 1.0)
    t = np.clip((bb * s + ff) / np.maximum(ee, 1e-12), 0.0, 1.0)
    s = np.clip((bb * t - c) / np.maximum(aa, 1e-12), 0.0, 1.0)
    return np.linalg.norm(p + d1 * s[..., None] - q - d2 * t[..., None], axis=-1)


def interpenetration(a: Motion, b: Motion, limits: Limits = Limits(), world_a=None, world_b=None) -> list[int]:
    """Frames in which two characters' capsules overlap (both on one timeline)."""
    pa = (world_a if world_a is not None else forward_kinematics(a))[0]
    pb = (world_b if world_b is not None else forward_kinematics(b))[0]
    sa, ra = _capsules(a, pa, limits)
    sb, rb = _capsules(b, pb, limits)
    reach = ra[:, None] + rb[None, :]
    frames = []
    for f in range(min(a.frames, b.frames)):
        centre_a, centre_b = pa[f, 0], pb[f, 0]
        if np.linalg.norm((centre_a - centre_b)[[0, 2]]) > 2.5:  # too far apart to touch
            continue
        if (_segment_distances(sa[f], sb[f]) < reach).any():
            frames.append(f)
    return frames


def check_scene(motions: dict, terrain=None, limits: Limits = Limits(), ground: float | None = 0.0) -> dict:
    """Every character's :class:`Check` with interpenetration against the others; the
    ground is ``terrain``, else the height ``ground`` (None: each motion's own floor, as
    for motion capture)."""
    worlds = {name: forward_kinematics(m) for name, m in motions.items()}
    out = {name: check(m, terrain, limits, ground=ground if terrain is None else None, world=worlds[name])
           for name, m in motions.items()}
    names = list(motions)
    for i, x in enumerate(names):
        for y in names[i + 1:]:
            frames = interpenetration(motions[x], motions[y], limits, worlds[x], worlds[y])
            out[x].touching[y] = tuple(frames)
            out[y].touching[x] = tuple(frames)
    return out
