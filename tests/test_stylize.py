"""Laban stylisation (§5.4): operators and the Time and Weight modifiers — the measurable
signatures of Fig. 5.16 on built-in and on Bandai clips."""

from pathlib import Path

import numpy as np
import pytest
from scipy.interpolate import CubicSpline
from scipy.ndimage import gaussian_filter1d

from doodle.app.cli.main import main
from library.manifest import builtin
from retarget.analysis import foot_contacts, stages
from retarget.bvh import read_bvh
from retarget.clips import load_clips
from retarget.skeleton import forward_kinematics
from retarget.stylize import motion_scale, sliding_share, stylize, time_modifier

CLIPS = load_clips(builtin())
BANDAI = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "mocap" / "bandai" / "dataset-1"


def effector(name):
    """The clip and its acting hand or foot (of the feet, the one that moves: a stomp's
    stamping foot, not its support)."""
    c = CLIPS[name][0]
    if name in ("Punch", "Throw", "Uppercut Jab"):
        return c, c.roles["right_hand"]
    world = forward_kinematics(c.motion)[0]
    feet = [c.roles["left_foot"], c.roles["right_foot"]]
    return c, max(feet, key=lambda j: float(np.ptp(world[:, j], axis=0).max()))


def path_of(motion, joint, rate=240.0, smooth=0.02):
    """The joint's path resampled by a cubic spline and lightly smoothed (in seconds), so
    clips at different frame rates compare."""
    p = forward_kinematics(motion)[0][:, joint]
    t = np.arange(motion.frames) * motion.frame_time
    tt = np.arange(0, t[-1], 1 / rate)
    return tt, gaussian_filter1d(CubicSpline(t, p)(tt), smooth * rate, axis=0)


def peak_jerk(motion, joint):
    tt, q = path_of(motion, joint)
    j = q
    for _ in range(3):
        j = np.gradient(j, tt, axis=0)
    return float(np.linalg.norm(j, axis=1).max())


def speed_variation(motion, joint):
    tt, q = path_of(motion, joint)
    v = np.linalg.norm(np.gradient(q, tt, axis=0), axis=1)
    return float(v.std() / v.mean())


def amplitude(motion, joint):
    return float(np.ptp(forward_kinematics(motion)[0][:, joint], axis=0).max())


def moving_effector(motion, roles, st):
    """The hand or foot that travels farthest during the execution stage."""
    w = forward_kinematics(motion)[0]
    ends = [roles[k] for k in ("left_hand", "right_hand", "left_foot", "right_foot") if k in roles]
    a, e = st.anticipation, max(st.execution, st.anticipation + 2)
    return max(ends, key=lambda j: np.linalg.norm(np.diff(w[a:e + 1, j], axis=0), axis=1).sum())


def execution_jerk(motion, joint, st):
    """Peak jerk of the joint during the execution stage (Fig. 5.16's end-effector jerk)."""
    tt, q = path_of(motion, joint)
    j = q
    for _ in range(3):
        j = np.gradient(j, tt, axis=0)
    inside = (tt >= st.anticipation * motion.frame_time) & (tt <= st.execution * motion.frame_time)
    return float(np.linalg.norm(j, axis=1)[inside].max())


# The strikes and other one-shots with an impulsive execution. Gentle clips (Raise Arms,
# Pick up, Greet, Despair, Kiss, Dance, Uppercut Jab…) keep Sudden's signature but not
# Sustained's: eq. 5.3 plays Sustained anticipation twice as fast and starts the execution
# fast then decelerates, which raises their (tiny) execution jerk. The Flip's execution is its
# flight, which Sustained does not slow (gravity's, not the mover's): its peak jerk stays the
# neutral's; only its shorter, jerkier Sudden execution is checked.
IMPULSIVE = ["Punch", "Kick", "Throw", "Stomp", "Crescent Kick", "Block", "Jump", "Flip", "Duck", "Stop",
             "Dodge", "Cast Fireball", "Yell", "Slap"]


AIRBORNE = ("Flip",)


@pytest.mark.parametrize("name", IMPULSIVE)
def test_sudden_and_sustained(name):
    clip = CLIPS[name][0]
    j = moving_effector(clip.motion, clip.roles, clip.stages)
    execution = clip.stages.execution - clip.stages.anticipation
    sudden, s_st = time_modifier(clip.motion, clip.stages, 1.0)
    sustained, u_st = time_modifier(clip.motion, clip.stages, -1.0)
    ratio = clip.motion.frame_time
    assert (s_st.execution - s_st.anticipation) * sudden.frame_time < execution * ratio  # shorter
    assert (u_st.execution - u_st.anticipation) * sustained.frame_time > execution * ratio  # longer
    neutral = execution_jerk(clip.motion, j, clip.stages)
    assert execution_jerk(sudden, j, s_st) > neutral
    assert neutral > execution_jerk(sustained, j, u_st) or name in AIRBORNE


