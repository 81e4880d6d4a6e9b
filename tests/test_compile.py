"""`doodle compile`: flat ground, built-in clips, one BVH per track."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from doodle.app.cli.main import main
from doodle.input.fileformat import write_doodle
from doodle.input.loader import load
from doodle.synth.strokes import stroke, synth_doodle
from retarget.bvh import read_bvh
from retarget.skeleton import end_site_positions, forward_kinematics

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples"))
from make_demo import FIG_4_7  # noqa: E402

DEMO = ROOT / "examples" / "demo.doodle"


@pytest.fixture(scope="module")
def compiled(tmp_path_factory):
    out = tmp_path_factory.mktemp("demo")
    assert main(["compile", str(DEMO), "-o", str(out)]) == 0
    return out, json.loads((out / "report.json").read_text())


def test_demo_compiles_to_the_recognised_sequence(compiled):
    out, report = compiled
    track = report["tracks"]["c0"]
    assert [s["action"] for s in track["segments"]] == FIG_4_7
    motion = read_bvh(out / "c0.bvh", unit=1.0)
    assert motion.frames == track["frames"] == int(np.floor(report["duration_s"] * 30)) + 1
    assert len(track["transitions"]) == len(FIG_4_7) - 1
    assert set(track["metrics"]) == {"ground_penetration_m", "root_deviation_m",
                                     "transition_smoothness"}


def test_root_follows_the_doodle_and_stays_put_in_place(compiled):
    """Walk segments travel the doodle's distance scaled 8.5×; Stomp stays in place; no
    part of the body goes more than a centimetre under the ground."""
    out, report = compiled
    motion = read_bvh(out / "c0.bvh", unit=1.0)
    world = forward_kinematics(motion)
    hips = world[0][:, motion.skeleton.index("Hips")]
    doodle = load(DEMO)
    t, p = doodle.t, doodle.track("c0").p
    for seg in report["tracks"]["c0"]["segments"]:
        a, b = int(round(seg["start"] * 30)), min(int(round(seg["end"] * 30)), motion.frames - 1)
        moved = np.linalg.norm(hips[b, [0, 2]] - hips[a, [0, 2]])
        if seg["action"] == "Walk":
            ia, ib = np.searchsorted(t, seg["start"]), np.searchsorted(t, seg["end"])
            doodled = 8.5 * np.linalg.norm(p[min(ib, len(t) - 1), [0, 2]] - p[ia, [0, 2]])
            assert moved == pytest.approx(doodled, rel=0.1)
        if seg["action"] == "Stomp":
            assert moved < 0.15
    lowest = min(world[0][..., 1].min(), min(e[:, 1].min() for e in end_site_positions(motion, world).values()))
    assert lowest > -0.01


def test_two_tracks_share_one_timeline(tmp_path):
    doodle = synth_doodle({"c0": [stroke("T_STILL", 0.5), stroke("T_Z", 1.0, 0.15), stroke("T_STILL", 0.5)],
                           "c1": [stroke("T_STILL", 0.5), stroke("T_Y", 0.3), stroke("T_N_Y", 0.3),
                                  stroke("T_STILL", 0.5)]}, seed=2)
    path = tmp_path / "two.doodle"
    write_doodle(path, doodle)
    out = tmp_path / "out"
    assert main(["compile", str(path), "-o", str(out)]) == 0
    a, b = read_bvh(out / "c0.bvh", unit=1.0), read_bvh(out / "c1.bvh", unit=1.0)
    assert a.frames == b.frames
    report = json.loads((out / "report.json").read_text())
    assert "Walk" in [s["action"] for s in report["tracks"]["c0"]["segments"]]
    assert "Stomp" in [s["action"] for s in report["tracks"]["c1"]["segments"]]


def test_a_failed_compile_leaves_existing_output(tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["compile", str(DEMO), "-o", str(out)]) == 0
    before = (out / "report.json").read_text()
    bad = tmp_path / "bad.doodle"
    bad.write_text("# doodle 1\n")
    assert main(["compile", str(bad), "-o", str(out)]) == 1
    assert "bad.doodle" in capsys.readouterr().err
    assert (out / "report.json").read_text() == before


def test_compile_with_a_library_imported_from_bandai(tmp_path, capsys):
    """Bandai's skeleton (a joint_Root above the Hips, centimetres) drives the output; actions
    Bandai has no fitting clip for play the built-in clip retargeted onto it (its walk-left
    is a forward walk facing left, not a side step); the walk still travels the doodle."""
    bandai = ROOT.parent / "shared" / "data" / "mocap" / "bandai" / "dataset-1"
    if not bandai.exists():
        pytest.skip("Bandai data not found")
    lib = tmp_path / "bandai"
    assert main(["library", "import", str(bandai), "--name", "bandai", "--include", "*_walk*_normal_*",
                 "-o", str(lib)]) == 0
    out = tmp_path / "out"
    assert main(["compile", str(DEMO), "--library", str(lib), "-o", str(out)]) == 0
    report = json.loads((out / "report.json").read_text())
    segs = report["tracks"]["c0"]["segments"]
    assert [s["action"] for s in segs] == FIG_4_7
    assert all(s["clip"] and "bandai" in s["clip"] for s in segs if s["action"] == "Walk")
    assert all(s["clip"] and "builtin" in s["clip"] for s in segs if s["action"] in ("Jump", "Stomp", "Side Walk Left"))
    motion = read_bvh(out / "c0.bvh")
    assert motion.skeleton.names[:2] == ("joint_Root", "Hips")
    hips = forward_kinematics(motion)[0][:, 1]
    walk = next(s for s in segs if s["action"] == "Walk")
    a, b = int(round(walk["start"] * 30)), int(round(walk["end"] * 30))
    assert np.linalg.norm(hips[b, [0, 2]] - hips[a, [0, 2]]) > 0.5


def test_two_bone_ik_reaches_its_target():
    from retarget.feet import two_bone_ik

    walk = read_bvh(ROOT / "library" / "builtin" / "clips" / "walk.bvh", unit=1.0)
    sk = walk.skeleton
    ankle = sk.index("LeftFoot")
    knee, hip = int(sk.parents[ankle]), int(sk.parents[int(sk.parents[ankle])])
    before = forward_kinematics(walk)
    target = before[0][:, ankle] + [0.03, 0.02, -0.04]
    after = forward_kinematics(two_bone_ik(walk, hip, knee, ankle, target, np.ones(walk.frames)))
    assert np.abs(after[0][:, ankle] - target).max() < 1e-3
    # the foot keeps its orientation in the world
    assert np.allclose(np.abs(np.sum(after[1][:, ankle] * before[1][:, ankle], axis=1)), 1.0, atol=1e-9)


def test_feet_are_pinned_and_above_the_ground():
    """Feet standing where they land cut the demo's sliding (the animation check's: a flat
    foot moving) from what the blended clips give to none, and nothing is under the ground."""
    from doodle.app.pipeline import compile_doodle, quality
    from retarget.qa import check

    doodle = load(DEMO)
    loose, = compile_doodle(doodle, pin=False)
    result, = compile_doodle(doodle)
    pinned = quality(result)
    assert check(result.motion, ground=0.0).sliding_per_s == 0.0 < check(loose.motion, ground=0.0).sliding_per_s
    assert pinned["ground_penetration_m"] == 0.0


def test_compile_on_an_elevation_grid(tmp_path):
    """On matplotlib's Jacksboro elevation grid the character walks the doodle over the
    relief: hips a body's height above the ground under them, nothing under the ground."""
    from retarget.terrain import parse_terrain

    out = tmp_path / "out"
    assert main(["compile", str(DEMO), "--terrain", "jacksboro", "-o", str(out), "--no-effort"]) == 0
    report = json.loads((out / "report.json").read_text())
    assert report["terrain"] == "jacksboro"
    assert [s["action"] for s in report["tracks"]["c0"]["segments"]] == FIG_4_7
    assert report["tracks"]["c0"]["metrics"]["ground_penetration_m"] == 0.0
    motion = read_bvh(out / "c0.bvh", unit=1.0)
    hips = forward_kinematics(motion)[0][:, 0]
    ground = parse_terrain("jacksboro").height(hips[:, [0, 2]])
    assert np.ptp(ground) > 0.25  # the relief is really there (0.56 m over the 20 m grid, at true scale)
    above = hips[:, 1] - ground
    assert 0.55 < above.min() and above.max() < 1.9  # (the jump crouches to 0.63 m on flat ground, and rises)
    assert report["tracks"]["c0"]["check"]["passes"]  # feet on the ground under them: no hovering, sinking, sliding


