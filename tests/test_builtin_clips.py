"""The library's own built-in clips (library/builtin/clips, listed in clips.toml): they load,
the feet do not slide or sink, cyclic clips loop, and the stated stages fit the clip."""

import tomllib
from pathlib import Path

import numpy as np
import pytest

from library.builtin.humanoid import STANDARD, animate, leg, plant, pose
from retarget.analysis import foot_contacts, guess_roles
from retarget.bvh import read_bvh
from retarget.skeleton import end_site_positions, forward_kinematics

BUILTIN = Path(__file__).resolve().parents[1] / "library" / "builtin"
MANIFEST = BUILTIN / "clips.toml"


def _entries():
    if not MANIFEST.exists():
        return []
    return tomllib.loads(MANIFEST.read_text())["actions"]


ENTRIES = _entries()
IDS = [e["name"] for e in ENTRIES]


@pytest.fixture(scope="module", params=ENTRIES, ids=IDS)
def clip(request):
    entry = request.param
    motion = read_bvh(BUILTIN / entry["clips"][0])
    return entry, motion, forward_kinematics(motion)


def test_manifest_lists_the_clips_and_roles():
    if not ENTRIES:
        pytest.skip("clips.toml not generated (run library/builtin/make_clips.py)")
    data = tomllib.loads(MANIFEST.read_text())
    names = {e["name"] for e in ENTRIES}
    builtin = {a["name"] for a in tomllib.loads((BUILTIN / "library.toml").read_text())["actions"]}
    assert builtin <= names, sorted(builtin - names)  # every built-in action has a clip
    assert data["skeleton"] == {"pelvis": "Hips", "chest": "Spine2", "head": "Head", "left_foot": "LeftFoot",
                                "right_foot": "RightFoot", "left_hand": "LeftHand", "right_hand": "RightHand"}


def test_clip_loads_on_the_standard_skeleton(clip):
    entry, motion, _ = clip
    assert motion.skeleton.names == STANDARD.names
    assert abs(motion.fps - 30) < 1e-9
    assert 10 <= motion.frames <= 120
    assert (BUILTIN / entry["clips"][0]).stat().st_size < 100_000
    roles = guess_roles(motion.skeleton)
    assert {motion.skeleton.names[roles[r]] for r in ("pelvis", "chest", "head")} == {"Hips", "Spine2", "Head"}


def test_no_joint_below_the_ground(clip):
    _, motion, world = clip
    ends = end_site_positions(motion, world)
    lowest = min(world[0][..., 1].min(), *(e[:, 1].min() for e in ends.values()))
    assert lowest > -0.01


def test_feet_do_not_slide_in_contact(clip):
    _, motion, world = clip
    feet = [motion.skeleton.index("LeftFoot"), motion.skeleton.index("RightFoot")]
    contacts = foot_contacts(motion, feet, world=world[0])
    for k, j in enumerate(feet):
        xz = world[0][:, j][:, [0, 2]]
        start = None
        for f in range(motion.frames + 1):
            inside = f < motion.frames and contacts[f, k]
            if inside and start is None:
                start = f
            if start is not None:
                if inside:  # how far the foot got from where the contact began
                    assert np.linalg.norm(xz[f] - xz[start]) < 0.01, (motion.skeleton.names[j], start, f)
                else:
                    start = None


CYCLIC = [e for e in ENTRIES if e["name"] in {"Idle", "Walk", "Walk Back", "Side Walk Left", "Side Walk Right"}]


@pytest.mark.parametrize("entry", CYCLIC, ids=[e["name"] for e in CYCLIC])
def test_cyclic_clips_loop(entry):
    motion = read_bvh(BUILTIN / entry["clips"][0])
    pos = forward_kinematics(motion)[0]
    rel = pos - pos[:, :1]
    assert np.abs(rel[0] - rel[-1]).max() < 0.02  # pose: pelvis-relative, within 2 cm
    v_first, v_last = rel[1] - rel[0], rel[-1] - rel[-2]
    assert np.abs(v_first - v_last).max() < 0.02  # per-frame velocities match roughly
    root_first, root_last = pos[1, 0] - pos[0, 0], pos[-1, 0] - pos[-2, 0]
    assert np.abs(root_first - root_last).max() < 0.02


WAY = {"Walk": (2, 1), "Walk Back": (2, -1), "Side Walk Left": (0, 1), "Side Walk Right": (0, -1)}


