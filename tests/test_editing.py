"""Resampling and mirroring motions."""

from pathlib import Path

import numpy as np
import pytest

from retarget.bvh import read_bvh, write_bvh
from retarget.editing import mirror, mirror_pairs, resample
from retarget.skeleton import forward_kinematics

MOCAP = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mocap"
FILES = [MOCAP / "bandai" / "dataset-1" / "dataset-1_punch_normal_001.bvh", MOCAP / "deepmimic" / "kick.bvh"]


@pytest.fixture(params=FILES, ids=lambda p: p.name)
def motion(request):
    if not request.param.exists():
        pytest.skip("mocap not found")
    return read_bvh(request.param)


def test_mirror_swaps_sides_and_reflects(motion, tmp_path):
    sk = motion.skeleton
    pairs = mirror_pairs(sk)
    names = dict(zip(sk.names, (sk.names[p] for p in pairs)))
    left = "Hand_L" if "Hand_L" in names else "left_wrist"
    right = "Hand_R" if "Hand_R" in names else "right_wrist"
    assert names[left] == right and names[right] == left
    mirrored = mirror(motion)
    a = forward_kinematics(motion)[0]
    b = forward_kinematics(mirrored)[0]
    np.testing.assert_allclose(b, a[:, pairs] * [-1, 1, 1], atol=1e-9)
    twice = mirror(mirrored)
    np.testing.assert_allclose(twice.translations, motion.translations, atol=1e-12)
    np.testing.assert_allclose(np.abs(np.sum(twice.rotations * motion.rotations, axis=-1)), 1.0, atol=1e-12)
    write_bvh(tmp_path / "m.bvh", mirrored)  # still a consistent skeleton
    back = read_bvh(tmp_path / "m.bvh", unit=1.0)
    np.testing.assert_allclose(forward_kinematics(back)[0], b, atol=1e-5)


def test_resample_keeps_the_motion(motion):
    fast = resample(motion, 2 * motion.fps)
    assert fast.frames == 2 * motion.frames - 1
    np.testing.assert_allclose(forward_kinematics(fast)[0][::2], forward_kinematics(motion)[0], atol=1e-9)
    back = resample(fast, motion.fps)
    assert back.frames == motion.frames
    np.testing.assert_allclose(forward_kinematics(back)[0], forward_kinematics(motion)[0], atol=1e-6)
    slow = resample(motion, motion.fps / 3)
    assert slow.frame_time == pytest.approx(3 * motion.frame_time)
