"""Stage extraction on hand-labelled real clips (bench/stage_labels.toml): clearly better
than cutting each action in five equal parts, on the clips its constants were chosen on and
on the held-out ones; a clip of several punches splits into its repetitions."""

from pathlib import Path

import pytest

from bench.stages_accuracy import labels, real_errors, split_errors
from retarget.analysis import repetitions, stages
from retarget.bvh import read_bvh

MOCAP = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mocap"


@pytest.fixture(scope="module")
def labelled():
    clips = labels()
    if not all((MOCAP / c.file).exists() for c in clips):
        pytest.skip(f"labelled Bandai clips not found under {MOCAP}")
    return clips


def test_label_file_is_well_formed():
    clips = labels()
    assert len(clips) >= 14 and {c.split for c in clips} == {"tune", "held-out"}
    for clip in clips:
        assert clip.note
        for start, end, *ends in clip.reps:
            assert start <= ends[0] <= ends[1] <= ends[2] <= ends[3] <= end


@pytest.mark.parametrize("split", ["tune", "held-out"])
def test_extraction_beats_five_equal_parts(labelled, split):
    part = [c for c in labelled if c.split == split]
    new = real_errors(part, "speed", MOCAP).mean()
    base = real_errors(part, "equal", MOCAP).mean()
    assert new <= 0.6 * base, (new, base)
    assert new < real_errors(part, "keyframes", MOCAP).mean()


def test_extraction_with_its_own_split_beats_five_equal_parts(labelled):
    errors, right, total = split_errors(labelled, MOCAP)
    assert right == total  # every clip's number of repetitions found
    assert errors.mean() <= 0.6 * real_errors(labelled, "equal", MOCAP).mean()


def test_punch_splits_into_its_repetitions(labelled):
    clip = next(c for c in labelled if "punch" in c.file)
    motion = read_bvh(MOCAP / clip.file)
    found = repetitions(motion)
    assert len(found) == len(clip.reps) == 5
    assert found[0][0] == 0 and found[-1][1] == motion.frames
    for (a, b), (_, _, *ends) in zip(found, clip.reps):
        assert a <= ends[0] and ends[3] < b  # each jab, from its start to its follow-through, in one range
    first = stages(motion)  # the clip's stages are its first jab's; the transition runs to the end
    assert first.execution < found[0][1] and first.transition == motion.frames


@pytest.mark.parametrize("name", ["dataset-1_bow_normal_001", "dataset-2_raise-up-left-hand_normal_001"])
def test_one_action_is_one_repetition(labelled, name):
    clip = next(c for c in labelled if name in c.file)
    motion = read_bvh(MOCAP / clip.file)
    assert repetitions(motion) == [(0, motion.frames)]  # a bow's rise, a raise's lowering: no repeats