@pytest.mark.parametrize("entry", [e for e in CYCLIC if e["name"] in WAY], ids=[e["name"] for e in CYCLIC if e["name"] in WAY])
def test_walks_travel_their_way(entry):
    motion = read_bvh(BUILTIN / entry["clips"][0])
    world = forward_kinematics(motion)
    axis, sign = WAY[entry["name"]]
    travel = world[0][-1, 0] - world[0][0, 0]
    assert sign * travel[axis] > 0.3 and abs(travel[2 - axis]) < 0.05
    assert entry["cycle_length"] == pytest.approx(abs(travel[axis]), rel=0.05)
    if entry["name"] == "Walk":
        assert 0.9 <= motion.duration <= 1.3 and 1.1 <= entry["cycle_length"] <= 1.5


def test_stages_increase_within_the_clip(clip):
    entry, motion, _ = clip
    st = entry["stages"]
    assert len(st) == 4 and all(isinstance(s, int) for s in st)
    assert 0 <= st[0] and all(a < b for a, b in zip(st, st[1:])) and st[-1] < motion.frames


def test_keyframe_tool_and_foot_locking():
    # rest pose: 1.7 m tall, toes on the ground, Hips at 0.95 m
    rest = animate([(0, pose(), None), (1 / 30, pose(), None)])
    pos, _ = forward_kinematics(rest)
    ends = end_site_positions(rest)
    head = ends[STANDARD.index("Head")][0]
    toe = ends[STANDARD.index("LeftToeBase")][0]
    assert head[1] == pytest.approx(1.70) and toe[1] == pytest.approx(0.0) and pos[0, 0, 1] == pytest.approx(0.95)
    # IK puts the ankle where asked
    target = np.array([0.05, -0.7, 0.2])
    m = animate([(0, leg("Left", target), None), (1, pose(), None)])
    p = forward_kinematics(m)[0][0]
    assert np.allclose(p[STANDARD.index("LeftFoot")] - p[STANDARD.index("LeftUpLeg")], target, atol=1e-6)
    # a crouch in place: plant lowers the body and keeps both feet where they were
    keys = [(0, pose(), None), (0.5, {**leg("Left", (0, -0.6, 0)), **leg("Right", (0, -0.6, 0))}, None),
            (1, pose(), None)]
    planted = plant(animate(keys))
    pos = forward_kinematics(planted)[0]
    feet = pos[:, [STANDARD.index("LeftFoot"), STANDARD.index("RightFoot")]]
    assert np.abs(feet - feet[:1]).max() < 1e-6  # ankles at 8 cm all along
    assert pos[15, 0, 1] == pytest.approx(0.95 - 0.22, abs=1e-3)


def test_clip_passes_the_animation_check(clip):
    """No pops, the fastest joint with a margin under the check's 15 m/s (real motion capture
    peaks at 10.3 m/s Bandai, 12.2 m/s DeepMimic; a compiled scene may speed a clip up), no
    flat foot sliding, no hovering, no sinking."""
    from retarget.qa import check

    entry, motion, world = clip
    c = check(motion, ground=0.0, world=world)
    assert not c.pops and c.fastest < 12.0, (entry["name"], c.fastest, c.pops)
    assert not c.sliding, (entry["name"], c.sliding)
    assert not c.hovering and not c.sinking, (entry["name"], c.hovering, c.sinking)


@pytest.mark.parametrize("name", ["Side Walk Left", "Side Walk Right"])
def test_side_steps_are_steps(name):
    """A plausible side step: each foot steps 0.3–0.5 m about 1–1.6 times a second."""
    entry = next(e for e in ENTRIES if e["name"] == name)
    motion = read_bvh(BUILTIN / entry["clips"][0])
    steps_per_s = 2 / motion.duration  # a lead step and a closing step per cycle
    assert 1.0 <= steps_per_s <= 1.6 and 0.3 <= entry["cycle_length"] <= 0.5


def test_paced_keys_keep_points_under_the_speed():
    from library.builtin.humanoid import key_travel, pace, peak_speeds

    keys = [(0, pose(), None), (0.1, pose(LeftArm=(0, 0, 90)), None), (0.3, pose(), None)]
    travel = key_travel(keys)
    assert travel == pytest.approx([np.pi / 2 * 0.71] * 2, rel=0.01)  # the hand's tip: a quarter circle of 0.71 m
    paced = pace(keys, 10.0)
    gaps = np.diff([k[0] for k in paced])
    assert gaps[0] == pytest.approx(travel[0] / 10.0) and gaps[1] == pytest.approx(0.2)  # only stretched
    m = animate(paced)
    assert peak_speeds(m, [k[0] for k in paced]).max() < 1.6 * 10.0  # an eased peak
    hand = end_site_positions(m)[STANDARD.index("LeftHand")]
    assert hand[:, 1].max() <= 1.39 + 0.71 + 1e-6  # never above the keyed raised arm
