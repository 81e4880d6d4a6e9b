"""Bounded memory for long doodles: the block-wise, joint-subset and in-place forms give,
bit for bit, what the whole-array forms give (on small motions, with small blocks)."""

from dataclasses import replace

import numpy as np
import pytest

import retarget.feet as feet_module
import retarget.qa as qa_module
import retarget.skeleton as skeleton_module
from retarget.feet import clamp_to_ground, pin_feet
from retarget.qa import check, check_world
from retarget.skeleton import _kinematics, end_site_positions, forward_kinematics, kinematics_of


@pytest.fixture(scope="module")
def walk():
    from library.manifest import builtin
    from retarget.clips import load_clips

    clips = load_clips(builtin())
    clip = clips["Walk"][0]
    m = clip.motion
    twice = replace(m, translations=np.concatenate([m.translations, m.translations[::-1]]),
                    rotations=np.concatenate([m.rotations, m.rotations[::-1]]))
    trans = twice.translations.copy()
    trans[:, 0, 1] -= np.linspace(0.0, 0.3, twice.frames)  # sinks into the floor: clamping lifts it
    return clip, replace(twice, translations=trans)


def _same(a, b):
    return np.array_equal(a, b) and a.dtype == b.dtype


@pytest.mark.parametrize("block", [1, 7, 50])
def test_kinematics_of_chosen_joints_is_forward_kinematics_bit_for_bit(walk, block, monkeypatch):
    _, m = walk
    positions, rotations = _kinematics(m)
    monkeypatch.setattr(skeleton_module, "FK_BLOCK", block)
    joints = [0, 3, 5, len(m.skeleton) - 1]
    p, r = kinematics_of(m, joints)
    for j in joints:
        assert _same(p[:, j], positions[:, j]) and _same(r[:, j], rotations[:, j])
        assert _same(p[:, j, 1], positions[:, j, 1])
    assert _same(p[:, -1], positions[:, -1])  # a negative joint counts from the end
    with pytest.raises(KeyError):
        p[:, 1]
    everywhere, r = kinematics_of(m, joints, every_position=True)
    assert _same(everywhere, positions)


@pytest.mark.parametrize("block", [5, 13])
def test_clamp_to_ground_in_blocks_and_in_place_is_the_same(walk, block, monkeypatch):
    _, m = walk
    whole = clamp_to_ground(m)
    monkeypatch.setattr(feet_module, "FK_BLOCK", block)
    assert _same(clamp_to_ground(m).translations, whole.translations)
    own = replace(m, translations=m.translations.copy())
    out = clamp_to_ground(own, in_place=True)
    assert _same(out.translations, whole.translations) and out.translations is own.translations
    assert not np.array_equal(m.translations, whole.translations)  # the caller's motion left alone


def test_pin_feet_in_place_is_the_same(walk):
    clip, m = walk
    feet = [clip.roles["left_foot"], clip.roles["right_foot"]]
    contacts = np.zeros((m.frames, 2), dtype=bool)
    contacts[5:20, 0] = contacts[25:40, 1] = True
    before = m.rotations.copy(), m.translations.copy()
    copied = pin_feet(m, feet, contacts=contacts, standing=[0.08, 0.08])
    assert _same(m.rotations, before[0]) and _same(m.translations, before[1])
    own = replace(m, translations=m.translations.copy(), rotations=m.rotations.copy())
    moved = pin_feet(own, feet, contacts=contacts, standing=[0.08, 0.08], in_place=True)
    assert _same(moved.rotations, copied.rotations) and _same(moved.translations, copied.translations)


@pytest.mark.parametrize("block", [3, 11])
def test_check_with_its_world_and_in_blocks_is_the_check(walk, block, monkeypatch):
    _, m = walk
    whole = check(m, ground=0.0, world=forward_kinematics(m))
    monkeypatch.setattr(qa_module, "CHECK_BLOCK", block)
    light = check(m, ground=0.0, world=check_world(m))
    assert light == whole
    world = check_world(m)
    full = forward_kinematics(m)
    for j, end in end_site_positions(m, world).items():
        assert _same(end, end_site_positions(m, full)[j])
