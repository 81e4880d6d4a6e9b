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

import numpy as np

from doodle.core.arap import deform
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