@pytest.mark.xfail(strict=True, reason="fails on the built-in Kick (not yet understood)")
def test_sudden_raises_peak_speed_and_shortens_the_execution_on_every_clip():
    """Was: execution jerk inside the stages' execution. Time now retimes the acting hand or
    foot's own burst (the stages may put the execution elsewhere), so the signature is measured
    there: peak speed and the burst's half-maximum width (retarget.effort_signature)."""
    from retarget.effort_signature import signature

    for name, (clip,) in CLIPS.items():
        neutral = signature(clip.motion)
        sudden = signature(time_modifier(clip.motion, clip.stages, 1.0)[0], neutral.effector)
        assert sudden.peak_speed > neutral.peak_speed and sudden.execution < neutral.execution, name


@pytest.mark.parametrize("name", ["Punch", "Kick", "Throw", "Stomp", "Crescent Kick"])
def test_strong_and_light(name):
    clip, j = effector(name)
    strong = stylize(clip.motion, clip.stages, 0.0, 1.0)
    light = stylize(clip.motion, clip.stages, 0.0, -1.0)
    assert strong.duration == pytest.approx(clip.motion.duration, abs=clip.motion.frame_time)
    assert strong.fps == pytest.approx(120.0)
    assert speed_variation(strong, j) > speed_variation(clip.motion, j) > speed_variation(light, j)
    if name in ("Punch", "Kick"):
        assert amplitude(strong, j) > amplitude(clip.motion, j) > amplitude(light, j)


def test_neutral_is_unchanged_and_nothing_breaks():
    for name, (clip,) in CLIPS.items():
        same = stylize(clip.motion, clip.stages, 0.0, 0.0)
        assert same is clip.motion, name
        for lt, lw in ((1, 0), (-1, 0), (0, 1), (0, -1), (0.5, 0.5), (-0.5, -0.5)):
            m = stylize(clip.motion, clip.stages, lt, lw)
            assert np.isfinite(m.rotations).all() and np.isfinite(m.translations).all(), (name, lt, lw)
            q = m.rotations
            dots = np.sum(q[1:] * q[:-1], axis=-1)
            assert dots.min() > 0, (name, lt, lw)  # no sign flips between frames
            assert dots.min() > np.cos(np.radians(120) / 2), (name, lt, lw)  # nor turns interpolation can't follow


def test_motion_scale_keeps_planted_feet_on_the_ground():
    clip = CLIPS["Kick"][0]
    feet = [clip.roles["left_foot"], clip.roles["right_foot"]]
    before = forward_kinematics(clip.motion)[0]
    contact = foot_contacts(clip.motion, feet, world=before)
    scaled = motion_scale(clip.motion, 0, clip.motion.frames, 1.8, "partial")
    after = forward_kinematics(scaled)[0]
    for k, f in enumerate(feet):
        assert np.abs(after[contact[:, k], f, 1] - before[contact[:, k], f, 1]).max() < 0.01


def test_stylize_command(tmp_path, capsys):
    clip = Path(__file__).resolve().parents[1] / "library" / "builtin" / "clips" / "punch.bvh"
    out, png = tmp_path / "p.bvh", tmp_path / "p.png"
    assert main(["stylize", str(clip), "--time", "1", "--stages", "9,16,20,27", "-o", str(out),
                 "--compare", str(png)]) == 0
    assert read_bvh(out, unit=1.0).fps == pytest.approx(120.0)
    assert png.stat().st_size > 10_000
    assert main(["stylize", str(clip), "--time", "2", "-o", str(out)]) == 1
    assert "between -1 and 1" in capsys.readouterr().err


