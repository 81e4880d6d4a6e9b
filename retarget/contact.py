"""Contact: an arm bent so its hand meets a target at one frame (the contact of a slap, a
handshake…), eased in and out around it — the adaptation of an independent clip to a contact
constraint (thesis §6.2.2). The thesis deforms the clip as-rigidly-as-possible (eq. 6.4–6.7);
here the arm's two-bone chain is solved analytically (:func:`retarget.feet.two_bone_ik`) with
a cosine-eased weight, which reaches the target exactly when it is within the arm's reach
and leaves the rest of the body and of the clip untouched.
"""

from __future__ import annotations

import numpy as np

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


def reach(motion: Motion, target, frame: int, side: str = "right", ease_s: float = EASE_S) -> Motion:
    """``motion`` with the ``side`` hand at ``target`` (world, metres) at ``frame``."""
    shoulder, elbow, hand = arm_chain(motion, side)
    frame = int(np.clip(frame, 0, motion.frames - 1))
    weight = contact_weight(motion.frames, frame, int(round(ease_s / motion.frame_time)))
    world = forward_kinematics(motion)
    goal = np.broadcast_to(np.asarray(target, dtype=float), (motion.frames, 3)).copy()
    # follow the clip's own hand path shifted by the correction at the contact frame
    goal = world[0][:, hand] + (goal[frame] - world[0][frame, hand])
    return two_bone_ik(motion, shoulder, elbow, hand, goal, weight, world=world)
