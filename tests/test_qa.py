"""The animation check (retarget.qa, ``doodle qa``): real walks pass it, and each defect it
names — a sliding foot, a pop, a one-frame turn, hovering, sinking, two bodies overlapping —
is found, in the frames where it was put."""

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from doodle.core import quat
from retarget.bvh import read_bvh, write_bvh
from retarget.qa import check, interpenetration

MOCAP = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap" / "bandai"
WALKS = sorted(MOCAP.glob("dataset-*/*walk*_normal_*.bvh")) if MOCAP.exists() else []
needs_mocap = pytest.mark.skipif(not WALKS, reason="../shared/data/mocap is not here")


@needs_mocap
@pytest.mark.parametrize("path", WALKS, ids=lambda p: p.stem)
def test_real_walks_pass(path):
    c = check(read_bvh(path))
    assert c.passes, c.summary()


def _walk():
    return read_bvh(next(p for p in WALKS if p.stem.endswith("dataset-2_walk_normal_001")))


def _moved(motion, offsets):
    """The motion with its root moved by ``offsets`` (F, 3)."""
    t = motion.translations.copy()
    t[:, 0] += offsets
    return replace(motion, translations=t)


@needs_mocap
def test_a_pop_and_a_one_frame_turn_are_found_where_they_are():
    walk = _walk()
    jump = np.zeros((walk.frames, 3))
    jump[100] = [0.6, 0.0, 0.0]  # the whole body away and back in one frame
    popped = check(_moved(walk, jump))
    assert 100 in popped.pops and popped.fastest > 15 and not popped.passes
    r = walk.rotations.copy()
    turn = quat.exp(np.array([0.0, np.radians(40.0), 0.0]))  # 40° about the vertical
    r[150:, 0] = quat.multiply(np.broadcast_to(turn, r[150:, 0].shape), r[150:, 0])
    turned = check(replace(walk, rotations=r))
    assert turned.turns == (150,)


@needs_mocap
def test_sliding_hovering_and_sinking_are_found():
    walk = _walk()
    base = check(walk)
    drift = np.zeros((walk.frames, 3))
    drift[:, 2] = np.cumsum(np.full(walk.frames, 0.6 * walk.frame_time))  # 0.6 m/s forward on top of the walk
    slid = check(_moved(walk, drift))
    assert slid.sliding_per_s > 5 * max(base.sliding_per_s, 0.3)
    ground = 0.0425  # the walk's floor (its soles' 2nd percentile)
    lift = np.zeros((walk.frames, 3))
    lift[:, 1] = 0.05
    assert check(_moved(walk, lift), ground=ground).hovering
    assert check(_moved(walk, -lift), ground=ground).sinking


@needs_mocap
def test_two_bodies_in_one_place_interpenetrate_and_apart_do_not():
    walk = _walk().slice(0, 40)
    apart = np.zeros((walk.frames, 3))
    apart[:, 0] = 1.5
    assert len(interpenetration(walk, walk)) == walk.frames
    assert interpenetration(walk, _moved(walk, apart)) == []


def test_compile_reports_the_check_and_qa_reads_it(tmp_path, capsys):
    from doodle.app.cli.main import main

    demo = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"
    out = tmp_path / "demo"
    assert main(["compile", str(demo), "-o", str(out), "--no-effort"]) == 0
    printed = capsys.readouterr().out
    assert "  check: sliding" in printed
    import json

    figures = json.loads((out / "report.json").read_text())["tracks"]["c0"]["check"]
    assert set(figures) >= {"passes", "sliding_frames_per_s", "pops", "one_frame_turns", "hovering_frames",
                            "interpenetration_frames"}
    code = main(["qa", str(out), "-v"])
    assert code == (0 if figures["passes"] else 4)
    assert "c0.bvh" in capsys.readouterr().out


