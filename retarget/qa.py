"""The animation check: what an animator sees in motion, measured frame by frame.

Each measure names the frames it happens in, so a failure can be looked at:

* **sliding** — a foot flat on the floor (every point of it within :attr:`Limits.flat` of
  its height when the character stands: a swinging foot passes 2–3 cm higher) of which no point — ankle,
  toes, toe tips — moves horizontally slower than :attr:`Limits.slide` (a foot rolling over
  its heel or toes is not sliding) between two frames it is flat in, flat for at least
  :attr:`Limits.stance` (a swinging foot skimming the floor is not standing on it); reported
  as frames per second of motion;
* **pops** — any joint or end site moving faster than :attr:`Limits.pop` between two frames,
  or the pelvis rising faster than :attr:`Limits.rise` while both soles are on the ground
  (within :attr:`Limits.hover`) and stay there for :attr:`Limits.push` (not a take-off): a body
  jerked up out of a crouch — real motion capture rises at most 1.7 m/s so (a roll; a jump's
  landing recovery under 1 m/s);
* **one-frame turns** — the pelvis's heading changing by more than :attr:`Limits.turn` in one
  frame while the frames either side turn less than a third of that (a turn that is not
  eased);
* **hovering** — a foot held still for longer than :attr:`Limits.held` with its sole more
  than :attr:`Limits.hover` above the ground, or both feet above it for longer than
  :attr:`Limits.flight` (longer than any real jump's flight), and **sinking** —
  any point of the body below the ground by more than :attr:`Limits.sink`;
* **interpenetration** — two characters' bodies, as capsules around their bones
  (:attr:`Limits.limb` radius — the neck, hands and toes too —, :attr:`Limits.trunk` for the
  spine, :attr:`Limits.head` around the head, from its joint to its top), overlapping; an
  interaction's contact joints (:class:`Contact`: a slapping hand and the head, two kissing
  heads) may touch, sinking at most :attr:`Limits.touch` into each other;
* **contacts missed** — at an interaction's contact frame its contact joints' surfaces farther
  apart than :attr:`Limits.contact`;
* **reactions leading their cause** — the receiver's reaction under way (its contact joint
  moving, relative to its pelvis, faster than :attr:`Limits.stir`) before the contact frame.

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
from retarget.skeleton import Motion, end_site_positions, forward_kinematics, kinematics_of


@dataclass(frozen=True)
class Limits:
    """The thresholds of the animation check."""

    slide: float = 0.3  # m/s: a flat foot moving faster slides
    flat: float = 0.01  # m: every point of a foot within this of its standing height: flat on the floor
    stance: float = 0.1  # s: ... for at least this long
    still: float = 0.1  # m/s: a foot whose every point moves slower than this stands still ...
    held: float = 0.5  # s: ... and one held still above the ground longer than this stands in the air
    slides_per_s: float = 0.3  # sliding frames per second the check allows
    pop: float = 15.0  # m/s: no joint of a person moves faster
    rise: float = 2.5  # m/s: the pelvis rises no faster with both soles on the ground (mocap: ≤ 1.7) …
    push: float = 0.3  # s: … unless they leave it within this (a jump's push-off rises at ~2.8 m/s)
    turn: float = 6.0  # degrees of heading in one frame (real walks turn ≤ 6.4° a frame), the frames around it
    # turning under a third of that: a step, not a turn
    hover: float = 0.02  # m: soles above the ground ...
    flight: float = 0.8  # s: ... for longer than a real jump's flight
    sink: float = 0.01  # m below the ground
    limb: float = 0.05  # m: capsule radius of a limb bone
    trunk: float = 0.1  # m: capsule radius of a spine bone
    head: float = 0.09  # m: capsule radius around the head (its joint to its top)
    touch: float = 0.01  # m: contact joints may sink this far into each other (skin gives)
    contact: float = 0.03  # m: contact joints' surfaces farther apart than this miss the contact
    stir: float = 0.3  # m/s: a reaction is under way once its contact joint moves this fast


@dataclass(frozen=True)
class Contact:
    """An interaction as compiled: role 0's joint meets role 1's at ``frame`` (e.g. the
    slapper's right hand and the other's head); ``reaction``: the first and last frames of
    role 1's reaction clip, when role 1 reacts (Slapped) rather than acts alike (Kiss)."""

    interaction: str
    tracks: tuple  # (role 0's track, role 1's track)
    joints: tuple  # (role 0's joint role, role 1's), e.g. ("right_hand", "head")
    frame: int
    reaction: tuple | None = None


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
    missed: tuple = ()  # contact frames of its interactions whose contact joints do not meet
    gap: float = 0.0  # m: the gap between contact joints' surfaces at a contact frame farthest from 0 (< 0: sunk)
    leads: tuple = ()  # frames a reaction of its interactions is under way before the contact

    @property
    def sliding_per_s(self) -> float:
        return len(self.sliding) / max(self.frames / self.fps, 1e-9)

    @property
    def passes(self) -> bool:
        allowed = self.limits.slides_per_s * self.frames / self.fps + 1e-6  # frames, over the motion's length
        return (len(self.sliding) <= allowed and not self.pops and not self.turns
                and not self.hovering and not self.sinking and not any(self.touching.values())
                and not self.missed and not self.leads)

    def figures(self) -> dict:
        """The figures as report.json holds them (frames as lists; at most 50 listed)."""
        def listed(frames):
            return [int(f) for f in frames[:50]]

        return {"passes": self.passes, "sliding_frames_per_s": round(self.sliding_per_s, 3),
                "sliding_frames": listed(self.sliding), "pops": len(self.pops), "pop_frames": listed(self.pops),
                "fastest_joint_m_per_s": round(self.fastest, 3), "one_frame_turns": listed(self.turns),
                "hovering_frames": len(self.hovering), "hover_m": round(self.highest, 4),
                "sinking_frames": len(self.sinking), "sink_m": round(self.deepest, 4),
                "interpenetration_frames": {k: len(v) for k, v in self.touching.items()},
                "contacts_missed": listed(self.missed), "contact_gap_m": round(self.gap, 4),
                "reaction_lead_frames": listed(self.leads)}

    def summary(self) -> str:
        """One line: the figures and whether they pass."""
        touching = sum(len(v) for v in self.touching.values())
        return (f"sliding {self.sliding_per_s:.2f} frames/s, pops {len(self.pops)} (fastest joint "
                f"{self.fastest:.1f} m/s), one-frame turns {len(self.turns)}, hovering {len(self.hovering)} "
                f"frames (up to {self.highest * 100:.1f} cm), sinking {len(self.sinking)}, interpenetration "
                f"{touching} frames, contacts missed {len(self.missed)}, reaction leading {len(self.leads)} frames: "
                f"{'passes' if self.passes else 'FAILS'}")


