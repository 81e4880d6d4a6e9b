"""Feet that stay where they land: contact pinning with two-bone IK.

Foot skating — a planted foot sliding over the ground — is what blending clips onto a new
path produces; the thesis leaves it to future work (§5.3). Here, after sequencing:

1. contacts are detected per foot on the sequenced motion: near its lowest height and
   slower than a brisk step (1 m/s) — a looser speed bound than clip analysis uses, since
   a sliding planted foot is exactly what must be caught;
2. each contact interval gets one target: where the ankle stood, averaged horizontally over
   the interval, at its lowest height there;
3. every frame of the interval the leg (hip, knee, ankle) is bent and swung analytically so
   the ankle reaches the target (two-bone IK), with the correction faded in and out over a
   few frames at the interval's ends so nothing pops.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from doodle.core import quat
from retarget.analysis import foot_contacts
from retarget.skeleton import Motion, forward_kinematics


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _angle(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(np.sum(_unit(u) * _unit(v), axis=-1), -1.0, 1.0))


def two_bone_ik(motion: Motion, hip: int, knee: int, ankle: int, target: np.ndarray, weight: np.ndarray,
                world: tuple | None = None) -> Motion:
    """The motion with the hip and knee rotated so the ankle reaches ``target`` (F, 3) where
    ``weight`` (F,) is 1 (blended towards it in between, untouched at 0). ``world``: the
    motion's forward kinematics if already known (only this leg's chain must be current)."""
    positions, world = forward_kinematics(motion) if world is None else world
    a, b, c = positions[:, hip], positions[:, knee], positions[:, ankle]
    t = c + (target - c) * weight[:, None]
    lab = np.linalg.norm(b - a, axis=1)
    lcb = np.linalg.norm(b - c, axis=1)
    lat = np.clip(np.linalg.norm(t - a, axis=1), 1e-4, lab + lcb - 1e-4)
    ac_ab_0 = _angle(c - a, b - a)
    ba_bc_0 = _angle(a - b, c - b)
    ac_at_0 = _angle(c - a, t - a)
    ac_ab_1 = np.arccos(np.clip((lcb**2 - lab**2 - lat**2) / (-2 * lab * lat), -1, 1))
    ba_bc_1 = np.arccos(np.clip((lat**2 - lab**2 - lcb**2) / (-2 * lab * lcb), -1, 1))
    axis0 = np.cross(c - a, b - a)
    # a straight leg has no bend plane: bend forward, about the hip's own x axis
    straight = np.linalg.norm(axis0, axis=1) < 1e-9
    axis0[straight] = quat.rotate(world[straight, hip], np.tile([1.0, 0.0, 0.0], (int(straight.sum()), 1)))
    axis0 = _unit(axis0)
    axis1 = np.cross(c - a, t - a)
    axis1 = np.where(np.linalg.norm(axis1, axis=1, keepdims=True) < 1e-12, axis0, _unit(axis1))
    a_inv, b_inv = quat.conjugate(world[:, hip]), quat.conjugate(world[:, knee])
    r0 = quat.exp(quat.rotate(a_inv, axis0) * (ac_ab_1 - ac_ab_0)[:, None])
    r1 = quat.exp(quat.rotate(b_inv, axis0) * (ba_bc_1 - ba_bc_0)[:, None])
    r2 = quat.exp(quat.rotate(a_inv, axis1) * ac_at_0[:, None])
    rots = motion.rotations.copy()
    rots[:, hip] = quat.multiply(quat.multiply(rots[:, hip], r0), r2)
    rots[:, knee] = quat.multiply(rots[:, knee], r1)
    # the foot keeps its orientation in the world (its sole stays on the ground)
    new_hip_world = quat.multiply(world[:, int(motion.skeleton.parents[hip])], rots[:, hip])
    new_knee_world = quat.multiply(new_hip_world, rots[:, knee])
    rots[:, ankle] = quat.multiply(quat.conjugate(new_knee_world), world[:, ankle])
    return replace(motion, rotations=rots)


def _intervals(mask: np.ndarray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


CONTACT_SPEED = 1.0  # m/s: a planted foot, even sliding, moves slower than a stepping one


def planted(motion: Motion, feet: list[int], positions: np.ndarray | None = None, terrain=None,
            height: float = 0.03) -> np.ndarray:
    """(F, len(feet)) bool: each foot near its lowest height above the ground and under
    CONTACT_SPEED."""
    positions = forward_kinematics(motion)[0] if positions is None else positions
    if terrain is None:
        return foot_contacts(motion, feet, speed=CONTACT_SPEED, world=positions)
    foot = positions[:, feet]
    above = foot[:, :, 1] - terrain.height(foot[:, :, [0, 2]])
    speed = np.linalg.norm(np.gradient(foot, motion.frame_time, axis=0), axis=2)
    return (above - above.min(axis=0) <= height) & (speed <= CONTACT_SPEED)


def pin_feet(motion: Motion, feet: list[int], fade: int = 3, terrain=None) -> Motion:
    """The motion with each foot held still over each of its contact intervals."""
    original = forward_kinematics(motion)[0]
    contacts = planted(motion, feet, original, terrain)
    for k, ankle in enumerate(feet):
        knee = int(motion.skeleton.parents[ankle])
        hip = int(motion.skeleton.parents[knee])
        if knee < 0 or hip < 0:
            continue
        positions = original
        contact = contacts[:, k]
        target = positions[:, ankle].copy()
        weight = np.zeros(motion.frames)
        for s, e in _intervals(contact):
            spot = positions[s:e, ankle]
            target[max(0, s - fade): min(motion.frames, e + fade)] = [spot[:, 0].mean(), spot[:, 1].min(),
                                                                      spot[:, 2].mean()]
            weight[s:e] = 1.0
            for k in range(1, fade + 1):  # fade in before and out after
                w = 1.0 - k / (fade + 1)
                if s - k >= 0:
                    weight[s - k] = max(weight[s - k], w)
                if e - 1 + k < motion.frames:
                    weight[e - 1 + k] = max(weight[e - 1 + k], w)
        if weight.any():
            motion = two_bone_ik(motion, hip, knee, ankle, target, weight)
    return motion


def clamp_to_ground(motion: Motion, terrain=None) -> Motion:
    """The motion raised, frame by frame, so no joint or End Site is below the ground
    (``terrain``; flat y = 0 when None); the lift is eased in and out over a few frames."""
    from scipy.ndimage import gaussian_filter1d, maximum_filter1d

    from retarget.skeleton import end_site_positions

    world = forward_kinematics(motion)
    points = [world[0]] + [end[:, None] for end in end_site_positions(motion, world).values()]
    points = np.concatenate(points, axis=1)
    ground = 0.0 if terrain is None else terrain.height(points[:, :, [0, 2]])
    lift = np.maximum(0.0, np.max(ground - points[:, :, 1], axis=1))
    if not lift.any():
        return motion
    lift = np.maximum(gaussian_filter1d(maximum_filter1d(lift, 5), 1.5), lift)
    trans = motion.translations.copy()
    trans[:, 0, 1] += lift
    return replace(motion, translations=trans)
