"""Contact adaptation (§6.2.2): the slapping hand meets its target at the contact frame."""

import numpy as np
import pytest

from library.manifest import builtin
from retarget.clips import load_clips
from retarget.contact import arm_chain, contact_weight, reach
from retarget.skeleton import forward_kinematics

SLAP = load_clips(builtin())["Slap"][0]


@pytest.mark.parametrize("offset", [(0.10, 0.05, 0.10), (-0.15, -0.05, 0.05), (0.0, 0.12, -0.08)])
def test_slapping_hand_reaches_its_target(offset):
    m = SLAP.motion
    frame = SLAP.stages.execution  # contact at the end of the execution
    shoulder, elbow, hand = arm_chain(m)
    before = forward_kinematics(m)[0]
    aim = before[frame, hand] + np.array(offset) - before[frame, shoulder]
    target = before[frame, shoulder] + 0.45 * aim / np.linalg.norm(aim)  # within the arm's reach (0.53 m)
    after = forward_kinematics(reach(m, target, frame))[0]
    assert np.linalg.norm(after[frame, hand] - target) < 0.02
    far = np.abs(np.arange(m.frames) - frame) > round(0.25 / m.frame_time)
    assert np.allclose(after[far], before[far], atol=1e-9)  # untouched away from the contact
    others = [j for j in range(len(m.skeleton)) if j not in (elbow, hand) and m.skeleton.parents[j] != hand]
    assert np.allclose(after[:, others], before[:, others], atol=1e-6)  # only the arm moves
    step = np.linalg.norm(np.diff(after[:, hand], axis=0), axis=1)
    assert step.max() < 3 * np.linalg.norm(np.diff(before[:, hand], axis=0), axis=1).max() + 0.02  # no jump


def test_contact_weight_eases_in_and_out():
    w = contact_weight(21, 10, 5)
    assert w[10] == 1.0 and w[4] == 0.0 and w[16] == 0.0 and np.all(np.diff(w[:11]) >= 0)


def test_a_target_out_of_reach_gets_the_arm_pointing_at_it():
    m = SLAP.motion
    frame = SLAP.stages.execution
    shoulder, _, hand = arm_chain(m)
    before = forward_kinematics(m)[0]
    target = before[frame, shoulder] + np.array([0.0, 0.0, 2.0])
    after = forward_kinematics(reach(m, target, frame))[0]
    direction = (after[frame, hand] - after[frame, shoulder]) / np.linalg.norm(after[frame, hand] - after[frame, shoulder])
    assert direction[2] > 0.99


def test_local_coordinates_are_rigid_invariants():
    from scipy.spatial.transform import Rotation

    from doodle.core.arap import local_coordinates

    rng = np.random.default_rng(4)
    p = np.cumsum(rng.normal(size=(20, 3)), axis=0)
    moved = Rotation.from_rotvec([0.3, -1.2, 0.5]).apply(p) + [4.0, -2.0, 7.0]
    for a, b in zip(local_coordinates(p), local_coordinates(moved)):
        assert np.allclose(a, b)


def test_arap_path_reaches_the_target_and_keeps_the_shape():
    """Eq. 6.7 on an arc: the contact point meets the target, the window's ends stay, and the
    neighbour-frame coordinates (α, β) change less than under a plain eased shift."""
    from doodle.core.arap import local_coordinates
    from retarget.contact import arap_path, contact_weight

    s = np.linspace(0, np.pi, 41)
    path = np.column_stack([np.cos(s), np.sin(s), 0.2 * s])
    target = path[20] + [0.05, 0.08, -0.04]
    new = arap_path(path, 20, target, 8, 32)
    assert np.linalg.norm(new[20] - target) < 1e-3
    assert np.array_equal(new[:9], path[:9]) and np.array_equal(new[32:], path[32:])
    eased = path + (target - path[20]) * contact_weight(41, 20, 12)[:, None]
    before = np.concatenate(local_coordinates(path[8:33]))
    assert np.abs(np.concatenate(local_coordinates(new[8:33])) - before).sum() < \
        np.abs(np.concatenate(local_coordinates(eased[8:33])) - before).sum()