def _flat_moves(foot_h: np.ndarray, points: np.ndarray, dt: float, limits: Limits) -> tuple[np.ndarray, np.ndarray]:
    """For one foot — its points' heights above the ground ``foot_h`` (F, k) and positions
    ``points`` (F, k, 3) —: per frame, whether it is flat on the floor (every point as low as
    when the character stands on it, its 10th percentile over the motion; for at least
    :attr:`Limits.stance`: a swinging foot skimming the floor for a moment is not standing on
    it), and per pair of consecutive frames how its stillest point moved horizontally (x, z;
    a foot rolling over its toes or heel keeps one point put: it does not slide). A foot
    slides between two frames it is flat in: still on the floor in the frame before it lifts,
    or the frame it lands, it has not slid yet."""
    flat = (foot_h - np.percentile(foot_h, 10, axis=0) <= limits.flat).all(axis=1)
    for a, b in _runs(flat):
        if (b - a) * dt < limits.stance:
            flat[a:b] = False
    step = np.diff(points[:, :, [0, 2]], axis=0)  # (F - 1, k, 2)
    still = np.linalg.norm(step, axis=2).argmin(axis=1)
    return flat, step[np.arange(len(step)), still]


def planted_moves(motion: Motion, world=None, limits: Limits = Limits()) -> tuple[np.ndarray, np.ndarray]:
    """Motion capture's planted feet, as :func:`check` reads them on the clip's own floor: per
    frame and foot, whether the foot is flat on the floor (F, feet), and per pair of
    consecutive frames how its stillest point moved horizontally (F − 1, feet, 2: x, z in
    metres)."""
    positions, rotations = world if world is not None else forward_kinematics(motion)
    ends = end_site_positions(motion, (positions, rotations))
    roles = guess_roles(motion.skeleton)
    feet = [roles[k] for k in ("left_foot", "right_foot") if k in roles]
    if motion.frames < 2 or not feet:
        n = max(motion.frames - 1, 0)
        return np.zeros((motion.frames, 0), dtype=bool), np.zeros((n, 0, 2))
    points = [foot_points(motion, positions, ends, a) for a in feet]
    ground = float(np.percentile(np.min([p[:, 1:, 1].min(axis=1) for p in points], axis=0), 2))
    pairs = [_flat_moves(p[..., 1] - ground, p, motion.frame_time, limits) for p in points]
    return np.stack([f for f, _ in pairs], axis=1), np.stack([m for _, m in pairs], axis=1)