def test_compile_applies_qualities_per_segment(tmp_path, capsys):
    import json

    demo = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"
    edits = tmp_path / "edits.json"
    edits.write_text(json.dumps({"segments": [{"track": "c0", "index": 9, "time": 1.0, "weight": 0.5}]}))
    out = tmp_path / "out"
    assert main(["compile", str(demo), "-o", str(out), "--edits", str(edits), "--no-effort"]) == 0
    segs = json.loads((out / "report.json").read_text())["tracks"]["c0"]["segments"]
    assert (segs[9]["action"], segs[9]["time"], segs[9]["weight"]) == ("Stomp", 1.0, 0.5)
    assert all(s["time"] == 0.0 for s in segs if s["index"] != 9)
    assert main(["compile", str(demo), "-o", str(out), "--time", "0.5"]) == 0
    segs = json.loads((out / "report.json").read_text())["tracks"]["c0"]["segments"]
    assert {s["action"] for s in segs if s["time"] == 0.5} == {"Jump", "Stomp"}  # one-shots; cyclic ones keep pace
    edits.write_text('{"segments": [{"track": "c0", "index": 1, "time": 3}]}')
    assert main(["compile", str(demo), "-o", str(out), "--edits", str(edits)]) == 1
    assert "'time' must be a number in [-1, 1]" in capsys.readouterr().err


def test_preferred_combination_keeps_timing_and_scales():
    from retarget.stylize import preferred

    clip, j = effector("Punch")
    strong = preferred(clip.motion, clip.stages, 0.0, 1.0)
    assert strong.frames == clip.motion.frames and strong.frame_time == clip.motion.frame_time
    assert amplitude(strong, j) > amplitude(clip.motion, j)
    assert preferred(clip.motion, clip.stages, 0.0, 0.0) is clip.motion


def test_compile_with_the_preferred_style(tmp_path):
    import json

    demo = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"
    out = tmp_path / "out"
    assert main(["compile", str(demo), "-o", str(out), "--time", "0.5", "--weight", "0.5", "--style", "preferred"]) == 0
    segs = json.loads((out / "report.json").read_text())["tracks"]["c0"]["segments"]
    assert {(s["action"], s["time"], s["weight"]) for s in segs if s["time"]} == {("Jump", 0.5, 0.5), ("Stomp", 0.5, 0.5)}


def test_weight_on_a_walk_cycle_keeps_the_loop_and_the_feet():
    from retarget.stylize import cyclic

    clip = CLIPS["Walk"][0]
    m = clip.motion
    hand, feet = clip.roles["right_hand"], [clip.roles["left_foot"], clip.roles["right_foot"]]
    before = forward_kinematics(m)[0]
    contact = foot_contacts(m, feet, world=before)
    strong, light = cyclic(m, 1.0), cyclic(m, -1.0)
    assert cyclic(m, 0.0) is m
    pelvis = clip.roles["pelvis"]

    def swing(motion):  # the hand's front-back swing relative to the hips
        w = forward_kinematics(motion)[0]
        return np.ptp(w[:, hand, 2] - w[:, pelvis, 2])

    assert swing(strong) > 1.3 * swing(m) and swing(light) < 0.8 * swing(m)
    for styled in (strong, light):
        assert styled.frames == m.frames and styled.frame_time == m.frame_time
        world = forward_kinematics(styled)[0]
        loop = np.abs(styled.rotations[-1] * np.sign(np.sum(styled.rotations[-1] * styled.rotations[0], -1))[:, None]
                      - styled.rotations[0]).max()
        assert loop < np.abs(m.rotations[-1] - m.rotations[0]).max() + 1e-3  # closes as well as the clip did
        for k, f in enumerate(feet):
            assert np.abs(world[contact[:, k], f, 1] - before[contact[:, k], f, 1]).max() < 0.01


def test_stylize_command_on_a_cycle(tmp_path):
    clip = Path(__file__).resolve().parents[1] / "library" / "builtin" / "clips" / "walk.bvh"
    out = tmp_path / "w.bvh"
    assert main(["stylize", str(clip), "--weight", "1", "--cyclic", "-o", str(out)]) == 0
    neutral, styled = read_bvh(clip, unit=1.0), read_bvh(out, unit=1.0)
    assert styled.frames == neutral.frames and styled.frame_time == pytest.approx(neutral.frame_time)
    assert not np.allclose(styled.rotations, neutral.rotations)


# --- signatures on real one-shots (held out: no constant was chosen on them) -------------------

HELD_OUT = ("bow", "bye", "byebye", "call", "guide", "kick", "punch", "respond", "slash")
STYLES = {"sudden": (1.0, 0.0), "sustained": (-1.0, 0.0), "strong": (0.0, 1.0), "light": (0.0, -1.0)}
STYLED = {**STYLES, "sudden light": (1.0, -1.0)}  # what the fixture below styles
# Known failures (bench.stylize_signatures prints the figures): none on these nine.
SIGNATURE_FAILS: set = set()
FEET_FAILS: set = set()


