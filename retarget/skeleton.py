"""Skeletons and motions as plain arrays.

A :class:`Skeleton` is a joint tree: names, parent indices (``-1`` for the root; parents
always come before their children), rest offsets from the parent, each joint's BVH channel
layout, and End Sites. A :class:`Motion` is a skeleton animated at a frame rate: per frame
and joint a local translation (the rest offset for joints without position channels; the
root's position for the root) and a local rotation quaternion ``(x, y, z, w)``.

Units: lengths are in metres inside the project (``read_bvh`` scales file units); angles
are quaternions. World frame: right-handed, +y up.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field, replace
from functools import lru_cache, wraps

import numpy as np

from doodle.core import quat

POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
ROTATION_CHANNELS = ("Xrotation", "Yrotation", "Zrotation")


@dataclass(frozen=True, eq=False)
class Skeleton:
    """A BVH skeleton: joint names, parents, rest offsets, channels and End Sites."""

    names: tuple[str, ...]
    parents: np.ndarray  # (J,) int, -1 for the root, parents[j] < j
    offsets: np.ndarray  # (J, 3) rest offset from the parent, metres
    channels: tuple[tuple[str, ...], ...]  # per joint, BVH channel names in file order
    end_sites: dict = field(default_factory=dict)  # joint index -> (3,) End Site offset, metres

    def __post_init__(self) -> None:
        n = len(self.names)
        if self.parents.shape != (n,) or self.offsets.shape != (n, 3) or len(self.channels) != n:
            raise ValueError("skeleton arrays do not agree in length")
        if n and (self.parents[0] != -1 or np.any(self.parents[1:] >= np.arange(1, n)) or np.any(self.parents[1:] < 0)):
            raise ValueError("joints must be ordered parents first, with a single root at index 0")

    def __len__(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(f"no joint {name!r} in the skeleton") from None

    def children(self, j: int) -> list[int]:
        return [int(c) for c in np.flatnonzero(self.parents == j)]

    def subtree(self, j: int) -> list[int]:
        """Joint ``j`` and every joint below it (parents come first, so one pass finds them)."""
        inside = np.zeros(len(self.names), dtype=bool)
        inside[j] = True
        for k in range(j + 1, len(self.names)):
            inside[k] = inside[self.parents[k]]
        return [int(k) for k in np.flatnonzero(inside)]


@dataclass(frozen=True, eq=False)
class Motion:
    """An animation of a skeleton: each frame's local translations and rotations."""

    skeleton: Skeleton
    translations: np.ndarray  # (F, J, 3) local translation of each joint, metres
    rotations: np.ndarray  # (F, J, 4) local rotation quaternions xyzw
    frame_time: float  # seconds per frame, exactly as given (no rounding of the rate)

    def __post_init__(self) -> None:
        f, j = self.rotations.shape[:2]
        if self.translations.shape != (f, j, 3) or self.rotations.shape != (f, j, 4) or j != len(self.skeleton):
            raise ValueError("motion arrays do not agree with each other or with the skeleton")

    @property
    def frames(self) -> int:
        return len(self.rotations)

    @property
    def fps(self) -> float:
        return 1.0 / self.frame_time

    @property
    def duration(self) -> float:
        return self.frames * self.frame_time

    @property
    def root(self) -> np.ndarray:
        """(F, 3) root position."""
        return self.translations[:, 0]

    def slice(self, start: int, stop: int) -> "Motion":
        """Frames ``[start, stop)``."""
        return replace(self, translations=self.translations[start:stop], rotations=self.rotations[start:stop])


def per_motion(fn):
    """``fn(motion, *args)`` worked out once per motion and arguments and kept for as long as
    the motion lives (a :class:`weakref.WeakKeyDictionary`; motions are never changed in
    place, so it stays true). For small results read in several passes over a compile's
    clips (a clip's travel curve, its joints' speeds), where a recency cache of the clips'
    forward kinematics would be long gone by the next pass. Arrays come back read-only."""
    memo: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()

    @wraps(fn)
    def kept(motion: "Motion", *args):
        known = memo.get(motion)
        if known is None:
            known = memo[motion] = {}
        if args not in known:
            out = fn(motion, *args)
            if isinstance(out, np.ndarray):
                out.flags.writeable = False
            known[args] = out
        return known[args]

    kept.cache_clear = memo.clear
    return kept


