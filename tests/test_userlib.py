"""A user library on another skeleton (Bandai): built-in clips retargeted onto it for the
actions it misses, clips chosen by the way they travel relative to their facing, cycle
lengths of one stride. Real data through ../shared/data/mocap (skipped when absent)."""

import warnings
from pathlib import Path

import numpy as np
import pytest

from library.manifest import builtin
from retarget.analysis import (cycle_length, facing, facing_yaw, feet_low, guess_roles, travel_yaw)
from retarget.bvh import read_bvh
from retarget.clips import face_front, load_clips
from retarget.qa import check
from retarget.skeleton import forward_kinematics
from retarget.transfer_skeleton import joint_map, retarget

ROOT = Path(__file__).resolve().parents[1]
MOCAP = ROOT.parent / "shared" / "data" / "mocap"
BANDAI = MOCAP / "bandai"
BUILTIN = ROOT / "library" / "builtin" / "clips"


@pytest.fixture(scope="module")
def bandai_pose():
    path = BANDAI / "dataset-1" / "dataset-1_bow_normal_001.bvh"
    if not path.exists():
        pytest.skip(f"{path} not found")
    return read_bvh(path)


def _on_bandai(name, reference):
    return retarget(read_bvh(BUILTIN / f"{name}.bvh"), reference.skeleton, reference)


def test_joints_map_by_role_chains(bandai_pose):
    sk, src = bandai_pose.skeleton, read_bvh(BUILTIN / "idle.bvh").skeleton
    named = {sk.names[a]: src.names[b] for a, b in joint_map(src, sk).items()}
    assert named["Hips"] == "Hips" and named["Chest"] == "Spine2" and named["Head"] == "Head"
    assert [named[n] for n in ("Shoulder_L", "UpperArm_L", "LowerArm_L", "Hand_L")] == [
        "LeftShoulder", "LeftArm", "LeftForeArm", "LeftHand"]
    assert [named[n] for n in ("UpperLeg_R", "LowerLeg_R", "Foot_R", "Toes_R")] == [
        "RightUpLeg", "RightLeg", "RightFoot", "RightToeBase"]
    assert "joint_Root" not in named


def test_retargeted_jump_leaves_the_ground_and_lands_without_pops(bandai_pose):
    motion = _on_bandai("jump", bandai_pose)
    low = feet_low(motion)
    assert abs(low[0]) < 0.01 and abs(low[-1]) < 0.01  # stands on the ground before and after
    assert low.max() > 0.15  # both feet leave the ground
    c = check(motion, ground=0.0)
    assert not c.pops and not c.hovering and not c.sinking


def test_retargeted_raised_arm_ends_above_the_head(bandai_pose):
    motion = _on_bandai("raise_one_arm", bandai_pose)
    sk, pos = motion.skeleton, forward_kinematics(motion)[0]
    above = np.maximum(pos[:, sk.index("Hand_L"), 1], pos[:, sk.index("Hand_R"), 1]) - pos[:, sk.index("Head"), 1]
    assert above[0] < -0.3 and above.max() > 0.1  # from arms down to a hand over the head
    assert not check(motion, ground=0.0).pops


def test_retargeted_idle_and_stomp_stand_on_the_ground(bandai_pose):
    for name in ("idle", "stomp"):
        motion = _on_bandai(name, bandai_pose)
        sk, pos = motion.skeleton, forward_kinematics(motion)[0]
        c = check(motion, ground=0.0)
        assert not c.pops and not c.hovering and not c.sinking, name
        assert abs(np.percentile(feet_low(motion), 5)) < 0.01, name
        chest = pos[:, sk.index("Chest"), 1]
        assert np.all(pos[:, sk.index("Hand_L"), 1] < chest), name  # arms down, not the T-pose
        assert np.all(pos[:, sk.index("Head"), 1] > 1.2), name  # upright


def test_bandai_walk_left_is_a_forward_walk_facing_left():
    path = BANDAI / "dataset-1" / "dataset-1_walk-left_normal_001.bvh"
    if not path.exists():
        pytest.skip(f"{path} not found")
    motion = read_bvh(path)
    assert 60 < np.degrees(facing_yaw(motion)) < 100  # the performer faces the world's left ...
    assert abs(np.degrees(travel_yaw(motion))) < 30  # ... and walks where they face: forwards
    front = face_front(motion)  # loaded clips face +z: travel is relative to the facing
    assert abs(np.degrees(facing_yaw(front))) < 1
    assert abs(np.degrees(travel_yaw(front) - travel_yaw(motion))) < 1


