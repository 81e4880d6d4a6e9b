"""Transition points between two clips (thesis §5.3.1).

Every frame of the source clip S is compared with every frame of the target clip T by the
distance between feature vectors — for every joint its position (relative to the pelvis,
with the pelvis's heading removed), velocity, acceleration and jerk, after Kovar et al.
2002 — giving a distance map. Transitions are taken at local minima of the map, and among
them the one nearest to the time pair the stage policies ask for:

* the target is entered at the middle of its preparation (``p_t/2``), else of its
  anticipation (``a_t/2``), else at its start;
* the source is left in the middle of its transition stage (``(t_s + f_s)/2``), else at the
  end of its follow-through (``f_s``), else at its end;

so that no transition cuts an execution stage.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from doodle.core import quat
from doodle.core.filters import minimum_filter
from retarget.analysis import Stages
from retarget.skeleton import Motion, forward_kinematics

DERIVATIVE_WEIGHTS = (1.0, 0.1, 0.01, 0.001)  # position, velocity, acceleration, jerk (per s^k)


def frame_features(motion: Motion, pelvis: int) -> np.ndarray:
    """(F, D) per-frame features: pelvis-relative joint positions in the pelvis's heading
    frame, and their first three time derivatives, weighted to comparable scales. Computed
    once per clip (a scene transitions between the same few clips many times); read-only."""
    return _frame_features(motion, int(pelvis))


@lru_cache(maxsize=64)  # bounded: a long clip's features are about a megabyte
def _frame_features(motion: Motion, pelvis: int) -> np.ndarray:
    positions, rotations = forward_kinematics(motion)
    rel = positions - positions[:, pelvis : pelvis + 1]
    forward = quat.front(rotations[:, pelvis])
    yaw = np.arctan2(forward[:, 0], forward[:, 2])
    c, s = np.cos(yaw)[:, None], np.sin(yaw)[:, None]  # turned by −yaw about y, every frame at once
    rel = np.stack([c * rel[..., 0] - s * rel[..., 2], rel[..., 1], s * rel[..., 0] + c * rel[..., 2]], axis=-1)
    feats = [rel]
    for _ in range(3):
        feats.append(np.gradient(feats[-1], motion.frame_time, axis=0) if motion.frames > 1 else feats[-1] * 0)
    out = np.concatenate([w * f.reshape(motion.frames, -1) for w, f in zip(DERIVATIVE_WEIGHTS, feats)], axis=1)
    out.flags.writeable = False
    return out


def distance_map(source: Motion, target: Motion, pelvis_s: int, pelvis_t: int) -> np.ndarray:
    """(Fs, Ft) Euclidean distances between the frames' feature vectors."""
    a, b = frame_features(source, pelvis_s), frame_features(target, pelvis_t)
    d2 = (a * a).sum(1)[:, None] + (b * b).sum(1)[None, :] - 2 * a @ b.T
    return np.sqrt(np.maximum(d2, 0.0))


def policy_frames(s: Stages, t: Stages) -> tuple[float, float]:
    """The (source, target) frame pair the stage policies aim for."""
    if t.preparation > 0:
        tt = t.preparation / 2
    elif t.anticipation > 0:
        tt = t.anticipation / 2
    else:
        tt = 0.0
    if s.transition > s.follow_through > s.execution:
        ts = (s.transition + s.follow_through) / 2
    elif s.follow_through > s.execution:
        ts = float(s.follow_through)
    else:
        ts = float(s.transition)
    return ts, tt


def transition_point(source: Motion, target: Motion, s: Stages, t: Stages, pelvis_s: int = 0,
                     pelvis_t: int = 0) -> tuple[int, int]:
    """Frames (i, j): leave the source at its frame i and enter the target at its frame j —
    the local minimum of the distance map nearest the policies' pair, never inside either
    clip's execution stage."""
    d = distance_map(source, target, pelvis_s, pelvis_t)
    minima = np.argwhere(d <= minimum_filter(d, size=3, mode="nearest"))
    ok = (minima[:, 0] >= s.execution) & (minima[:, 1] <= t.anticipation)
    candidates = minima[ok] if ok.any() else minima
    ts, tt = policy_frames(s, t)
    scale = np.array([max(source.frames, 1), max(target.frames, 1)], dtype=float)
    near = np.linalg.norm((candidates - [ts, tt]) / scale, axis=1)
    i, j = candidates[int(np.argmin(near))]
    return int(i), int(j)