def test_bad_terrain_spec_is_one_line(tmp_path, capsys):
    assert main(["compile", str(DEMO), "--terrain", "mesh:" + str(tmp_path / "none.obj"), "-o",
                 str(tmp_path / "o")]) == 1
    err = capsys.readouterr().err
    assert err.startswith("doodle: error:") and "none.obj" in err


def test_preview_images(tmp_path):
    import matplotlib.image as mpimg

    out = tmp_path / "out"
    assert main(["compile", str(DEMO), "-o", str(out), "--preview"]) == 0
    report = json.loads((out / "report.json").read_text())
    names = sorted(Path(p).name for p in report["preview"])
    assert names in (["keyframes.png", "plan.png"], ["keyframes.png", "plan.png", "render.png"])  # render: with EGL
    for name in ("plan.png", "keyframes.png"):
        image = mpimg.imread(out / name)[..., :3]
        ink = (image.mean(axis=2) < 0.6).mean()
        assert 0.002 < ink < 0.5, name  # drawn, not blank
    # coloured segments in the plan view: more than the grey and black of axes and text
    plan = mpimg.imread(out / "plan.png")[..., :3]
    assert (np.ptp(plan, axis=2) > 0.3).mean() > 0.001


def test_gesture_retiming_follows_the_hand(tmp_path):
    """§5.3.3: with --retime gesture a one-shot clip advances with the hand's arc length:
    a stroke that is slow, then fast, plays the clip's first half over most of the time."""
    from doodle.app.pipeline import gesture_timing
    from retarget.trajectory import Span

    n = 100
    t = np.linspace(0, 1, n)
    s = np.where(t < 0.8, 0.25 * t / 0.8, 0.25 + 0.75 * (t - 0.8) / 0.2)  # 25 % of the way in 80 % of the time
    track = type("T", (), {"t": t, "p": np.column_stack([np.zeros(n), s, np.zeros(n)]), "q": np.tile([0, 0, 0, 1.0], (n, 1))})
    times, fraction = gesture_timing(track, Span("Stomp", 0.0, 1.0, 0, n, True, False, False))
    assert fraction[0] == 0 and fraction[-1] == pytest.approx(1.0)
    assert np.interp(0.8, times, fraction) == pytest.approx(0.25, abs=0.02)
    assert main(["compile", str(DEMO), "-o", str(tmp_path / "out"), "--retime", "gesture"]) == 0


