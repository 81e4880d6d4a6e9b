"""Retargeting: a clip moved onto another humanoid skeleton by bone directions.

Two skeletons rarely agree on anything but anatomy: joint counts differ (three spine joints
or two), rest poses differ (a T-pose, or Bandai's rest where every bone lies along +x) and
so do local axis conventions. So nothing is copied as a raw local rotation:

1. **Joints by role** — each skeleton's joints are placed on six chains between the roles
   :func:`retarget.analysis.guess_roles` finds (pelvis→chest, chest→head, chest→each hand,
   pelvis→each foot), at their fraction of the chain's rest length; the joints below a foot
   (toes) by depth. A target joint takes the source joint at the same index of a chain of
   as many joints, else the one nearest in fraction.
2. **A common reference pose** — the target is put in the source's rest pose (the built-in
   humanoid's T-pose): starting from a real pose of the target (``reference``, e.g. the
   first frame of one of its clips, which carries its own twist conventions), each bone is
   turned so it points as the source's does at rest (the pelvis and chest by their up and
   left-to-right axes together).
3. **Rotations as world-space changes** — at each frame a target bone's world rotation is
   the source bone's change from its rest, applied to the target's reference:
   ``Q_t = (Q_s · Q_s,rest⁻¹) · Q_t,ref``; bones point as the source's do, twist included.
   Joints without a counterpart (fingers) keep the reference's local rotation.
4. **Root and ground** — the pelvis follows the source's, scaled by the ratio of leg
   lengths; then the body is lifted or lowered so that where the source's feet touch the
   ground the target's lowest foot point is as high as the source's (between contacts —
   a jump's flight — the correction is interpolated), so the feet stay on the ground.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation

from retarget.analysis import _chain, feet_low, guess_roles
from retarget.skeleton import Motion, Skeleton, forward_kinematics

CHAINS = (("spine", "pelvis", "chest"), ("neck", "chest", "head"), ("left_arm", "chest", "left_hand"),
          ("right_arm", "chest", "right_hand"), ("left_leg", "pelvis", "left_foot"),
          ("right_leg", "pelvis", "right_foot"))
GROUNDED = 0.03  # m: the source's lowest foot point within this of its ground touches it


@dataclass(frozen=True)
class Places:
    """Where each joint of a skeleton lies on the role chains."""

    place: dict  # joint -> (chain, fraction): its first chain, at its share of the chain's rest length
    chains: dict  # chain -> [(joint, fraction)] from the chain's start (included) to its end
    roles: dict  # role -> joint


def _rest_positions(skeleton: Skeleton) -> np.ndarray:
    pos = np.zeros((len(skeleton), 3))
    for j, p in enumerate(skeleton.parents):
        pos[j] = skeleton.offsets[j] + (pos[p] if p >= 0 else 0.0)
    return pos


def places(skeleton: Skeleton, roles: dict | None = None) -> Places:
    """Each joint's chain and fraction (:data:`CHAINS`); toes as chains ``left_foot+1``… by
    depth (``roles``: role → joint, default guessed from the names). Raises ValueError
    naming a role that cannot be found."""
    roles = dict(guess_roles(skeleton) if roles is None else roles)
    missing = [r for c in CHAINS for r in c[1:] if r not in roles]
    if missing:
        raise ValueError(f"cannot tell which joint is the {missing[0].replace('_', ' ')}")
    rest = _rest_positions(skeleton)
    place, chains = {}, {}
    for name, start, end in CHAINS:
        joints = _chain(skeleton, roles[start], roles[end])[::-1]
        lengths = np.linalg.norm(np.diff(rest[joints], axis=0), axis=1)
        fractions = np.concatenate([[0.0], np.cumsum(lengths) / max(float(lengths.sum()), 1e-9)])
        chains[name] = [(j, float(f)) for j, f in zip(joints, fractions)]
        for j, f in chains[name]:
            place.setdefault(j, (name, float(f)))
    for side in ("left_foot", "right_foot"):
        j, depth = roles[side], 0
        while skeleton.children(j):
            j, depth = skeleton.children(j)[0], depth + 1
            place[j] = (f"{side}+{depth}", 0.0)
            chains[f"{side}+{depth}"] = [(j, 0.0)]
    return Places(place, chains, roles)


def joint_map(source: Skeleton, target: Skeleton, roles: dict | None = None) -> dict[int, int]:
    """Target joint → the source joint at the same place: on chains of as many joints, the
    one at the same index; otherwise the one nearest in fraction (the roles onto the roles)."""
    src, tgt = places(source), places(target, roles)
    out = {}
    for j, (chain, f) in tgt.place.items():
        if chain not in src.chains:
            continue
        mine, theirs = tgt.chains[chain], src.chains[chain]
        if len(mine) == len(theirs):
            out[j] = theirs[[k for k, _ in mine].index(j)][0]
        else:
            out[j] = min(theirs, key=lambda kg: (abs(kg[1] - f), kg[1]))[0]
    for role in src.roles:
        if role in tgt.roles:
            out[tgt.roles[role]] = src.roles[role]
    return out


def _next_on_chain(pl: Places, joint: int) -> int | None:
    chain, _ = pl.place[joint]
    joints = [j for j, _ in pl.chains[chain]]
    k = joints.index(joint)
    if k + 1 < len(joints):
        return joints[k + 1]
    toes = pl.chains.get(f"{chain[:-4]}_foot+1") if chain.endswith("_leg") else None
    return toes[0][0] if toes else None


def _axes(skeleton: Skeleton, pl: Places, joint: int, positions: np.ndarray) -> np.ndarray | None:
    """(k, 3) the directions that orient ``joint``: up and left-to-right for the pelvis and
    chest; along its bone (to the next joint on its chain, or the first toe) otherwise."""
    r = pl.roles
    if joint == r["pelvis"]:
        hips = [pl.chains[f"{s}_leg"][1][0] for s in ("left", "right")]
        return np.stack([positions[r["chest"]] - positions[joint], positions[hips[0]] - positions[hips[1]]])
    if joint == r["chest"]:
        shoulders = [pl.chains[f"{s}_arm"][1][0] for s in ("left", "right")]
        return np.stack([positions[r["head"]] - positions[joint], positions[shoulders[0]] - positions[shoulders[1]]])
    after = _next_on_chain(pl, joint) if joint in pl.place else None
    return None if after is None else (positions[after] - positions[joint])[None]


def _align(want: np.ndarray, have: np.ndarray) -> Rotation:
    """The rotation taking the directions ``have`` onto ``want`` (the first one exactly)."""
    want = want / np.linalg.norm(want, axis=1, keepdims=True)
    have = have / np.linalg.norm(have, axis=1, keepdims=True)
    if len(want) == 1:
        axis = np.cross(have[0], want[0])
        s, c = np.linalg.norm(axis), float(have[0] @ want[0])
        if s < 1e-9:
            if c > 0:
                return Rotation.identity()
            perp = np.cross(have[0], [0, 0, 1.0]) if abs(have[0, 2]) < 0.9 else np.cross(have[0], [0, 1.0, 0])
            return Rotation.from_rotvec(np.pi * perp / np.linalg.norm(perp))
        return Rotation.from_rotvec(axis / s * np.arctan2(s, c))
    return Rotation.align_vectors(want, have, weights=[np.inf] + [1.0] * (len(want) - 1))[0]


def reference_pose(source: Skeleton, target: Skeleton, reference: Motion, roles: dict | None = None) -> np.ndarray:
    """(J, 4) world rotations of the target in the source's rest pose, starting from the
    first frame of ``reference`` (a motion on the target skeleton)."""
    src, tgt = places(source), places(target, roles)
    mapping = joint_map(source, target, roles)
    src_rest = _rest_positions(source)
    base_pos, base_rot = (a[0] for a in forward_kinematics(reference.slice(0, 1)))
    correction = [Rotation.identity()] * len(target)
    for j in range(len(target)):
        parent = int(target.parents[j])
        correction[j] = correction[parent] if parent >= 0 else Rotation.identity()
        have = _axes(target, tgt, j, base_pos) if j in mapping else None
        want = _axes(source, src, mapping[j], src_rest) if have is not None else None
        if have is not None and want is not None and len(want) == len(have) and np.all(np.linalg.norm(have, axis=1) > 1e-6):
            correction[j] = _align(want, have)
    return np.stack([(c * Rotation.from_quat(q)).as_quat() for c, q in zip(correction, base_rot)])


def leg_length(skeleton: Skeleton, roles: dict | None = None) -> float:
    """Rest length (m) of the left leg, hip to ankle."""
    pl = places(skeleton, roles)
    joints = [j for j, _ in pl.chains["left_leg"]][1:]
    rest = _rest_positions(skeleton)
    return float(np.linalg.norm(np.diff(rest[joints], axis=0), axis=1).sum())


def retarget(motion: Motion, target: Skeleton, reference: Motion, roles: dict | None = None) -> Motion:
    """``motion`` (on the built-in humanoid, or any skeleton whose rest pose is a T-pose)
    played by the ``target`` skeleton (see the module docstring); ``reference`` is a
    motion on the target whose first frame gives its twist conventions and the rotations
    of joints without a counterpart; ``roles``: the target's role → joint (default: guessed
    from its joint names). Raises ValueError when a role cannot be found."""
    source = motion.skeleton
    mapping = joint_map(source, target, roles)
    pelvis_t, pelvis_s = places(target, roles).roles["pelvis"], places(source).roles["pelvis"]
    src_world = forward_kinematics(motion)
    src_rest_rot = forward_kinematics(Motion(source, source.offsets[None].copy(),
                                             np.tile([0.0, 0.0, 0.0, 1.0], (1, len(source), 1)), 1.0))[1][0]
    ref = reference_pose(source, target, reference, roles)
    frames = motion.frames
    world_rot = np.empty((frames, len(target), 4))
    local = np.empty((frames, len(target), 4))
    base_local = reference.rotations[0]
    above = set(_chain(target, 0, pelvis_t)[1:]) if pelvis_t != 0 else set()  # helpers above the pelvis
    for j in range(len(target)):
        parent = int(target.parents[j])
        if j in above:
            world_rot[:, j] = (0.0, 0.0, 0.0, 1.0)
        elif j in mapping:
            k = mapping[j]
            delta = Rotation.from_quat(src_world[1][:, k]) * Rotation.from_quat(src_rest_rot[k]).inv()
            world_rot[:, j] = (delta * Rotation.from_quat(ref[j])).as_quat()
        else:
            parent_rot = Rotation.from_quat(world_rot[:, parent]) if parent >= 0 else Rotation.identity()
            world_rot[:, j] = (parent_rot * Rotation.from_quat(base_local[j])).as_quat()
        if parent < 0:
            local[:, j] = world_rot[:, j]
        else:
            local[:, j] = (Rotation.from_quat(world_rot[:, parent]).inv() * Rotation.from_quat(world_rot[:, j])).as_quat()
    scale = leg_length(target, roles) / leg_length(source)
    trans = np.broadcast_to(reference.translations[0], (frames, len(target), 3)).copy()
    for a in above:
        trans[:, a] = 0.0
    trans[:, 0] = 0.0
    trans[:, pelvis_t] = src_world[0][:, pelvis_s] * scale
    out = Motion(target, trans, local, motion.frame_time)
    return _grounded(out, motion, src_world, pelvis_t, places(target, roles).roles)


def _grounded(out: Motion, source: Motion, src_world, pelvis: int, roles: dict) -> Motion:
    """``out`` lifted or lowered so its lowest foot point matches the source's where the
    source's feet touch the ground; interpolated in between."""
    src_low = feet_low(source, src_world)
    low = feet_low(out, roles=roles)
    touching = src_low <= src_low.min() + GROUNDED
    frames = np.arange(out.frames)
    lift = np.interp(frames, frames[touching], (src_low - low)[touching])
    trans = out.translations.copy()
    trans[:, pelvis, 1] += lift
    return Motion(out.skeleton, trans, out.rotations, out.frame_time)