@needs_mocap
def test_qa_passes_a_real_walk_alone_or_in_a_folder_and_refuses_what_is_not_a_scene(tmp_path, capsys):
    from doodle.app.cli.main import main

    write_bvh(tmp_path / "walk.bvh", _walk())
    assert main(["qa", str(tmp_path)]) == 0
    assert "passes" in capsys.readouterr().out
    assert main(["qa", str(tmp_path / "walk.bvh")]) == 0  # one clip, on its own floor
    out = capsys.readouterr().out
    assert out.startswith(f"{tmp_path / 'walk.bvh'}: ") and "passes" in out
    (tmp_path / "notes.txt").write_text("not a scene")
    assert main(["qa", str(tmp_path / "notes.txt")]) == 1
    assert "notes.txt: not a folder or a BVH file" in capsys.readouterr().err


@needs_mocap
def test_a_foot_standing_still_above_a_step_down_hovers():
    """A character standing still: over flat ground it passes; where the ground under one
    foot drops 5 cm (that foot now stands in the air) it hovers."""
    from retarget.analysis import guess_roles
    from retarget.skeleton import forward_kinematics

    clip = read_bvh(next(MOCAP.glob("dataset-2/*wave-both-hands_normal_001.bvh")))
    left = forward_kinematics(clip)[0][0, guess_roles(clip.skeleton)["left_foot"]]
    right = forward_kinematics(clip)[0][0, guess_roles(clip.skeleton)["right_foot"]]
    floor = 0.0425
    split = (left[0] + right[0]) / 2

    class Step:
        def height(self, xz):
            xz = np.asarray(xz)
            side = (xz[..., 0] - split) * np.sign(left[0] - right[0]) > 0
            return np.where(side, floor - 0.05, floor)

    assert not check(clip, ground=floor).hovering
    stepped = check(clip, terrain=Step())
    assert len(stepped.hovering) > 0.9 * clip.frames and stepped.highest > 0.045


def test_a_flip_is_not_a_turn_but_a_snap_of_heading_is():
    """Heading read from the pelvis's front and left axes, each as level as it lies: a flip
    pitches the front through the vertical without turning the character."""
    from library.manifest import builtin
    from retarget.clips import load_clips

    clips = load_clips(builtin())
    for name in ("Flip", "Back Flip"):
        assert not check(clips[name][0].motion, ground=0.0).turns, name
    idle = clips["Idle"][0].motion
    r = idle.rotations.copy()
    snap = quat.exp(np.array([0.0, np.radians(30.0), 0.0]))
    r[40:, 0] = quat.multiply(np.tile(snap, (idle.frames - 40, 1)), r[40:, 0])
    assert check(replace(idle, rotations=r), ground=0.0).turns == (40,)


def test_hovering_is_measured_above_where_the_skeletons_feet_stand():
    """A skeleton whose lowest foot joint stands 3 cm above the floor (mocap: the joints sit
    inside the shoe) is not hovering there, and is when raised 3 cm more."""
    from library.manifest import builtin
    from retarget.clips import load_clips

    idle = load_clips(builtin())["Idle"][0].motion
    up = _moved(idle, np.tile([0.0, 0.03, 0.0], (idle.frames, 1)))
    assert check(up, ground=0.0).hovering and not check(up, ground=0.0, sole=0.03).hovering
    higher = _moved(idle, np.tile([0.0, 0.06, 0.0], (idle.frames, 1)))
    assert check(higher, ground=0.0, sole=0.03).hovering


def test_a_foot_lifting_off_is_not_sliding_in_the_frame_before():
    """Sliding is a flat foot moving between two frames it is flat in: a foot still on the
    floor in the frame before it lifts has not slid."""
    from library.manifest import builtin
    from retarget.clips import load_clips

    idle = load_clips(builtin())["Idle"][0].motion
    n = idle.frames
    lift = np.zeros((n, 3))
    lift[30:, 1] = 0.05 * np.minimum(np.arange(n - 30) + 1, 5)  # up 5 cm a frame from frame 30 …
    lift[30:, 2] = 0.04 * (np.arange(n - 30) + 1)  # … moving forward 1.2 m/s
    assert not check(_moved(idle, lift), ground=0.0).sliding
    drag = np.zeros((n, 3))
    drag[30:, 2] = 0.04 * (np.arange(n - 30) + 1)  # the same without lifting: sliding
    assert check(_moved(idle, drag), ground=0.0).sliding