def foot_points(motion: Motion, positions: np.ndarray, ends: dict, ankle: int) -> np.ndarray:
    """(F, 1 + k, 3): the ankle, then the sole's points — its descendants (toes) and their end
    sites (the ankle again when it has none)."""
    below = [j for j in motion.skeleton.subtree(ankle) if j != ankle]
    points = [positions[:, j] for j in [ankle, *below]] + [ends[j] for j in [ankle, *below] if j in ends]
    return np.stack(points if len(points) > 1 else points * 2, axis=1)


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


CHECK_BLOCK = 4096  # frames of the body's points worked out at once


def check(motion: Motion, terrain=None, limits: Limits = Limits(), ground: float | None = None,
          world=None, sole: float = 0.0) -> Check:
    """The check of one character. The ground is ``terrain`` (its height under each point),
    else the height ``ground``, else — motion capture — the clip's lowest sole height.
    ``sole``: how high the skeleton's lowest foot joint or end site stands above the floor
    when it stands (its joints sit inside the foot: 0 for the built-in humanoid, 2–4 cm for
    Bandai's), so a foot is hovering only that much higher."""
    standing_sole = sole if (terrain is not None or ground is not None) else 0.0  # mocap: its own floor
    positions, rotations = world if world is not None else forward_kinematics(motion)
    ends = end_site_positions(motion, (positions, rotations))
    roles = guess_roles(motion.skeleton)
    dt = motion.frame_time
    pelvis = roles.get("pelvis", 0)
    body = [j for j in range(len(motion.skeleton)) if j != 0 or pelvis == 0]  # not a helper root on the floor

    def every(a: int, b: int) -> np.ndarray:  # every point of the body, frames [a, b)
        return np.concatenate([positions[a:b, body]] + [e[a:b, None] for e in ends.values()], axis=1)

    feet = [roles[k] for k in ("left_foot", "right_foot") if k in roles]
    feet_points = [foot_points(motion, positions, ends, a) for a in feet]  # the ankle, then its sole's points
    soles = [p[:, 1:] for p in feet_points]

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
    grounded = np.ones(motion.frames, dtype=bool)  # both soles on the ground
    for points, sole in zip(feet_points, soles):
        sole_h = height(sole).min(axis=1) - standing_sole
        sole_heights.append(sole_h)
        grounded &= sole_h <= limits.hover
        # flat: every point of the foot — ankle, toes, tips — as low as when the character stands
        # on it (its 10th percentile over the motion), so whatever the skeleton puts where
        flat, step = _flat_moves(height(points), points, dt, limits)
        sliding[1:] |= flat[1:] & flat[:-1] & (np.linalg.norm(step, axis=1) / dt > limits.slide)
        points = points[:, :, [0, 2]]
        # standing in the air: the foot still, every point of it, for longer than a foot is held up
        # in the air by people (:attr:`Limits.held`) — but its sole above the ground
        still = np.linalg.norm(np.gradient(points, dt, axis=0), axis=2).max(axis=1) <= limits.still
        for a, b in _runs(still & (sole_h > limits.hover)):
            if (b - a) * dt >= limits.held:
                standing[a:b] = True
        lowest = np.minimum(lowest, sole_h)
    # the body's fastest point and lowest height per frame, in blocks of frames (a long motion's
    # (F, points, 3) is never copied whole)
    blocks = range(0, motion.frames, CHECK_BLOCK)
    speeds = (np.concatenate([np.linalg.norm(np.diff(every(a, a + CHECK_BLOCK + 1), axis=0), axis=2).max(axis=1)
                              for a in blocks if a + 1 < motion.frames]) / dt
              if motion.frames > 1 else np.zeros(0))
    pops = np.flatnonzero(speeds > limits.pop) + 1
    if len(feet) == 2 and motion.frames > 1:  # jerked up out of a crouch, feet on the ground
        rising = np.flatnonzero((np.diff(positions[:, pelvis, 1]) / dt > limits.rise) & grounded[1:] & grounded[:-1]) + 1
        aloft = np.flatnonzero(lowest > limits.hover)  # both soles off the ground
        take_off = aloft[np.minimum(np.searchsorted(aloft, rising), len(aloft) - 1)] if len(aloft) else rising - 1
        pops = np.union1d(pops, rising[(take_off < rising) | (take_off - rising > limits.push / dt)])
    hovering = standing.copy()
    if soles:
        for a, b in _runs(lowest > limits.hover):
            if (b - a) * dt > limits.flight:
                hovering[a:b] = True
    sole_top = np.max(sole_heights, axis=0) if soles else lowest
    body_h = np.concatenate([height(every(a, a + CHECK_BLOCK)).min(axis=1) for a in blocks] or [np.zeros(0)])
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

    # the heading from the front and the left axes, each weighted by how level it lies: a
    # flip pitches the front through the vertical (its heading would swap in a frame) but
    # keeps the left level; a cartwheel the other way round
    front = quat.rotate(root_q, np.tile([0.0, 0.0, 1.0], (len(root_q), 1)))
    left = quat.rotate(root_q, np.tile([1.0, 0.0, 0.0], (len(root_q), 1)))
    level_f, level_l = front[:, 0] ** 2 + front[:, 2] ** 2, left[:, 0] ** 2 + left[:, 2] ** 2
    c = level_f * front[:, 2] + level_l * left[:, 0]  # the left axis turned back by a right angle
    s = level_f * front[:, 0] - level_l * left[:, 2]
    yaw = np.unwrap(np.arctan2(s, c))
    step = np.degrees(np.abs(np.diff(yaw)))
    out = []
    for k in range(len(step)):
        before = step[k - 1] if k > 0 else 0.0
        after = step[k + 1] if k + 1 < len(step) else 0.0
        if step[k] > limit_deg and before < limit_deg / 3 and after < limit_deg / 3:
            out.append(k + 1)
    return out


