"""Whole-motion edits: resampling to another frame rate and left/right mirroring."""

from __future__ import annotations

import re
from dataclasses import replace

import numpy as np

from doodle.core import quat
from retarget.skeleton import Motion, Skeleton

_SIDES = [(r"Left", "Right"), (r"left", "right"), (r"_L\b", "_R"), (r"_l\b", "_r"), (r"\bL_", "R_"), (r"\bl_", "r_"),
          (r"^L", "R")]


def resample(motion: Motion, fps: float) -> Motion:
    """The motion at ``fps`` frames per second over the same duration: translations
    linearly, rotations by slerp. The last frame keeps the original last pose when the
    duration is a whole number of new frames."""
    if not fps > 0:
        raise ValueError("fps must be positive")
    old_t = np.arange(motion.frames) * motion.frame_time
    span = old_t[-1]
    count = int(np.floor(span * fps + 1e-9)) + 1
    new_t = np.minimum(np.arange(count) / fps, span)
    trans = np.stack([np.stack([np.interp(new_t, old_t, motion.translations[:, j, k]) for k in range(3)], axis=-1)
                      for j in range(len(motion.skeleton))], axis=1)
    if motion.frames == 1:
        rots = motion.rotations.copy()
    else:
        rots = quat.slerp_keys(old_t, motion.rotations, new_t)
    return replace(motion, translations=trans, rotations=rots, frame_time=1.0 / fps)


def mirror_pairs(skeleton: Skeleton) -> np.ndarray:
    """For each joint, its left/right counterpart by name (itself when it has none)."""
    index = {n: i for i, n in enumerate(skeleton.names)}
    pairs = np.arange(len(skeleton))
    for i, name in enumerate(skeleton.names):
        for left, right in _SIDES:
            for a, b in ((left, right), (right, left)):
                other = re.sub(a, b.replace("\\b", ""), name, count=1)
                if other != name and other in index:
                    pairs[i] = index[other]
                    break
            if pairs[i] != i:
                break
    return pairs


def mirror(motion: Motion) -> Motion:
    """The motion reflected through the character's sagittal plane (x → −x, since +x is
    the character's left), with left and right joints exchanged: a right-hand punch
    becomes a left-hand punch. ``mirror(mirror(m))`` is ``m``."""
    sk = motion.skeleton
    pairs = mirror_pairs(sk)
    flip = np.array([-1.0, 1.0, 1.0])
    qflip = np.array([1.0, -1.0, -1.0, 1.0])  # M R M for M = diag(-1, 1, 1)
    offsets = sk.offsets[pairs] * flip
    ends = {j: sk.end_sites[int(pairs[j])] * flip for j in sk.end_sites if int(pairs[j]) in sk.end_sites}
    skeleton = replace(sk, offsets=offsets, end_sites=ends)
    return replace(motion, skeleton=skeleton, translations=motion.translations[:, pairs] * flip,
                   rotations=motion.rotations[:, pairs] * qflip)
