"""An action's clips, loaded and analysed: motion, roles, stages, cycle length, contacts."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doodle.core.errors import DoodleError
from library.manifest import ROLES, ActionDef, Library
from retarget.analysis import Stages, cycle_length, foot_contacts, guess_roles, stages
from retarget.bvh import read_bvh
from retarget.skeleton import Motion


@dataclass(frozen=True, eq=False)
class Clip:
    action: str
    path: str
    motion: Motion
    roles: dict  # role -> joint index
    stages: Stages
    cycle_length: float | None  # metres per cycle, cyclic actions only
    contacts: np.ndarray  # (F, 2) left and right foot in contact


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


def load_clip(library: Library, action: ActionDef, path: str) -> Clip:
    where = f"{action.source or library.source}: action {action.name!r}"
    motion = read_bvh(path)
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
    return Clip(action.name, path, motion, roles, found, cycle, contacts)


def load_clips(library: Library) -> dict[str, list[Clip]]:
    """Every action's clips, by action name."""
    return {a.name: [load_clip(library, a, p) for p in a.clips] for a in library.actions if a.clips}