def _capsules(motion: Motion, positions: np.ndarray, limits: Limits, ends: dict | None = None):
    """Bones as segments (F, B, 2, 3) with radii (B,) and each bone's two joints (B, 2):
    every joint to its parent, and the hands', feet's and head's end sites to their joint
    (a bone to an end site names its joint twice). The spine's bones are trunk-wide, the
    head's is :attr:`Limits.head` wide, the neck and the rest limb-wide."""
    sk = motion.skeleton
    roles = guess_roles(sk)
    head = roles.get("head")
    trunk = set()
    j = roles.get("chest")
    while j is not None and j >= 0:
        trunk.add(j)
        j = int(sk.parents[j])
    bones = [(int(sk.parents[j]), j) for j in range(1, len(sk)) if np.linalg.norm(sk.offsets[j]) > 0.02]
    ends = ends if ends is not None else end_site_positions(motion)
    tips = [j for j in ends if np.linalg.norm(ends[j][0] - positions[0, j]) > 0.02]
    seg = np.stack([np.stack([positions[:, a] for a, _ in bones] + [positions[:, j] for j in tips], axis=1),
                    np.stack([positions[:, b] for _, b in bones] + [ends[j] for j in tips], axis=1)], axis=2)
    radii = np.array([limits.trunk if b in trunk else limits.limb for _, b in bones]
                     + [limits.head if j == head else limits.limb for j in tips])
    return seg, radii, np.array(bones + [(j, j) for j in tips]).reshape(-1, 2)


