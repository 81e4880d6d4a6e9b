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


GAMMA = 1e4  # weight of the contact term of eq. 6.7 against the shape terms
STAY = 1e-3  # a little weight on staying put: (α, β) do not see a twist about A_i


def local_coordinates(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(α_i, β_i)`` of the interior points of a path (n, 3) in their neighbours' frame
    (eq. 6.4–6.6): n − 2 values each."""
    d = p[1:-1] - p[:-2]
    a = p[2:] - p[:-2]
    a = a / np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-9)
    return np.sum(d * a, axis=1), np.linalg.norm(np.cross(d, a), axis=1)


def arap_path(path: np.ndarray, frame: int, target, lo: int, hi: int) -> np.ndarray:
    """The path (n, 3) with ``path[frame]`` moved to ``target`` and the points between
    ``lo`` and ``hi`` (kept fixed) moved as rigidly as possible (eq. 6.7)."""
    from scipy.optimize import least_squares

    path = np.asarray(path, dtype=float)
    lo, hi = max(0, lo), min(len(path) - 1, hi)
    if not lo < frame < hi:
        out = path.copy()
        out[frame] = target
        return out
    window = path[lo:hi + 1]
    alpha0, beta0 = local_coordinates(window)
    c = frame - lo

    def residuals(x):
        p = window.copy()
        p[1:-1] = x.reshape(-1, 3)
        alpha, beta = local_coordinates(p)
        return np.concatenate([alpha - alpha0, beta - beta0, np.sqrt(GAMMA) * (p[c] - target),
                               np.sqrt(STAY) * (p[1:-1] - window[1:-1]).ravel()])

    start = window[1:-1] + (np.asarray(target) - window[c]) * contact_weight(len(window), c, c if c else 1)[1:-1,
                                                                                                           None]
    solved = least_squares(residuals, start.ravel(), method="lm", xtol=1e-10, ftol=1e-10)
    out = path.copy()
    out[lo + 1:hi] = solved.x.reshape(-1, 3)
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
