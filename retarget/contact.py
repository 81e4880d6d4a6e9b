"""Contact: an arm bent so its hand meets a target at one frame (the contact of a slap, a
handshake…) — the adaptation of an independent clip to a contact constraint (thesis §6.2.2).

The hand's trajectory around the contact is deformed *as rigidly as possible* (eq. 6.4–6.7):
every point ``p_i`` is written in its neighbours' frame, ``p_i = p_{i−1} + α_i A_i + β_i B_i``
with ``A_i`` the unit ``p_{i+1} − p_{i−1}`` (eq. 6.4–6.6), and the new trajectory keeps each
``(α_i, β_i)`` while its contact point meets the target (eq. 6.7, cost
``Σ ‖(α, β)₀ − (α, β)‖² + γ ‖p_c − target‖²``, solved by least squares — the thesis uses
gradient descent — over :data:`EASE_S` either side of the contact, the window's ends
fixed). The arm's two-bone chain (:func:`retarget.feet.two_bone_ik`) then follows the new
path, which reaches the target exactly when it is within the arm's reach and leaves the rest
of the body and of the clip untouched.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from doodle.core import quat
from doodle.core.arap import deform
from doodle.core.filters import gaussian_filter1d
from retarget.analysis import guess_roles
from retarget.feet import two_bone_ik
from retarget.skeleton import Motion, forward_kinematics

EASE_S = 0.25  # seconds over which the arm eases into and out of the contact


def arm_chain(motion: Motion, side: str = "right") -> tuple[int, int, int]:
    """(upper arm, forearm, hand) joints of the ``side`` arm, from the hand's role."""
    roles = guess_roles(motion.skeleton)
    hand = roles.get(f"{side}_hand")
    if hand is None:
        raise ValueError(f"no {side} hand found in the skeleton")
    elbow = int(motion.skeleton.parents[hand])
    shoulder = int(motion.skeleton.parents[elbow])
    if elbow < 0 or shoulder < 0:
        raise ValueError(f"the {side} hand has no two-bone arm above it")
    return shoulder, elbow, hand


def contact_weight(frames: int, frame: int, ease: int) -> np.ndarray:
    """1 at ``frame``, cosine-eased to 0 over ``ease`` frames either side, 0 elsewhere."""
    k = np.arange(frames)
    d = np.abs(k - frame) / max(ease, 1)
    return np.where(d < 1.0, 0.5 + 0.5 * np.cos(np.pi * np.minimum(d, 1.0)), 0.0)


def arap_path(path: np.ndarray, frame: int, target, lo: int, hi: int) -> np.ndarray:
    """The path (n, 3) with ``path[frame]`` moved to ``target`` and the points between
    ``lo`` and ``hi`` (kept fixed) moved as rigidly as possible (eq. 6.7,
    :func:`doodle.core.arap.deform`)."""
    path = np.asarray(path, dtype=float)
    lo, hi = max(0, lo), min(len(path) - 1, hi)
    out = path.copy()
    if not lo < frame < hi:
        out[frame] = target
        return out
    window = path[lo:hi + 1]
    c = frame - lo
    start = window + (np.asarray(target) - window[c]) * contact_weight(len(window), c, c)[:, None]
    out[lo:hi + 1] = deform(window, {c: np.asarray(target, dtype=float)}, start)
    return out


def reach(motion: Motion, target, frame: int, side: str = "right", ease_s: float = EASE_S) -> Motion:
    """``motion`` with the ``side`` hand at ``target`` (world, metres) at ``frame``, its path
    around the contact deformed as rigidly as possible (:func:`arap_path`)."""
    shoulder, elbow, hand = arm_chain(motion, side)
    frame = int(np.clip(frame, 0, motion.frames - 1))
    ease = int(round(ease_s / motion.frame_time))
    world = forward_kinematics(motion)
    goal = arap_path(world[0][:, hand], frame, np.asarray(target, dtype=float), frame - ease, frame + ease)
    weight = (np.abs(np.arange(motion.frames) - frame) < ease).astype(float)
    return two_bone_ik(motion, shoulder, elbow, hand, goal, weight, world=world)


def facing_frame(motion: Motion, world=None) -> np.ndarray:
    """(F, 3, 3) per frame the pelvis's ground frame — columns right, up, front — from the
    root's heading (a clip faces +z; its right is −x)."""
    rotations = (world if world is not None else forward_kinematics(motion))[1]
    front = quat.front(rotations[:, 0]) * [1.0, 0.0, 1.0]
    front /= np.maximum(np.linalg.norm(front, axis=1, keepdims=True), 1e-9)
    up = np.tile([0.0, 1.0, 0.0], (len(front), 1))
    return np.stack([np.cross(front, up), up, front], axis=2)


def body_offset(motion: Motion, joint: int, frame: int, world=None) -> np.ndarray:
    """``joint`` at ``frame`` relative to the root's start on the ground, in the root's
    ground frame: (right, up, front) metres."""
    world = world if world is not None else forward_kinematics(motion)
    positions = world[0]
    axes = facing_frame(motion, world)[frame]
    d = positions[frame, joint] - positions[0, 0] * [1.0, 0.0, 1.0]
    return d @ axes