def closest_points(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The closest points (B1, B2, 3) of every segment of ``a`` (B1, 2, 3) to every segment
    of ``b`` (B2, 2, 3): on ``a``'s segment, and on ``b``'s."""
    p, q = a[:, None, 0], b[None, :, 0]
    d1, d2 = a[:, None, 1] - p, b[None, :, 1] - q
    r = p - q
    aa, ee, ff = (d1 * d1).sum(-1), (d2 * d2).sum(-1), (d2 * r).sum(-1)
    c, bb = (d1 * r).sum(-1), (d1 * d2).sum(-1)
    denom = np.maximum(aa * ee - bb * bb, 1e-12)
    s = np.clip((bb * ff - c * ee) / denom, 0.0, 1.0)
    t = np.clip((bb * s + ff) / np.maximum(ee, 1e-12), 0.0, 1.0)
    s = np.clip((bb * t - c) / np.maximum(aa, 1e-12), 0.0, 1.0)
    return p + d1 * s[..., None], q + d2 * t[..., None]


def _segment_distances(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Closest distances between every segment of ``a`` (B1, 2, 3) and of ``b`` (B2, 2, 3)."""
    x, y = closest_points(a, b)
    return np.linalg.norm(x - y, axis=-1)


def capsules(motion: Motion, limits: Limits = Limits(), world=None):
    """The body as the check sees it: segments (F, B, 2, 3), radii (B,) and each one's two
    joints (B, 2) (:func:`_capsules`)."""
    world = world if world is not None else forward_kinematics(motion)
    return _capsules(motion, world[0], limits, end_site_positions(motion, world))


def interpenetration(a: Motion, b: Motion, limits: Limits = Limits(), world_a=None, world_b=None,
                     touching: tuple = ()) -> list[int]:
    """Frames in which two characters' capsules overlap (both on one timeline).
    ``touching``: (joint of a, joint of b) pairs whose bones may sink :attr:`Limits.touch`
    into each other (an interaction's contact)."""
    wa = world_a if world_a is not None else forward_kinematics(a)
    wb = world_b if world_b is not None else forward_kinematics(b)
    pa, pb = wa[0], wb[0]
    sa, ra, ja = _capsules(a, pa, limits, end_site_positions(a, wa))
    sb, rb, jb = _capsules(b, pb, limits, end_site_positions(b, wb))
    reach = ra[:, None] + rb[None, :]
    for x, y in touching:
        allowed = (ja == x).any(axis=1)[:, None] & (jb == y).any(axis=1)[None, :]
        reach = np.where(allowed, reach - limits.touch, reach)
    frames = []
    for f in range(min(a.frames, b.frames)):
        centre_a, centre_b = pa[f, 0], pb[f, 0]
        if np.linalg.norm((centre_a - centre_b)[[0, 2]]) > 2.5:  # too far apart to touch
            continue
        if (_segment_distances(sa[f], sb[f]) < reach).any():
            frames.append(f)
    return frames


def contact_gap(a: Motion, b: Motion, joint_a: int, joint_b: int, frame: int, limits: Limits = Limits(),
                world_a=None, world_b=None) -> float:
    """How far apart (m) the surfaces of ``joint_a``'s bones on ``a`` and ``joint_b``'s on
    ``b`` are at ``frame`` (negative: sunk into each other)."""
    wa = world_a if world_a is not None else forward_kinematics(a)
    wb = world_b if world_b is not None else forward_kinematics(b)
    sa, ra, ja = _capsules(a, wa[0], limits, end_site_positions(a, wa))
    sb, rb, jb = _capsules(b, wb[0], limits, end_site_positions(b, wb))
    ka, kb = (ja == joint_a).any(axis=1), (jb == joint_b).any(axis=1)
    d = _segment_distances(sa[frame, ka], sb[frame, kb]) - ra[ka][:, None] - rb[kb][None, :]
    return float(d.min())


def reaction_onset(motion: Motion, joint: int, first: int, last: int, limits: Limits = Limits(),
                   world=None) -> int | None:
    """The frame a reaction gets under way between ``first`` and ``last``: going back from
    its ``joint``'s fastest moment (relative to the pelvis) to where it moved slower than
    :attr:`Limits.stir`. None when it never moves that fast."""
    positions = (world if world is not None else forward_kinematics(motion))[0]
    pelvis = guess_roles(motion.skeleton).get("pelvis", 0)
    first, last = max(0, first), min(motion.frames - 1, last)
    if last - first < 2:
        return None
    rel = positions[first:last + 1, joint] - positions[first:last + 1, pelvis]
    speed = np.linalg.norm(np.diff(rel, axis=0), axis=1) / motion.frame_time  # speed[k]: frame k → k + 1
    peak = int(np.argmax(speed))
    if speed[peak] <= limits.stir:
        return None
    k = peak
    while k > 0 and speed[k - 1] > limits.stir:
        k -= 1
    return first + k


def check_world(motion: Motion) -> tuple:
    """The forward kinematics :func:`check` and :func:`check_scene` read (and the report's
    metrics): every joint's position, but the rotations only of the pelvis and the joints
    with End Sites (a long motion's rotations of every joint are never made)."""
    joints = {0, guess_roles(motion.skeleton).get("pelvis", 0), *motion.skeleton.end_sites}
    return kinematics_of(motion, joints, every_position=True)


def check_scene(motions: dict, terrain=None, limits: Limits = Limits(), ground: float | None = 0.0,
                contacts: tuple = (), soles: dict | None = None, worlds: dict | None = None) -> dict:
    """Every character's :class:`Check` with interpenetration against the others; the
    ground is ``terrain``, else the height ``ground`` (None: each motion's own floor, as
    for motion capture). ``contacts`` (:class:`Contact`): the scene's interactions, whose
    contact joints may touch and must meet, and whose reactions must not lead the contact
    (both characters of an interaction get its findings). ``soles``: per character, how high
    its skeleton's feet stand on the floor (:func:`check`'s ``sole``). ``worlds``: each
    motion's forward kinematics, where already worked out (shared with the report's metrics)."""
    from dataclasses import replace

    worlds = {name: (worlds or {}).get(name) or forward_kinematics(m) for name, m in motions.items()}
    out = {name: check(m, terrain, limits, ground=ground if terrain is None else None, world=worlds[name],
                       sole=(soles or {}).get(name, 0.0)) for name, m in motions.items()}
    joints = {name: guess_roles(m.skeleton) for name, m in motions.items()}
    names = list(motions)
    for i, x in enumerate(names):
        for y in names[i + 1:]:
            touching = [(joints[x].get(c.joints[k]), joints[y].get(c.joints[1 - k]))
                        for c in contacts for k in (0, 1) if c.tracks == ((x, y) if k == 0 else (y, x))]
            frames = interpenetration(motions[x], motions[y], limits, worlds[x], worlds[y],
                                      tuple(t for t in touching if None not in t))
            out[x].touching[y] = tuple(frames)
            out[y].touching[x] = tuple(frames)
    for c in contacts:
        ta, tb = c.tracks
        if ta not in motions or tb not in motions:
            continue
        ja, jb = joints[ta].get(c.joints[0]), joints[tb].get(c.joints[1])
        frame = min(int(c.frame), motions[ta].frames - 1, motions[tb].frames - 1)
        missed, gap, leads = (), 0.0, ()
        if ja is not None and jb is not None:
            gap = contact_gap(motions[ta], motions[tb], ja, jb, frame, limits, worlds[ta], worlds[tb])
            missed = (frame,) if gap > limits.contact else ()
        if c.reaction is not None and jb is not None:
            onset = reaction_onset(motions[tb], jb, *c.reaction, limits, worlds[tb])
            leads = tuple(range(onset, frame)) if onset is not None else ()
        for name in (ta, tb):
            got = out[name]
            out[name] = replace(got, missed=got.missed + missed, gap=gap if abs(gap) > abs(got.gap) else got.gap,
                                leads=got.leads + leads)
    return out
