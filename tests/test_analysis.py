"""Clip analysis on real motion capture: roles, partition, stages, cycles, foot contacts;
clips named by a library manifest."""

from pathlib import Path

import numpy as np
import pytest

from doodle.core.errors import DoodleError
from library.manifest import load_library
from retarget.analysis import (body_joints, cycle_length, cycle_period, foot_contacts, guess_roles, partition,
                               stages)
from retarget.bvh import read_bvh, write_bvh
from retarget.clips import load_clips
from retarget.skeleton import forward_kinematics

MOCAP = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mocap"
BANDAI = MOCAP / "bandai" / "dataset-1"


def bandai(content: str):
    path = BANDAI / f"dataset-1_{content}_normal_001.bvh"
    if not path.exists():
        pytest.skip(f"{path} not found")
    return read_bvh(path)


def test_roles_and_partition_of_the_bandai_skeleton():
    motion = bandai("walk")
    sk = motion.skeleton
    roles = guess_roles(sk)
    assert {r: sk.names[j] for r, j in roles.items()} == {
        "pelvis": "Hips", "chest": "Chest", "head": "Head", "left_foot": "Foot_L", "right_foot": "Foot_R",
        "left_hand": "Hand_L", "right_hand": "Hand_R"}
    parts = partition(sk, roles["pelvis"], roles["chest"], roles["head"])
    names = {k: {sk.names[j] for j in v} for k, v in parts.items()}
    assert names["spine"] == {"Hips", "Spine", "Chest", "Neck", "Head"}
    assert {"Shoulder_L", "Shoulder_R", "UpperLeg_L", "UpperLeg_R"} <= names["primary"]
    assert {"Hand_L", "Toes_R", "joint_Root"} <= names["secondary"]
    assert "joint_Root" not in {sk.names[j] for j in body_joints(sk)}


def test_deepmimic_roles():
    path = MOCAP / "deepmimic" / "walk.bvh"
    if not path.exists():
        pytest.skip("DeepMimic walk not found")
    sk = read_bvh(path).skeleton
    roles = guess_roles(sk)
    assert sk.names[roles["left_foot"]] == "left_ankle" and sk.names[roles["right_hand"]] == "right_wrist"


def test_walk_cycle_length_matches_hip_travel_per_cycle():
    """The walk's cycle length is within 10 % of the distance the hips travel between two
    heel strikes of the same foot (strikes from the foot contacts)."""
    motion = bandai("walk")
    roles = guess_roles(motion.skeleton)
    contacts = foot_contacts(motion, [roles["left_foot"], roles["right_foot"]])
    left = contacts[:, 0]
    strikes = np.flatnonzero(left[1:] & ~left[:-1]) + 1
    assert len(strikes) >= 3
    hips = forward_kinematics(motion)[0][:, roles["pelvis"]][:, [0, 2]]
    travel = np.mean([np.linalg.norm(hips[b] - hips[a]) for a, b in zip(strikes, strikes[1:])])
    assert cycle_length(motion) == pytest.approx(travel, rel=0.10)
    assert cycle_period(motion) * motion.frame_time == pytest.approx(np.mean(np.diff(strikes)) * motion.frame_time,
                                                                     rel=0.10)


def test_walk_feet_alternate_and_stay_put_in_contact():
    motion = bandai("walk")
    roles = guess_roles(motion.skeleton)
    feet = [roles["left_foot"], roles["right_foot"]]
    contacts = foot_contacts(motion, feet)
    assert 0.25 < contacts[:, 0].mean() < 0.75 and 0.25 < contacts[:, 1].mean() < 0.75
    world = forward_kinematics(motion)[0][:, feet]
    slide = np.linalg.norm(np.diff(world[:, :, [0, 2]], axis=0), axis=2)
    both = contacts[1:] & contacts[:-1]
    assert np.median(slide[both]) < 0.01  # under a centimetre per frame while planted