def contact_frame(motion: Motion, stages, joint: int, world=None) -> int:
    """The clip frame its contact happens at: within its execution stage, the frame whose
    ``joint`` (the slapping hand, the kissing head) reaches farthest forward."""
    world = world if world is not None else forward_kinematics(motion)
    lo, hi = stages.bounds()["execution"]
    hi = min(max(hi, lo + 1), motion.frames)
    forward = [body_offset(motion, joint, f, world)[2] for f in range(lo, hi)]
    return lo + int(np.argmax(forward))


def playing_frame(motion: Motion, clip: Motion, clip_frame: int, first: int, last: int) -> int:
    """The frame of ``motion`` between ``first`` and ``last`` that plays ``clip``'s frame
    ``clip_frame``: the one whose joints' local rotations (the root's left out) are nearest
    the clip's there."""
    first, last = max(0, first), min(motion.frames - 1, max(first, last))
    want = clip.rotations[clip_frame, 1:]
    have = motion.rotations[first:last + 1, 1:]
    dots = np.abs(np.sum(have * want[None], axis=-1)).clip(0.0, 1.0)
    return first + int(np.argmin(np.sum(np.arccos(dots), axis=1)))


def retimed(motion: Motion, first: int, last: int, at: int, to: int) -> Motion:
    """``motion`` with what it plays at frame ``at`` played at frame ``to`` instead, the
    frames between ``first`` and ``last`` (kept) stretched and squeezed piecewise linearly
    around it (a reaction timed to its cause)."""
    first, last = max(0, first), min(motion.frames - 1, last)
    if not first < to < last or not first < at < last or at == to:
        return motion
    frames = np.arange(first, last + 1, dtype=float)
    source = np.interp(frames, [first, to, last], [first, at, last])
    k = np.minimum(np.floor(source).astype(int), motion.frames - 2)
    w = (source - k)[:, None, None]
    trans = motion.translations.copy()
    rots = motion.rotations.copy()
    trans[first:last + 1] = motion.translations[k] * (1 - w) + motion.translations[k + 1] * w
    a, b = motion.rotations[k], motion.rotations[k + 1]
    b = np.where(np.sum(a * b, axis=-1, keepdims=True) < 0, -b, b)
    q = a * (1 - w) + b * w
    rots[first:last + 1] = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return replace(motion, translations=trans, rotations=rots)


def apart(motion: Motion, other: Motion, touching: tuple = (), rounds: int = 8, margin: float = 0.015,
          sigma: float = 2.0, vertical: float = 0.0) -> Motion:
    """``motion`` with its arms bent out of ``other``'s body wherever the animation check's
    capsules (:func:`retarget.qa.capsules`) overlap — an arm's bones pushed off by the
    overlap plus ``margin``, the push eased over a few frames (a Gaussian of ``sigma``
    frames) and followed by the arm's two-bone chain. ``touching``: (joint of motion, joint
    of other) contact pairs allowed to touch (:attr:`retarget.qa.Limits.touch`).
    ``vertical`` (+1 over, −1 under): two embracing characters' arms pass one over the
    other's instead of being pushed out sideways."""
    from retarget.qa import Limits, capsules, closest_points

    limits = Limits()
    so, ro, jo = capsules(other, limits)
    arms = {side: arm_chain(motion, side) for side in ("left", "right") if guess_roles(motion.skeleton).get(f"{side}_hand") is not None}
    base = forward_kinematics(motion)
    offsets = {side: np.zeros((motion.frames, 3)) for side in arms}
    out = motion
    for _ in range(rounds):
        sm, rm, jm = capsules(out, limits)
        allowed = np.zeros((len(rm), len(ro)))
        for x, y in touching:
            allowed += ((jm == x).any(axis=1)[:, None] & (jo == y).any(axis=1)[None, :]) * limits.touch
        pushed = False
        for side, (shoulder, elbow, hand) in arms.items():
            mine = np.flatnonzero(np.isin(jm, [elbow, hand]).any(axis=1))
            push = np.zeros((motion.frames, 3))
            for f in range(min(motion.frames, other.frames)):
                pa, pb = closest_points(sm[f, mine], so[f])
                d = np.linalg.norm(pa - pb, axis=-1)
                depth = rm[mine][:, None] + ro[None, :] - allowed[mine] - d
                k = np.unravel_index(np.argmax(depth), depth.shape)
                if depth[k] > 0:
                    away = (pa[k] - pb[k]) / max(float(d[k]), 1e-9)
                    if vertical and ro[k[1]] <= limits.limb:  # an arm against an arm: over or under it
                        away = away + vertical * np.array([0.0, 1.0, 0.0])
                        away /= max(float(np.linalg.norm(away)), 1e-9)
                    push[f] = away * (depth[k] + margin)
            if np.any(push):
                pushed = True
                offsets[side] += gaussian_filter1d(push, sigma, axis=0, mode="nearest") * np.sqrt(2 * np.pi) * sigma / 2
        if not pushed:
            break
        out = motion
        for side, (shoulder, elbow, hand) in arms.items():
            if np.any(offsets[side]):
                size = np.linalg.norm(offsets[side], axis=1)
                weight = np.clip(size / 0.005, 0.0, 1.0)
                out = two_bone_ik(out, shoulder, elbow, hand, base[0][:, hand] + offsets[side], weight)
    return out
