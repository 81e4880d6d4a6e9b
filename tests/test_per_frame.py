"""Per-frame work that stays constant per frame: the span and searchsorted forms of
whole-timeline loops give what the plain whole-array formulas give, on small inputs."""

from types import SimpleNamespace

import numpy as np
import pytest

from doodle.app.pipeline import walk_progress
from retarget.feet import nearest_true
from retarget.sequence import _blend_weights


def _nearest_plain(mask):
    idx = np.flatnonzero(mask)
    return idx[np.abs(idx[None, :] - np.arange(len(mask))[:, None]).argmin(axis=1)]


@pytest.mark.parametrize("seed", range(6))
def test_nearest_true_is_the_plain_nearest_with_the_earlier_on_a_tie(seed):
    rng = np.random.default_rng(seed)
    for n in (1, 2, 5, 17, 60):
        mask = rng.random(n) < rng.uniform(0.05, 0.9)
        if not mask.any():
            mask[rng.integers(n)] = True
        assert np.array_equal(nearest_true(mask), _nearest_plain(mask))
    tie = np.array([True, False, True, False, False, False, True])
    assert nearest_true(tie).tolist() == [0, 0, 2, 2, 2, 6, 6]


def _progress_plain(times, step, t0, t1):
    inside = (times[1:] > t0) & (times[1:] <= t1)
    return np.concatenate([[0.0], np.cumsum(np.where(inside, step, 0.0))])


@pytest.mark.parametrize("t0, t1", [(0.0, 1.0), (-0.5, 0.4), (0.33, 0.71), (0.5, 2.5), (0.1, 0.1), (1.2, 3.0)])
def test_walk_progress_over_its_span_interpolates_as_the_whole_timeline(t0, t1):
    times = np.arange(31) / 30.0 * 1.5
    step = np.random.default_rng(1).uniform(0.0, 0.1, len(times) - 1)
    whole = _progress_plain(times, step, t0, t1)
    window, progress = walk_progress(times, step, t0, t1)
    assert len(window) == len(progress) <= len(times)
    probe = np.concatenate([times, np.linspace(-1.0, 3.0, 97)])
    assert np.array_equal(np.interp(probe, window, progress), np.interp(probe, times, whole))
    assert progress[-1] == whole[-1]


def _blend_plain(placed, times, blend):
    out = []
    for k, pl in enumerate(placed):
        lo = pl.span.t0 - (blend / 2 if k > 0 else 0.0)
        hi = pl.span.t1 + (blend / 2 if k < len(placed) - 1 else 0.0)
        mask = (times >= lo - 1e-9) & (times <= hi + 1e-9)
        if k == 0:
            mask |= times < pl.span.t0
        if k == len(placed) - 1:
            mask |= times > pl.span.t1
        out.append(np.flatnonzero(mask))
    return out


@pytest.mark.parametrize("bounds", [[0.0, 0.4, 0.9, 1.5], [0.25, 0.5, 1.0], [-0.2, 0.7, 2.0], [0.3, 0.3, 0.8, 0.8]])
def test_blend_frames_found_by_search_are_the_masks_frames(bounds):
    times = np.arange(46) / 30.0
    placed = [SimpleNamespace(span=SimpleNamespace(t0=a, t1=b)) for a, b in zip(bounds, bounds[1:])]
    found = {id(pl): idx for pl, idx, _ in _blend_weights(placed, times, 0.2)}
    for pl, idx in zip(placed, _blend_plain(placed, times, 0.2)):
        assert np.array_equal(found.get(id(pl), np.zeros(0, dtype=int)), idx)


def _kinematics_plain(motion):
    from doodle.core import quat

    sk = motion.skeleton
    positions, rotations = np.empty((motion.frames, len(sk), 3)), np.empty((motion.frames, len(sk), 4))
    for k in range(len(sk)):
        p = sk.parents[k]
        if p < 0:
            rotations[:, k], positions[:, k] = motion.rotations[:, k], motion.translations[:, k]
        else:
            rotations[:, k] = quat.multiply(rotations[:, p], motion.rotations[:, k])
            positions[:, k] = positions[:, p] + quat.rotate(rotations[:, p], motion.translations[:, k])
    return positions, rotations / np.linalg.norm(rotations, axis=-1, keepdims=True)


def test_forward_kinematics_by_levels_and_blocks_is_joint_by_joint_to_the_bit(monkeypatch):
    from library.manifest import builtin
    from retarget import skeleton
    from retarget.clips import load_clips
    from retarget.skeleton import Motion

    clips = load_clips(builtin())
    motions = [clips[name][0].motion for name in ("Walk", "Jump", "Punch")]
    m = motions[0]
    rng = np.random.default_rng(3)
    q = rng.normal(size=(150, len(m.skeleton), 4))  # not unit: the normalisation at the end counts too
    motions.append(Motion(m.skeleton, rng.normal(size=(150, len(m.skeleton), 3)), q, m.frame_time))
    monkeypatch.setattr(skeleton, "FK_BLOCK", 64)  # several blocks, the last one short
    for motion in motions:
        positions, rotations = skeleton._kinematics(motion)
        want = _kinematics_plain(motion)
        assert np.array_equal(positions, want[0]) and np.array_equal(rotations, want[1])
        assert positions.flags.c_contiguous and rotations.flags.c_contiguous


def test_bvh_text_written_in_blocks_is_the_text_written_at_once(monkeypatch):
    from library.manifest import builtin
    from retarget import bvh
    from retarget.clips import load_clips

    motion = load_clips(builtin())["Walk"][0].motion
    whole = bvh.format_bvh(motion, unit=0.01)
    monkeypatch.setattr(bvh, "ROWS_AT_ONCE", 7)  # several blocks, the last one short
    assert len(list(bvh.bvh_chunks(motion, unit=0.01))) > 2
    assert bvh.format_bvh(motion, unit=0.01) == whole


def test_csv_rows_read_at_once_are_the_rows_read_line_by_line():
    from doodle.input import csvimport

    rng = np.random.default_rng(5)
    fields = ["1.5", " 2.25", "-0", "+3", "1e-3", "nan", "-7.125 ", "0.1", "12345.678901234567", "-inf"]
    rows = [",".join(rng.choice(fields, 6)) for _ in range(40)]
    used = [4, 0, 2, 5]  # not in file order
    fast = csvimport._parse_data(rows, list(range(1, 41)), 6, used, list("abcd"), "x.csv")
    plain = np.array([[float(r.split(",")[j]) for j in used] for r in rows])
    assert fast.shape == (40, 4)
    assert np.array_equal(fast, plain, equal_nan=True) and np.array_equal(np.signbit(fast), np.signbit(plain))
    odd = rows[:3] + ["1_000,2,3,4,5,6"]  # only float() reads it: line by line, as before
    assert csvimport._parse_data(odd, [1, 2, 3, 4], 6, [0], ["t"], "x.csv")[-1, 0] == 1000.0
