"""Transition points on frame-distance maps with the stage policies (§5.3.1)."""

import numpy as np

from library.manifest import builtin
from retarget.analysis import Stages
from retarget.clips import load_clips
from retarget.transitions import distance_map, policy_frames, transition_point

CLIPS = load_clips(builtin())


def clip(name):
    return CLIPS[name][0]


def test_policies():
    full = Stages(10, 20, 30, 40, 50)
    assert policy_frames(full, full) == ((40 + 50) / 2, 5.0)
    no_prep = Stages(0, 20, 30, 40, 50)
    assert policy_frames(no_prep, no_prep)[1] == 10.0
    bare = Stages(0, 0, 30, 30, 30)
    assert policy_frames(bare, bare) == (30.0, 0.0)
    no_transition = Stages(10, 20, 30, 40, 40)
    assert policy_frames(no_transition, full)[0] == 40.0


def test_distance_map_of_a_clip_with_itself_is_zero_on_the_diagonal():
    punch = clip("Punch")
    d = distance_map(punch.motion, punch.motion, 0, 0)
    assert np.allclose(np.diag(d), 0, atol=1e-6) and (d >= 0).all()
    assert d[0, punch.stages.execution] > 0.1  # rest and strike are far apart


def test_transition_points_never_cut_an_execution():
    for a, b in [("Punch", "Kick"), ("Kick", "Stomp"), ("Jump", "Flip"), ("Throw", "Duck")]:
        s, t = clip(a), clip(b)
        i, j = transition_point(s.motion, t.motion, s.stages, t.stages)
        assert i >= s.stages.execution, (a, b, i)
        assert j <= t.stages.anticipation, (a, b, j)
        assert 0 <= i < s.motion.frames and 0 <= j < t.motion.frames


def test_features_turn_every_frame_into_the_pelvis_heading_and_are_computed_once():
    """The vectorised heading turn equals turning each frame with scipy's Rotation (the
    definition), and a clip's features are computed once and read-only."""
    from scipy.spatial.transform import Rotation

    from retarget.skeleton import forward_kinematics
    from retarget.transitions import frame_features

    motion = clip("Walk").motion
    positions, rotations = forward_kinematics(motion)
    rel = positions - positions[:, :1]
    forward = Rotation.from_quat(rotations[:, 0]).apply([0.0, 0.0, 1.0])
    yaw = np.arctan2(forward[:, 0], forward[:, 2])
    turned = np.stack([Rotation.from_rotvec([0.0, -y, 0.0]).apply(r) for y, r in zip(yaw, rel)])
    feats = frame_features(motion, 0)
    np.testing.assert_allclose(feats[:, : rel[0].size], turned.reshape(motion.frames, -1), atol=1e-12)
    assert frame_features(motion, 0) is feats and not feats.flags.writeable
