"""An action's clips, loaded and analysed: motion, roles, stages, cycle length, contacts,
and the direction they travel in.

A clip is put on the floor on loading — its floor, the 2nd percentile of its lowest foot
point (as :mod:`retarget.qa` reads motion capture), at y = 0: Bandai's toe joints rest 4 cm
up — and turned to face +z (the character frame's front), whatever way its
performer faced in the capture (Bandai's ``walk-left`` faces 80° left): the trajectory
transfer turns a clip by its direction of travel (``Span.travel_yaw``), which then means
the direction relative to where the body faces, and a clip entered from another one does
not turn the body by the difference of the two captures' headings.

An action the output skeleton has no fitting clip of (none, or only clips travelling the
wrong way, :func:`fits`) plays the built-in clip retargeted onto that skeleton
(:func:`retargeted`, :mod:`retarget.transfer_skeleton`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doodle.core import quat
from doodle.core.errors import DoodleError
from library.manifest import ROLES, ActionDef, Library
from retarget.analysis import (Stages, cycle_length, facing_yaw, feet_low, foot_contacts, guess_roles, stages,
                               travel_yaw)
from retarget.bvh import read_bvh
from retarget.skeleton import Motion, Skeleton, forward_kinematics


@dataclass(frozen=True, eq=False)
class Clip:
    """A library clip as the compile uses it: on the floor, facing front, analysed."""

    action: str
    path: str
    motion: Motion
    roles: dict  # role -> joint index
    stages: Stages
    cycle_length: float | None  # metres per cycle, cyclic actions only
    contacts: np.ndarray  # (F, 2) left and right foot in contact
    travel: float | None = None  # rad about +y: where the clip travels relative to its facing (None: on the spot)
    retargeted: bool = False  # a built-in clip moved onto another skeleton


def resolve_roles(motion: Motion, named: dict, where: str) -> dict[str, int]:
    """Role → joint index: the manifest's names, else guessed from joint names."""
    roles = guess_roles(motion.skeleton)
    for role, joint in named.items():
        try:
            roles[role] = motion.skeleton.index(joint)
        except KeyError:
            raise DoodleError(f"{where}: skeleton.{role}: no joint {joint!r} in the clip "
                              f"(joints: {', '.join(motion.skeleton.names)})") from None
    missing = [r for r in ROLES if r not in roles]
    if missing:
        raise DoodleError(f"{where}: cannot tell which joint is the {missing[0].replace('_', ' ')}; "
                          f"name it in the manifest's [skeleton] table")
    return roles


FRONT_TOLERANCE = np.radians(1.0)  # a clip facing within this of +z is left as it is (the built-in ones)
FIT = np.radians(45.0)  # a clip fits an action whose travel direction is within this of its own


def face_front(motion: Motion) -> Motion:
    """The motion turned about the vertical through the origin so that it faces +z
    (:func:`retarget.analysis.facing_yaw`). The turn goes into the pelvis (helper joints
    above it, like Bandai's ``joint_Root``, are replaced by the path when sequenced)."""
    yaw = facing_yaw(motion)
    if abs(yaw) <= FRONT_TOLERANCE:
        return motion
    turn = quat.exp(np.array([0.0, -yaw, 0.0]))
    pelvis = guess_roles(motion.skeleton).get("pelvis", 0)
    parent = int(motion.skeleton.parents[pelvis])
    trans, rots = motion.translations.copy(), motion.rotations.copy()
    local = motion.rotations[:, pelvis]
    if parent < 0:
        trans[:, pelvis] = quat.rotate(turn, motion.translations[:, pelvis])
        rots[:, pelvis] = quat.compose(turn, local)
    else:
        positions, world = forward_kinematics(motion)
        up_pos, up_rot = positions[:, parent], quat.unit(world[:, parent])
        at = up_pos + quat.rotate(up_rot, motion.translations[:, pelvis])
        trans[:, pelvis] = quat.rotate_inverse(up_rot, quat.rotate(turn, at) - up_pos)
        rots[:, pelvis] = quat.compose(quat.conjugate(up_rot), turn, up_rot, local)
    return Motion(motion.skeleton, trans, rots, motion.frame_time)


