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