@pytest.mark.parametrize("flag, value", [("--fps", "0"), ("--scale", "-2"), ("--threshold", "-1"), ("--time", "1.5")])
def test_bad_compile_options_are_one_line(tmp_path, capsys, flag, value):
    assert main(["compile", str(DEMO), "-o", str(tmp_path / "o"), flag, value]) == 1
    err = capsys.readouterr().err
    assert err.startswith("doodle: error:") and flag in err


def test_a_library_without_a_clip_for_an_action_says_which_segments_play_a_retargeted_one(tmp_path):
    """A user library that misses an action: compile warns, naming the action and the
    segments that play the built-in clip retargeted onto the library's skeleton."""
    import warnings

    from doodle.app.pipeline import compile_doodle
    from doodle.input.loader import load
    from retarget.importer import import_library

    bandai = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap" / "bandai" / "dataset-1"
    if not bandai.exists():
        pytest.skip("../shared/data/mocap is not here")
    import_library(bandai, "walks", tmp_path / "walks", None, "*_walk_normal_001*")
    demo = load(Path(__file__).resolve().parents[1] / "examples" / "demo.doodle")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        compile_doodle(demo, tmp_path / "walks")
    said = [str(w.message) for w in caught if "no clip of" in str(w.message)]
    assert any(s.startswith("the library has no clip of Jump on its skeleton: 1 segment plays the built-in clip "
                            "retargeted onto it (c0 4.") for s in said), said
    assert not any("rest pose" in s for s in said), said
    assert not any("no clip of Walk " in s for s in said)


def test_recognised_qualities_are_applied_on_a_grid_so_a_long_doodle_shares_its_stylised_clips():
    from doodle.app.pipeline import STYLE_STEP, _on_grid

    for value in (-1.0, -0.663, -0.012, 0.0, 0.024, 0.968, 0.989, 1.0):
        on = _on_grid(value)
        assert abs(on - value) <= STYLE_STEP / 2 + 1e-12
        assert abs(on / STYLE_STEP - round(on / STYLE_STEP)) < 1e-9
        assert repr(on) == repr(round(on, 2))  # written to the report as the value applied
    assert repr(_on_grid(-0.01)) == "0.0"  # never -0.0: the same stylised clip as 0.0


def test_the_demo_jump_lands_and_stands_up_at_a_persons_pace(compiled):
    """After the landing the body rises from its crouch over several frames, not two: the
    pelvis never rises faster than twice the built-in clip's own recovery (0.83 m/s)."""
    out, report = compiled
    track = report["tracks"]["c0"]
    jump = next(s for s in track["segments"] if s["action"] == "Jump")
    positions = forward_kinematics(read_bvh(out / "c0.bvh", unit=1.0))[0]
    y = positions[:, 0, 1]
    around = int(round(jump["end"] * 30)) - 15
    lowest = around + int(np.argmin(y[around: around + 30]))  # the landing crouch
    rise = np.diff(y[lowest: lowest + 20]) * 30
    assert y[lowest + 20] - y[lowest] > 0.2  # it does stand up …
    assert rise.max() < 2 * 0.83  # … at a person's pace (it rose 4–5 m/s in two frames before)