@pytest.mark.parametrize("content", ["kick", "punch"])
def test_stages_found_for_kick_and_punch(content):
    motion = bandai(content)
    found = stages(motion)
    bounds = found.bounds()
    assert found.transition == motion.frames
    ex0, ex1 = bounds["execution"]
    assert 0 < ex1 - ex0 < motion.frames  # an execution stage that is not the whole clip
    assert list(bounds) == ["preparation", "anticipation", "execution", "follow_through", "transition"]


def test_manifest_clips_roles_and_unknown_joints(tmp_path):
    motion = bandai("kick")
    folder = tmp_path / "lib"
    (folder / "clips").mkdir(parents=True)
    write_bvh(folder / "clips" / "kick.bvh", motion, unit=0.01)
    (folder / "library.toml").write_text(
        '[library]\nname = "mine"\n[skeleton]\npelvis = "Hips"\n\n'
        '[[actions]]\nname = "Kick"\nclips = ["clips/kick.bvh"]\nstages = [10, 20, 40, 60]\n')
    clips = load_clips(load_library(folder))
    kick = clips["Kick"][0]
    assert kick.stages.execution == 40 and kick.roles["pelvis"] == motion.skeleton.index("Hips")
    assert kick.contacts.shape == (motion.frames, 2)
    (folder / "library.toml").write_text(
        '[library]\nname = "mine"\n[skeleton]\npelvis = "Pelvis"\n\n'
        '[[actions]]\nname = "Kick"\nclips = ["clips/kick.bvh"]\n')
    with pytest.raises(DoodleError, match=r"library.toml: action 'Kick': skeleton.pelvis: no joint 'Pelvis'"):
        load_clips(load_library(folder))
    (folder / "library.toml").write_text(
        '[library]\nname = "mine"\n[[actions]]\nname = "Kick"\nclips = ["clips/kick.bvh"]\nstages = [10, 5, 40, 60]\n')
    with pytest.raises(DoodleError, match="field 'stages' must be four increasing"):
        load_library(folder)


def test_import_bandai_normal_style_gives_a_usable_library(tmp_path, capsys):
    """`doodle library import` of the Bandai dataset-1 normal-style clips: built-in names and
    expressions for walk, kick, punch…; stages for kick and punch; the walk's cycle length
    within 10 % of the hips' travel per cycle; the library recognises the demo doodle."""
    if not BANDAI.exists():
        pytest.skip("Bandai data not found")
    from doodle.app.cli.main import main

    out = tmp_path / "bandai"
    assert main(["library", "import", str(BANDAI), "--name", "bandai", "--include", "*_normal_*", "-o", str(out)]) == 0
    report = capsys.readouterr().out
    assert "Walk" in report and "Kick" in report and "Punch" in report
    lib = load_library(out)
    assert lib.action("Walk").expression and lib.action("Walk").cyclic
    assert not lib.action("slash").expression  # no built-in counterpart: clip only
    clips = load_clips(lib)
    for name in ("Kick", "Punch"):
        b = clips[name][0].stages.bounds()["execution"]
        assert 0 < b[1] - b[0] < clips[name][0].motion.frames
    walk = next(c for c in clips["Walk"] if c.motion.frames > 100)
    assert walk.cycle_length == pytest.approx(1.37, rel=0.10)  # hips: 1.355–1.387 m per cycle
    root = Path(__file__).resolve().parents[1]
    assert main(["recognize", "--library", str(out), str(root / "examples" / "demo.doodle")]) == 0
    assert "Walk" in capsys.readouterr().out


def test_import_errors(tmp_path):
    from retarget.importer import import_library

    with pytest.raises(DoodleError, match="not a folder"):
        import_library(tmp_path / "nope", "x", tmp_path / "out")
    (tmp_path / "empty").mkdir()
    with pytest.raises(DoodleError, match="no BVH files"):
        import_library(tmp_path / "empty", "x", tmp_path / "out")
    bad_map = tmp_path / "map.toml"
    bad_map.write_text('[[map]]\nmatch = "*"\n')
    (tmp_path / "empty" / "a.bvh").write_text("HIERARCHY\n")
    with pytest.raises(DoodleError, match="map #1: needs 'match'"):
        import_library(tmp_path / "empty", "x", tmp_path / "out", bad_map)