FK_CACHED = 20_000  # joint-frames: motions up to this size (a clip: ~2,000) keep their forward kinematics


def forward_kinematics(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """World positions (F, J, 3) and world rotations (F, J, 4) of every joint.

    A compile asks for the same clip's many times (its span, entry phase, timing, stylising:
    ~290 calls on 94 motions for a minute of doodle); a motion of up to :data:`FK_CACHED`
    joint-frames keeps its result (the 64 most recent), returned read-only — copy before
    changing it. Motions are never changed in place, so the result stays true."""
    if motion.frames * len(motion.skeleton) <= FK_CACHED:
        return _kept_kinematics(motion)
    return _kinematics(motion)


@lru_cache(maxsize=64)
def _kept_kinematics(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    positions, rotations = _kinematics(motion)
    positions.flags.writeable = False
    rotations.flags.writeable = False
    return positions, rotations


FK_BLOCK = 4096  # frames worked out at once: the temporaries stay small (and in the cache) at any length


def _kinematics(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """World positions and (normalised) rotations, joints a depth level at a time and frames
    in blocks of :data:`FK_BLOCK`, each component a contiguous row: the same arithmetic,
    in the same order, as composing joint by joint with :func:`doodle.core.quat.multiply`
    and :func:`~doodle.core.quat.rotate` (bit for bit), at a cost per frame that does not
    grow with the motion's length."""
    f, j = motion.frames, len(motion.skeleton)
    positions = np.empty((f, j, 3))
    rotations = np.empty((f, j, 4))
    levels = _levels(motion.skeleton)
    for a in range(0, f, FK_BLOCK):
        b = min(a + FK_BLOCK, f)
        pos, rot = _kinematics_block(motion.translations[a:b], motion.rotations[a:b], levels)
        positions[a:b] = pos.transpose(2, 1, 0)
        rotations[a:b] = rot.transpose(2, 1, 0)
        rotations[a:b] /= np.linalg.norm(rotations[a:b], axis=-1, keepdims=True)  # in place, block by block
    return positions, rotations


class Joints:
    """World positions or rotations (:func:`kinematics_of`) of some joints only, read as the
    whole (F, J, ·) array is read: ``a[:, j]`` and ``a[:, j, k]`` (any other joint is a KeyError)."""

    def __init__(self, columns: dict, joints: int):
        self.columns = columns  # joint -> (F, ·)
        self.joints = joints  # J: a negative joint counts from the end, as in the array

    def __getitem__(self, key):
        rows, joint, *rest = key
        if rows != slice(None):
            raise IndexError("Joints are read a whole joint at a time: a[:, j]")
        column = self.columns[int(joint) % self.joints]
        return column[(slice(None), *rest)] if rest else column


def kinematics_of(motion: Motion, joints, every_position: bool = False) -> tuple:
    """:func:`forward_kinematics` of ``joints`` only (their world positions and rotations,
    bit for bit the same), worked out in blocks of frames: a long motion's foot pinning
    needs its legs', not the (F, J, 7) of every joint. ``every_position``: the positions
    of every joint (the whole (F, J, 3) array), the rotations still only of ``joints``."""
    joints = sorted({int(j) for j in joints})
    f, j = motion.frames, len(motion.skeleton)
    everywhere = np.empty((f, j, 3)) if every_position else None
    positions = {} if every_position else {k: np.empty((f, 3)) for k in joints}
    rotations = {k: np.empty((f, 4)) for k in joints}
    levels = _levels(motion.skeleton)
    for a in range(0, f, FK_BLOCK):
        b = min(a + FK_BLOCK, f)
        pos, rot = _kinematics_block(motion.translations[a:b], motion.rotations[a:b], levels)
        block = np.empty((b - a, j, 4))
        block[:] = rot.transpose(2, 1, 0)
        block /= np.linalg.norm(block, axis=-1, keepdims=True)  # as _kinematics normalises
        if every_position:
            everywhere[a:b] = pos.transpose(2, 1, 0)
        for k in joints:
            if not every_position:
                positions[k][a:b] = pos[:, k].T
            rotations[k][a:b] = block[:, k]
    return everywhere if every_position else Joints(positions, j), Joints(rotations, j)


def _kinematics_block(translations: np.ndarray, rotations: np.ndarray, levels) -> tuple[np.ndarray, np.ndarray]:
    """Unnormalised world positions (3, J, F) and rotations (4, J, F) of frames (F, J, ·)."""
    local_t = np.ascontiguousarray(translations.transpose(2, 1, 0))
    local_r = np.ascontiguousarray(rotations.transpose(2, 1, 0))
    pos = np.empty_like(local_t)
    rot = np.empty_like(local_r)
    pos[:, 0] = local_t[:, 0]
    rot[:, 0] = local_r[:, 0]
    for idx, par in levels:
        ax, ay, az, aw = rot[:, par]  # the parents' world rotations (as quat.multiply's a, quat.rotate's q)
        bx, by, bz, bw = local_r[:, idx]
        rot[0, idx] = aw * bx + ax * bw + ay * bz - az * by
        rot[1, idx] = aw * by - ax * bz + ay * bw + az * bx
        rot[2, idx] = aw * bz + ax * by - ay * bx + az * bw
        rot[3, idx] = aw * bw - ax * bx - ay * by - az * bz
        ux, uy, uz = local_t[:, idx]
        tx = 2.0 * (ay * uz - az * uy)
        ty = 2.0 * (az * ux - ax * uz)
        tz = 2.0 * (ax * uy - ay * ux)
        px, py, pz = pos[:, par]
        pos[0, idx] = px + (ux + aw * tx + (ay * tz - az * ty))
        pos[1, idx] = py + (uy + aw * ty + (az * tx - ax * tz))
        pos[2, idx] = pz + (uz + aw * tz + (ax * ty - ay * tx))
    return pos, rot


@lru_cache(maxsize=32)
def _levels(skeleton: Skeleton) -> list[tuple[np.ndarray, np.ndarray]]:
    """(joints, their parents) per depth below the root, root's children first."""
    depth = np.zeros(len(skeleton), dtype=int)
    for k in range(1, len(skeleton)):
        depth[k] = depth[skeleton.parents[k]] + 1
    return [(np.flatnonzero(depth == d), skeleton.parents[depth == d].astype(np.intp))
            for d in range(1, int(depth.max(initial=0)) + 1)]


def end_site_positions(motion: Motion, world: tuple[np.ndarray, np.ndarray] | None = None,
                       joints=None) -> dict[int, np.ndarray]:
    """World positions (F, 3) of each End Site, by its joint (only those of ``joints``, if given)."""
    positions, rotations = world if world is not None else forward_kinematics(motion)
    # the offset turned by the rotation matrix, scipy's Rotation.apply to the bit: a compile's
    # output follows these positions to the last printed digit (quat.rotate differs in the last bit)
    return {j: positions[:, j] + np.einsum("ijk,k->ij", quat.as_matrix(rotations[:, j]), off)
            for j, off in motion.skeleton.end_sites.items() if joints is None or j in joints}


def body_points(motion: Motion, world: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """(F, joints + End Sites, 3): every point of the body — the End Sites too (fingertips,
    toes, the top of the head), which a turning hand or foot sweeps faster than its joint."""
    world = world if world is not None else forward_kinematics(motion)
    ends = end_site_positions(motion, world)
    return np.concatenate([world[0]] + [e[:, None] for e in ends.values()], axis=1)