def _same_foot_travel(motion):
    """Ground truth: the pelvis's travel between successive touchdowns of the same foot;
    in a clip too short for two, its travel over twice the time between the two feet's."""
    roles = guess_roles(motion.skeleton)
    pos = forward_kinematics(motion)[0]
    ankles = pos[:, [roles["left_foot"], roles["right_foot"]]]  # stances read here, apart from the code under test:
    speed = np.linalg.norm(np.gradient(ankles, motion.frame_time, axis=0), axis=2)  # an ankle low and slow
    contacts = (ankles[:, :, 1] - ankles[:, :, 1].min(axis=0) <= 0.03) & (speed <= 0.25)
    hips = pos[:, roles["pelvis"]][:, [0, 2]]
    downs = [np.flatnonzero(contacts[1:, k] & ~contacts[:-1, k] & np.r_[contacts[2:, k], True]) + 1 for k in (0, 1)]
    strides = []
    for d in downs:
        d = [b for a, b in zip(np.r_[-99, d], d) if b - a > 10]  # a touchdown (a stride lasts > 1/3 s), not a flicker
        strides += [np.linalg.norm(hips[b] - hips[a]) for a, b in zip(d, d[1:])]
    if strides:
        return float(np.median(strides))
    a, b = sorted([downs[0][0], downs[1][0]])
    speed = np.linalg.norm(hips[-1] - hips[0]) / (motion.frames - 1)
    return float(speed * 2 * (b - a))


def test_cycle_length_is_one_stride_on_every_bandai_walk():
    files = sorted(BANDAI.glob("dataset-*/*walk*.bvh"))
    if not files:
        pytest.skip("Bandai walks not found")
    assert len([f for f in files if "_normal_" in f.name]) == 11
    off = {}
    for path in files:
        motion = read_bvh(path)
        truth, found = _same_foot_travel(motion), cycle_length(motion)
        if abs(found / truth - 1) > 0.15:
            off[path.name] = (round(found, 2), round(truth, 2))
    assert not off, off


def test_cycle_length_of_the_builtin_walks_is_their_stride():
    lib = builtin()
    for name in ("Walk", "Walk Back", "Side Walk Left", "Side Walk Right"):
        action = lib.action(name)
        assert cycle_length(read_bvh(action.clips[0])) == pytest.approx(action.cycle_length, rel=0.05), name


def test_demo_with_the_bandai_library_holds_no_rest_pose(tmp_path):
    folder = BANDAI / "dataset-1"
    if not folder.exists():
        pytest.skip("Bandai data not found")
    from doodle.app.pipeline import compile_doodle, load_for_compile
    from doodle.input.loader import load
    from library.manifest import load_library
    from retarget.importer import import_library

    import_library(folder, "bandai", tmp_path / "bandai", None, "*_normal_*")
    lib = load_library(tmp_path / "bandai")
    assert "Side Walk Left" not in lib.names and "travels" in lib.action("walk-left").note
    assert lib.action("Walk Back").clips  # walk-back does travel backwards
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        result = compile_doodle(load(ROOT / "examples" / "demo.doodle"), library_dir=tmp_path / "bandai")[0]
    text = " ".join(str(w.message) for w in said)
    assert "rest pose" not in text
    assert "Jump on its skeleton: 1 segment plays the built-in clip retargeted" in text
    assert all(result.clips[s.action] for s in result.segments)  # every segment plays a clip
    assert result.clips["Walk"].endswith("dataset-1_walk_normal_001.bvh")
    turn = np.degrees(np.abs(np.diff(np.unwrap(facing(result.motion)))))
    assert turn.max() < 6.0  # no snap to face the capture's own heading
    c = check(result.motion, ground=0.0)
    assert not c.hovering and not c.sinking and not c.turns
    # the side step comes from the built-in clip: it travels leftwards relative to its facing
    clip = next(c for c in load_for_compile(tmp_path / "bandai").clips["Side Walk Left"] if c.retargeted)
    assert 60 < np.degrees(clip.travel) < 120


def test_load_clips_face_front_and_leave_builtin_clips_alone():
    clips = load_clips(builtin())
    walk = clips["Walk"][0]
    assert np.array_equal(walk.motion.rotations, read_bvh(walk.path).rotations)
    assert abs(walk.travel) < 0.05 and clips["Side Walk Left"][0].travel == pytest.approx(np.pi / 2, abs=0.05)


def test_a_skeleton_that_cannot_be_retargeted_onto_holds_the_rest_pose_and_says_so(tmp_path, monkeypatch):
    """Where the built-in clips cannot be put on a user library's skeleton, compile says so
    and names the segments that hold its rest pose — no traceback."""
    folder = BANDAI / "dataset-1"
    if not folder.exists():
        pytest.skip("Bandai data not found")
    import retarget.clips
    from doodle.app.pipeline import compile_doodle
    from doodle.input.loader import load
    from retarget.importer import import_library

    import_library(folder, "bandai", tmp_path / "bandai", None, "*_normal_*")

    def cannot(*_args, **_kw):
        raise ValueError("no chain from the pelvis to the left hand")

    monkeypatch.setattr(retarget.clips, "retargeted", cannot)
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        result = compile_doodle(load(ROOT / "examples" / "demo.doodle"), library_dir=tmp_path / "bandai")[0]
    text = " ".join(str(w.message) for w in said)
    assert "cannot be retargeted onto its skeleton: no chain from the pelvis to the left hand" in text
    assert "the library has no clip of Jump on its skeleton: 1 segment holds the rest pose (c0 4.23–5.22 s)" in text
    assert result.clips["Jump"] is None