def _case(content, name, fails):
    marks = [pytest.mark.xfail(strict=True, reason="known, see SIGNATURE_FAILS")] if (content, name) in fails else []
    return pytest.param(content, name, marks=marks, id=f"{content}-{name}")


@pytest.fixture(scope="module")
def styled_bandai():
    from retarget.effort_signature import signature

    cache = {}

    def get(content, name):
        if (content, name) not in cache:
            path = BANDAI / f"dataset-1_{content}_normal_001.bvh"
            if not path.exists():
                pytest.skip("Bandai data not found")
            motion = read_bvh(path)
            out = stylize(motion, stages(motion), *STYLED[name])
            n = signature(motion)
            cache[content, name] = motion, out, n, signature(out, n.effector)
        return cache[content, name]

    return get


@pytest.mark.parametrize("content,name", [_case(c, n, SIGNATURE_FAILS) for c in HELD_OUT for n in STYLES])
def test_signature_moves_the_right_way(styled_bandai, content, name):
    """Sudden: peak speed up, execution shorter; Sustained the reverse; Strong: extent and
    impact sharpness up; Light: both down — and no joint faster than real hands and feet."""
    from retarget.effort_signature import FASTEST, SIGNATURES

    _, _, neutral, styled = styled_bandai(content, name)
    r = styled.ratios(neutral)
    for measure, direction in SIGNATURES[name].items():
        assert (r[measure] - 1.0) * direction > 0, (measure, r[measure])
    assert styled.fastest <= FASTEST


@pytest.mark.parametrize("content,name", [_case(c, n, FEET_FAILS) for c in HELD_OUT for n in STYLES])
def test_styled_feet_slide_no_more_and_nothing_pops(styled_bandai, content, name):
    from retarget.qa import check

    motion, out, _, _ = styled_bandai(content, name)
    after = check(out)
    assert not after.pops
    assert len(after.sliding) / out.frames <= sliding_share(motion, out.frame_time) + 1e-9


# Sudden Light with Time and Weight together: Time's signature against the neutral clip.
# Weight used to retime the whole clip over Time's retiming, and Light's evening-out undid
# Sudden (none of the nine was faster and shorter than neutral); now Weight keeps the durations
# Time gives its stages. Known failure: the slash (peak 3.9 -> 3.2 m/s, execution shorter).
SUDDEN_LIGHT_FAILS = {("slash", "sudden light")}


@pytest.mark.parametrize("content,name", [_case(c, "sudden light", SUDDEN_LIGHT_FAILS) for c in HELD_OUT])
def test_sudden_light_is_sudden(styled_bandai, content, name):
    from retarget.effort_signature import FASTEST

    _, _, neutral, styled = styled_bandai(content, name)
    assert styled.peak_speed > neutral.peak_speed and styled.execution < neutral.execution
    assert styled.fastest <= FASTEST


def test_measures_on_a_known_path():
    """Extent is the path's diameter; the burst's half-maximum width and the fall of speed
    after the peak are what a triangle of speed says."""
    from retarget.effort_signature import burst, extent, impact_sharpness

    assert extent(np.array([[0, 0, 0], [1, 0, 0], [0.5, 0.5, 0]], float)) == pytest.approx(1.0)
    tt = np.arange(0, 1.0001, 0.01)
    speed = np.maximum(0.0, 1 - np.abs(tt - 0.5) / 0.25) * 4.0  # 4 m/s peak, falls in 0.25 s
    a, k, b = burst(speed)
    assert k == 50 and (b - a) * 0.01 == pytest.approx(0.25, abs=0.02)
    assert impact_sharpness(tt, speed) == pytest.approx(16.0, rel=0.05)


# Built-in one-shots that popped once styled: hands or feet swept their End Sites (fingertips,
# toes) past a person's speed — the joints were bounded, the End Sites were not — or the body
# was jerked up out of a crouch with both feet on the floor (Duck, Pick up).
@pytest.mark.parametrize("name,lt,lw", [("Jump", 0.0, -1.0), ("Uppercut Jab", 1.0, 0.0), ("Uppercut Jab", 1.0, -1.0),
                                        ("Get Angry", 1.0, 0.0), ("Greet", 1.0, 1.0), ("Slapped", 1.0, 0.0),
                                        ("Duck", 0.0, 1.0), ("Pick up", 1.0, 0.0), ("Pick up", 1.0, 1.0)])
def test_styled_built_ins_do_not_pop(name, lt, lw):
    from retarget.effort_signature import FASTEST
    from retarget.qa import check

    clip = CLIPS[name][0]
    after = check(stylize(clip.motion, clip.stages, lt, lw))
    assert after.fastest <= FASTEST and not after.pops, (after.fastest, after.pops)