def on_floor(motion: Motion) -> Motion:
    """The motion lowered or lifted so its floor is at y = 0 (see the module docstring);
    a clip within a millimetre of it is left as it is (the built-in ones)."""
    floor = float(np.percentile(feet_low(motion), 2))
    if abs(floor) <= 1e-3:
        return motion
    pelvis = guess_roles(motion.skeleton).get("pelvis", 0)
    parent = int(motion.skeleton.parents[pelvis])
    down = np.array([0.0, -floor, 0.0])
    trans = motion.translations.copy()
    if parent < 0:
        trans[:, pelvis] += down
    else:
        trans[:, pelvis] += quat.rotate_inverse(quat.unit(forward_kinematics(motion)[1][:, parent]), down)
    return Motion(motion.skeleton, trans, motion.rotations, motion.frame_time)


def load_clip(library: Library, action: ActionDef, path: str) -> Clip:
    where = f"{action.source or library.source}: action {action.name!r}"
    motion = face_front(on_floor(read_bvh(path)))
    roles = resolve_roles(motion, action.roles, where)
    if action.stages is not None:
        if action.stages[-1] > motion.frames:
            raise DoodleError(f"{where}: field 'stages': frame {action.stages[-1]} is past the clip's "
                              f"{motion.frames} frames ({path})")
        found = Stages(*action.stages, motion.frames)
    else:
        found = stages(motion)
    cycle = action.cycle_length if action.cycle_length is not None else (
        cycle_length(motion) if action.cyclic else None)
    contacts = foot_contacts(motion, [roles["left_foot"], roles["right_foot"]])
    return Clip(action.name, path, motion, roles, found, cycle, contacts, travel_yaw(motion))


def load_clips(library: Library) -> dict[str, list[Clip]]:
    """Every action's clips, by action name."""
    return {a.name: [load_clip(library, a, p) for p in a.clips] for a in library.actions if a.clips}


def travel_directions(library: Library, clips: dict | None = None) -> dict[str, float]:
    """What each travelling cyclic action of ``library`` means: the way its first clip
    travels relative to its facing (radians; the built-in Walk 0, Side Walk Left π/2…).
    ``clips``: the library's clips if already loaded."""
    out = {}
    for a in library.actions:
        if a.cyclic and not a.in_place and a.clips:
            clip = clips[a.name][0] if clips and clips.get(a.name) else load_clip(library, a, a.clips[0])
            if clip.travel is not None:
                out[a.name] = clip.travel
    return out


def fits(clip: Clip, want: float | None) -> bool:
    """Whether a clip travels the way an action means (``want``: radians about +y from the
    facing, as :attr:`Clip.travel`; None: any way, or on the spot)."""
    if want is None:
        return True
    return clip.travel is not None and abs(float(np.angle(np.exp(1j * (clip.travel - want))))) <= FIT


def retargeted(clip: Clip, skeleton: Skeleton, reference: Motion, roles: dict) -> Clip:
    """The clip played by ``skeleton`` (:func:`retarget.transfer_skeleton.retarget`;
    ``reference``: a motion on it, whose first frame gives its conventions; ``roles``: its
    role → joint). Raises ValueError when a role cannot be found. Stages and
    frames are the clip's; the cycle length scales with the legs."""
    from retarget.transfer_skeleton import leg_length, retarget

    motion = retarget(clip.motion, skeleton, reference, roles)
    scale = leg_length(skeleton, roles) / leg_length(clip.motion.skeleton)
    contacts = foot_contacts(motion, [roles["left_foot"], roles["right_foot"]])
    cycle = None if clip.cycle_length is None else clip.cycle_length * scale
    return Clip(clip.action, clip.path, motion, roles, clip.stages, cycle, contacts, travel_yaw(motion), True)