# Kicks whose styled kicking foot dragged along the floor: Weight widened the foot's path about
# its mean height, so the foot, below the mean through the wind-up, was pushed into the floor
# and held there while the neutral lifted it (then snapped up at 9 m/s).
@pytest.mark.parametrize("name,lt,lw", [("Crescent Kick", 0.0, 1.0), ("Kick", -1.0, -1.0)])
def test_a_styled_kick_lifts_its_foot(name, lt, lw):
    from retarget.analysis import guess_roles
    from retarget.qa import check

    clip = CLIPS[name][0]
    out = stylize(clip.motion, clip.stages, lt, lw)
    assert len(check(out).sliding) / out.frames <= sliding_share(clip.motion, out.frame_time) + 1e-9
    foot = guess_roles(out.skeleton)["right_foot"]  # the kicking foot
    neutral = forward_kinematics(clip.motion)[0][:, foot, 1]
    styled = forward_kinematics(out)[0][:, foot, 1]

    def clear(height):  # when the foot first stands 5 cm above its floor, as a share of the clip
        return np.argmax(height - neutral.min() > 0.05) / (len(height) - 1)

    assert styled.max() - neutral.min() > 0.3  # the kick happens
    assert clear(styled) <= clear(neutral) + 0.1


# Slowed by Sustained or Light, the flight of a jump, flip or back flip hung in the air for longer
# than any real jump (the animation check's hovering); how long a body stays up is gravity's.
@pytest.mark.parametrize("name,lt,lw", [("Jump", -1.0, 0.0), ("Jump", -1.0, -1.0), ("Flip", -1.0, 0.0),
                                        ("Flip", 0.0, -1.0), ("Back Flip", -1.0, 0.0), ("Back Flip", 0.0, -1.0)])
def test_a_styled_flight_does_not_hang_in_the_air(name, lt, lw):
    from retarget.qa import check

    clip = CLIPS[name][0]
    after = check(stylize(clip.motion, clip.stages, lt, lw))
    assert not after.hovering and after.passes, after.summary()


# Kicks whose styled toes went through the floor: Time's scaled wind-up or Light's narrowed path
# swung the kicking foot's toes below the floor the feet stand on — sinking, and the standing
# foot read as hovering above a floor that low for the whole clip.
@pytest.mark.parametrize("name,lt,lw", [("Kick", 1.0, 0.0), ("Kick", -1.0, 0.0), ("Kick", 1.0, -1.0),
                                        ("Kick", 0.0, -1.0), ("Crescent Kick", 0.0, -1.0),
                                        ("Crescent Kick", -1.0, -1.0)])
def test_a_styled_kick_keeps_its_toes_above_the_floor(name, lt, lw):
    from retarget.qa import check

    clip = CLIPS[name][0]
    after = check(stylize(clip.motion, clip.stages, lt, lw))
    assert after.passes and not after.sinking and not after.hovering, after.summary()


def _beat(motion, joint) -> float:
    """The median time between the acting hand's speed peaks: a wave's or a dance's stroke."""
    from scipy.signal import find_peaks

    from retarget.effort_signature import speed_profile

    t, v = speed_profile(motion, joint)
    peaks, _ = find_peaks(v, prominence=0.2 * np.median(v))
    return float(np.median(np.diff(t[peaks])))


@pytest.mark.parametrize("name", ["Dance", "wave-right-hand_normal_001", "wave-both-hands_normal_001"])
def test_sudden_quickens_every_stroke_of_a_repeated_movement(name):
    """A Sudden wave waves quickly, not just raises its arm quickly: the strokes that repeat the
    execution (a wave's swings, a dance's moves) were left at the neutral pace (their beat 0.99–
    1.03 × the neutral's) while Sustained slowed every one of them."""
    from retarget.effort_signature import most_moving

    if name in CLIPS:
        motion, st = CLIPS[name][0].motion, CLIPS[name][0].stages
    else:
        path = BANDAI.parent / "dataset-2" / f"dataset-2_{name}.bvh"
        if not path.exists():
            pytest.skip("Bandai data not found")
        motion = read_bvh(path)
        st = stages(motion)
    j = most_moving(motion)
    neutral = _beat(motion, j)
    assert _beat(stylize(motion, st, 1.0, 0.0), j) < 0.7 * neutral
    assert _beat(stylize(motion, st, 0.6, 0.0), j) < 0.8 * neutral
    assert _beat(stylize(motion, st, -1.0, 0.0), j) > 1.5 * neutral
