"""Compiled animation an animator accepts: the animation check (retarget.qa, calibrated on
real motion capture) passes on compiled scenes — the main example as the bundled doodle,
styled by the effort model, on uneven terrain, performed by other people's styles, and
with a real mocap library — and the mechanisms behind it hold on their own: pacing that
keeps joints under a person's speed, feet that stand where they land and step instead of
shuffling, jumps that travel in the air."""

import warnings
from pathlib import Path

import numpy as np
import pytest

from doodle.app.pipeline import compile_doodle
from doodle.input.loader import load
from retarget.qa import check_scene

DEMO = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"
BANDAI = Path(__file__).resolve().parents[2] / "shared" / "data" / "mocap" / "bandai" / "dataset-1"


def _checked(doodle, **kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        results = compile_doodle(doodle, **kw)
    return results, check_scene({r.track: r.motion for r in results}, kw.get("terrain"),
                                contacts=results[0].contacts, soles={r.track: r.sole for r in results})


def _effort():
    from laban.models import load as load_model

    return load_model(None)


@pytest.mark.parametrize("scene", ["styled by the effort model", "Jacksboro terrain"])
def test_the_main_example_passes_the_animation_check(scene):
    from retarget.terrain import parse_terrain

    kw = {"effort_model": _effort()} if scene.startswith("styled") else {"terrain": parse_terrain("jacksboro")}
    _, checks = _checked(load(DEMO), **kw)
    c = checks["c0"]
    assert c.passes, c.summary()
    assert c.fastest < 15.0 and not c.sliding and not c.hovering


@pytest.mark.parametrize("style", ["tempo×1.6", "size×0.5", "flow", "wobble 5°",
                                   "size×0.5 tempo×0.6 pause 0.15 s 144 Hz tilt 20° wobble 2° bob 4 mm arc 0"])
def test_the_main_example_performed_by_other_styles_passes(style):
    """Performers the constants were not chosen on: slow and small ones (a jump in half a
    second borrows time from the stands around it), one without pauses, a wobbly hand, and a
    quick small one with short pauses (its jump, in 0.6 s, has too little time around it for
    the flight at its own pace: the arms swung at 18 m/s)."""
    from doodle.synth.performers import MAIN_EXAMPLE, perform, style_grid

    chosen = next(s for s in style_grid() if s.label() == style)
    doodle, _ = perform(MAIN_EXAMPLE, chosen, seed=3)
    _, checks = _checked(doodle, effort_model=_effort())
    assert checks["c0"].passes, checks["c0"].summary()


def test_a_doodle_faster_than_a_character_can_go_is_followed_at_its_pace_and_said():
    """The main example laid out at 40 × the doodle (its walks asked at up to 12.6 m/s, its
    jump 4.3 m in a 0.5 s flight): the walks keep to the path at 4 m/s and fall behind, the
    jump flies as far as the doodle asks (within 9 m/s), the animation passes the check
    (before: the walk cycles played several times their pace, joints at 22.6 m/s), and each
    walk is said, with where."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        results = compile_doodle(load(DEMO), scale=40.0)
    checks = check_scene({r.track: r.motion for r in results}, None, contacts=results[0].contacts,
                         soles={r.track: r.sole for r in results})
    assert checks["c0"].passes, checks["c0"].summary()
    said = [str(w.message) for w in caught]
    walks = [m for m in said if "faster than it can walk (4.0 m/s)" in m]
    assert len(walks) == 3 and walks[0].startswith("c0 0.96–1.76 s: the doodle moves the character at up to "), said
    assert not [m for m in said if "farther than its flight" in m], said  # 4.5 m in 0.5 s: it can
    r = results[0]
    speed = np.hypot(*np.diff(r.path[:, [0, 2]], axis=0).T) / r.motion.frame_time
    jump = next(fr for s, fr in zip(r.segments, r.frame_ranges) if s.action == "Jump")
    walking = np.ones(len(speed), bool)
    walking[jump[0]:jump[1]] = False
    assert speed[walking].max() <= 4.0 * 1.02 and speed.max() <= 9.0 * 1.02  # the jump's flight: at most 9 m/s


def test_a_one_shot_action_given_less_time_than_it_needs_is_said():
    """A quick small performer's jump (0.6 s, the stands around it too short to lend the rest)
    is played faster than a person jumps: compile says so, with where and how long it needs;
    the same jump performed at the main example's pace is not said."""
    from doodle.synth.performers import MAIN_EXAMPLE, perform, style_grid

    quick = next(s for s in style_grid() if s.label().startswith("size×0.5 tempo×0.6 pause 0.15 s"))
    for doodle, said_for in ((perform(MAIN_EXAMPLE, quick, seed=3)[0], True), (load(DEMO), False)):
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            compile_doodle(doodle)
        said = [str(w.message) for w in caught if "for every joint to keep under a person's fastest" in str(w.message)]
        if said_for:
            assert len(said) == 1 and said[0].startswith("c0 1.97–2.58 s: Jump has 0.61 s "), said
            assert "its clip needs 0.97 s" in said[0]
        else:
            assert said == []


@pytest.mark.skipif(not BANDAI.exists(), reason="needs ../shared/data/mocap/bandai")
def test_the_main_example_with_a_real_mocap_library_passes(tmp_path):
    """Bandai's skeleton (its foot joints inside the shoe, a helper root on the floor) with
    built-in clips retargeted where it has none."""
    from retarget.importer import import_library

    import_library(BANDAI, "bandai", tmp_path / "bandai", None, "*_normal_*")
    results, checks = _checked(load(DEMO), library_dir=tmp_path / "bandai")
    assert checks["c0"].passes, checks["c0"].summary()
    assert 0.0 <= results[0].sole < 0.06


# --- the mechanisms ------------------------------------------------------------------------

def _clip(name):
    from library.manifest import builtin
    from retarget.clips import load_clips

    return load_clips(builtin())[name][0]


def _peak(motion, u, knots, duration, fps=30.0):
    """Fastest joint (m/s) of ``motion`` played through pacing knots over ``duration`` s."""
    from retarget.sequence import _sample
    from retarget.skeleton import Motion, end_site_positions, forward_kinematics

    t = np.linspace(0.0, 1.0, int(round(duration * fps)) + 1)
    trans, rots = _sample(motion, np.interp(t, u, knots))
    played = Motion(motion.skeleton, trans, rots, 1.0 / fps)
    world = forward_kinematics(played)
    points = np.concatenate([world[0]] + [e[:, None] for e in end_site_positions(played, world).values()], axis=1)
    return float(np.linalg.norm(np.diff(points, axis=0), axis=2).max() * fps)


def test_pacing_keeps_joints_under_the_limit_and_the_flight_at_its_own_pace():
    from retarget.sequence import QUICKEST, paced, shortest

    jump = _clip("Jump")
    m = jump.motion
    end = (m.frames - 1) * m.frame_time
    uniform = _peak(m, np.array([0.0, 1.0]), np.array([0.0, end]), 1.0)
    assert uniform > 15.0  # squeezed evenly into a second, the jump whips
    flight = (0.85, 1.3)
    least = shortest(m, natural=flight)
    assert least < 0.7 * end  # the wind-up and the landing's recovery squeezed …
    assert least >= flight[1] - flight[0] + (end - (flight[1] - flight[0])) / QUICKEST - 1e-9  # … at most so much
    duration = 1.05 * least
    u, knots = paced(m, 0.0, None, duration, 11.0, flight)
    assert u[0] == 0.0 and u[-1] == pytest.approx(1.0) and np.all(np.diff(u) >= 0)
    assert _peak(m, u, knots, duration) < 12.0
    inside = (knots[1:] > flight[0]) & (knots[:-1] < flight[1])
    assert np.allclose(np.diff(u)[inside] * duration, np.diff(knots)[inside])  # the flight in real time
    rate = np.diff(knots) / (np.diff(u) * duration)  # clip seconds per second played
    assert rate.max() <= QUICKEST + 1e-6  # standing up from the landing is never a pop
    short = 0.7  # the flight (0.45 s) and the rest at the joints' limit take 0.88 s: the flight plays
    # quicker, the joints kept under the limit
    u, knots = paced(m, 0.0, None, short, 11.0, flight)
    assert _peak(m, u, knots, short) < 12.0 < _peak(m, np.array([0.0, 1.0]), np.array([0.0, end]), short)
    slow = paced(m, 0.0, None, 2 * end)  # never slowed below its own pace for speed
    assert np.allclose(slow[0], [0.0, 1.0])
    long = 1.5 * end  # a jump held longer than the clip: slowed, all but the flight
    u, knots = paced(m, 0.0, None, long, 11.0, flight)
    assert u[0] == 0.0 and u[-1] == pytest.approx(1.0) and np.all(np.diff(u) > 0)
    assert np.allclose(np.diff(u)[inside] * long, np.diff(knots)[inside])  # the flight in real time
    rate = np.diff(knots) / (np.diff(u) * long)
    assert rate.min() > 0.5 and np.abs(np.diff(rate)).max() < 0.1  # the rest slowed evenly, eased (no lurch)



@pytest.mark.parametrize("name,slower", [("Get Angry", 1.4), ("Stomp", 1.3), ("Kick", 1.6)])
def test_a_slowed_action_keeps_its_raised_foot_at_its_own_pace(name, slower):
    """A one-shot slowed to fill a long segment (a slow performer's) plays the frames where a
    foot is off the ground at the clip's own pace and lets its stances take the time: slowed
    evenly, a Get Angry held its stamping foot 22 cm up, nearly still, for 0.57 s (the check's
    held foot, 0.5 s). Not where the stances would freeze (a Kick's foot is up nearly all the
    clip): then it is slowed evenly, as before."""
    from retarget.sequence import paced

    c = _clip(name)
    m = c.motion
    raised = ~c.contacts.all(axis=1)
    assert raised.any() and not raised.all()
    end = (m.frames - 1) * m.frame_time
    long = slower * end
    u, knots = paced(m, 0.0, None, long, 11.0, None, raised)
    assert u[0] == 0.0 and u[-1] == pytest.approx(1.0) and np.all(np.diff(u) > 0)
    f = np.rint(knots / m.frame_time).astype(int)
    up = raised[f[:-1]] | raised[f[1:]]
    rate = np.diff(knots) / (np.diff(u) * long)  # clip seconds per second played
    if name == "Kick":
        assert np.allclose(rate, 1.0 / slower)
        return
    assert np.allclose(rate[up], 1.0)
    assert 0.5 <= rate.min() < 1.0 / slower and np.abs(np.diff(rate)).max() < 0.15  # the stances slowed, eased

def test_a_foot_the_blends_shuffle_takes_a_step_and_does_not_slide():
    """A standing pose whose right foot the motion drags 30 cm along the floor in three
    frames: pinned, the foot stands, then steps in an arc over a step's time."""
    from dataclasses import replace

    from retarget.feet import pin_feet
    from retarget.qa import check
    from retarget.skeleton import forward_kinematics

    idle = _clip("Idle")
    m = idle.motion.slice(0, 1)
    frames = 40
    trans = np.repeat(m.translations, frames, axis=0)
    rots = np.repeat(m.rotations, frames, axis=0)
    m = replace(m, translations=trans, rotations=rots)
    feet = [idle.roles["left_foot"], idle.roles["right_foot"]]
    shift = np.clip((np.arange(frames) - 18) / 3.0, 0.0, 1.0) * 0.3  # the body slides 30 cm right…
    moved = m.translations.copy()
    moved[:, 0, 0] -= shift
    m = replace(m, translations=moved)
    contacts = np.ones((frames, 2), dtype=bool)
    contacts[19:21, 1] = False  # …and the clips lift the right foot for two frames only
    pinned = pin_feet(m, feet, contacts=contacts, standing=None)
    world = forward_kinematics(pinned)[0]
    right = world[:, feet[1]]
    assert right[:, 1].max() - right[0, 1] > 0.04  # lifted in an arc
    assert np.linalg.norm(right[-1, [0, 2]] - right[0, [0, 2]]) > 0.25  # to its new spot
    c = check(pinned, ground=0.0)
    assert not c.sliding and not c.pops, c.summary()


def test_feet_in_the_air_go_with_the_body_however_far_it_flies():
    """A back flip carried 6 m through its 1 s flight (a large performer's doodle laid on the
    ground: faster than a step goes): between take-off and landing the feet are not the
    steps' business — pinned, they were dragged along a step's low arc under the flipping body
    and, in a compiled scene, snapped back at 17 m/s."""
    from dataclasses import replace

    from retarget.feet import pin_feet
    from retarget.qa import check
    from retarget.skeleton import forward_kinematics

    flip = _clip("Back Flip")
    m, contacts = flip.motion, flip.contacts
    air = np.flatnonzero(~contacts.any(axis=1))
    assert len(air) > 10
    moved = m.translations.copy()
    travel = np.clip((np.arange(m.frames) - air[0]) / (air[-1] - air[0]), 0.0, 1.0) * 6.0
    moved[:, 0, 2] += travel
    m = replace(m, translations=moved)
    feet = [flip.roles["left_foot"], flip.roles["right_foot"]]
    pinned = pin_feet(m, feet, contacts=contacts)
    before, after = forward_kinematics(m)[0], forward_kinematics(pinned)[0]
    mid = air[len(air) // 4: -len(air) // 4]  # the flight, away from the pins' fades
    assert np.abs(after[mid][:, feet] - before[mid][:, feet]).max() < 1e-3  # (the pelvis eased by µm)
    assert check(pinned, ground=0.0).fastest <= check(m, ground=0.0).fastest + 0.1  # no joint whipped faster


@pytest.mark.parametrize("scene", ["Flip, default performer", "Back Flip after a walk, short pauses"])
def test_a_landing_foot_is_not_held_up_by_its_pin(scene):
    """The Flip's clip lands with its ankles at the floor, heels or toes first: raised to the
    standing height by the pins, the feet hovered 5-9 cm for four frames. A back flip's
    toes-first landing, pulled down to the standing height as its pin faded in, went through
    the floor, and the body lifted out of it over the frames around left the feet off it a
    frame longer: a flight longer than any real one."""
    from doodle.synth.performers import perform, style_grid

    if scene.startswith("Flip"):
        actions, style, seed = ("Idle", "Flip", "Idle"), "default", 34
    else:
        actions, style, seed = ("Idle", "Walk", "Back Flip", "Side Walk Left", "Idle"), "pause 0.15 s", 33
    doodle, _ = perform(actions, next(s for s in style_grid() if s.label() == style), seed=seed)
    _, checks = _checked(doodle, effort_model=_effort())
    assert checks["c0"].passes and not checks["c0"].hovering, checks["c0"].summary()


@pytest.mark.parametrize("actions, seed", [(("Idle", "Walk", "Raise One Arm", "Side Walk Left", "Idle"), 33),
                                           (("Idle", "Dance", "Idle"), 21)])
def test_a_cross_fade_between_far_apart_poses_does_not_whip(actions, seed):
    """A quick small performer: the raised arm's return to rest trimmed away for want of
    time, a 0.2 s cross-fade into the stand after it swung the hand down at 17 m/s; the Dance's
    arms at 16 m/s into the Idle. A cross-fade now lasts as long as the gap between the two
    poses needs (up to 0.6 s)."""
    from doodle.synth.performers import perform, style_grid
    from retarget.sequence import BLEND, BLEND_MOST, blend_lengths

    quick = next(s for s in style_grid() if s.label().startswith("size×0.5 tempo×0.6 pause 0.15 s"))
    doodle, _ = perform(actions, quick, seed=seed)
    _, checks = _checked(doodle, effort_model=_effort())
    assert checks["c0"].passes and not checks["c0"].pops, checks["c0"].summary()
    assert list(blend_lengths([0.0, 0.3, 1.0, 9.0])) == pytest.approx([BLEND, BLEND, 0.43, BLEND_MOST], abs=0.01)


def test_a_cross_fade_into_a_stand_does_not_jerk_the_body_up():
    """A quick performer's Duck (tempo × 0.6, read Sudden Strong): its getting up trimmed
    for want of time, it rose on its own at 2.2 m/s as the cross-fade into the stand after it
    began, and the two together lifted the pelvis at 2.6 m/s with both feet on the floor (a
    pop). The fade now lasts as long as keeps the pelvis under the rise limit, the clips' own
    motion included (0.36 -> 0.51 s here)."""
    from doodle.synth.performers import perform, style_grid
    from retarget.qa import Limits
    from retarget.sequence import RISE_MARGIN
    from retarget.skeleton import forward_kinematics

    quick = next(s for s in style_grid() if s.label() == "tempo×0.6")
    doodle, _ = perform(("Idle", "Walk", "Duck", "Side Walk Left", "Idle"), quick, seed=35)
    results, checks = _checked(doodle, effort_model=_effort())
    assert checks["c0"].passes and not checks["c0"].pops, checks["c0"].summary()
    motion = results[0].motion
    pelvis = forward_kinematics(motion)[0][:, results[0].roles["pelvis"], 1]
    assert np.diff(pelvis).max() / motion.frame_time < RISE_MARGIN * Limits().rise


def test_a_pinned_foot_the_hip_stays_out_of_reach_of_takes_a_new_spot():
    """A foot the contacts hold where it landed while the body settles 25 cm away, short of
    the 35 cm that re-plants a foot: once the hip has been out of the leg's reach for a while
    (the foot flat), the foot steps to where the clips put it; a moment's stretch (a step's
    toe-off) or a new spot too near to step to does not move it."""
    from retarget.feet import STRETCHED, _pins

    fps, leg = 30.0, 0.83
    t = np.arange(40) / fps
    x = np.clip(t / 0.5, 0.0, 1.0) * 0.25  # the body (and the clips' foot) moves 25 cm, then stands
    ankle = np.column_stack([x, np.full(len(t), 0.08), np.zeros(len(t))])
    hip = np.column_stack([x + 0.25, np.full(len(t), 0.9), np.zeros(len(t))])  # the hip ahead of the foot
    contact = np.ones(len(t), dtype=bool)
    target, _, _ = _pins(ankle, contact, 3, None, 0.08, fps=fps, hip=hip, leg=leg)
    assert target[0, 0] == pytest.approx(0.0) and target[-1, 0] > 0.05  # stepped forward
    target, _, _ = _pins(ankle, contact, 3, None, 0.08, fps=fps)  # no hip: held where it landed
    assert np.allclose(target[:, 0], 0.0)
    brief = np.column_stack([np.full(len(t), 0.1), np.full(len(t), 0.9), np.zeros(len(t))])  # within reach ...
    brief[10:10 + int(STRETCHED * fps) - 1, 0] = 0.5  # ... but for a moment shorter than STRETCHED
    target, _, _ = _pins(ankle, contact, 3, None, 0.08, fps=fps, hip=brief, leg=leg)
    assert np.allclose(target[:, 0], 0.0)


def test_a_foot_landing_where_it_stood_keeps_its_footprint():
    """Two contacts of one foot a frame apart (the cross-fades' votes flickering) whose clips
    put it 3-4 cm apart: the same footprint, not a new spot 3-4 cm off that the foot slid to in
    one frame (a Kick's standing foot, 4.6 cm in 1/30 s: the check's sliding)."""
    from retarget.feet import _pins

    frames = 20
    ankle = np.column_stack([np.where(np.arange(frames) < 10, 0.0, 0.035), np.full(frames, 0.08), np.zeros(frames)])
    contact = np.ones(frames, dtype=bool)
    contact[9] = False
    target, weight, _ = _pins(ankle, contact, 3, None, 0.08)
    assert np.allclose(target[weight > 0, 0], 0.0)


def test_a_large_performers_kick_does_not_hang_its_standing_foot():
    """A large performer (size × 1.4): coming to a stand out of the walk, the left foot was
    held 31 cm behind where the stand puts it, and the Kick after it (read Sudden) rose onto
    its hop with that foot out of the leg's reach, 4–6 cm above the floor for half a second
    (the check's foot held in the air). It now steps under the body as the walk ends."""
    from doodle.synth.performers import perform, style_grid

    large = next(s for s in style_grid() if s.label() == "size×1.4")
    doodle, _ = perform(("Idle", "Walk", "Kick", "Side Walk Left", "Idle"), large, seed=35)
    _, checks = _checked(doodle, effort_model=_effort())
    assert checks["c0"].passes and not checks["c0"].hovering, checks["c0"].summary()


def test_a_jump_travels_in_a_straight_line_at_an_even_speed_in_the_air():
    from retarget.trajectory import Span, world_path

    t = np.linspace(0.0, 1.0, 91)
    rng = np.random.default_rng(0)
    p = np.column_stack([0.02 * np.sin(9 * t), 0.1 + 0.05 * np.sin(np.pi * t), 0.08 * t ** 2])  # a wobbly hop
    p += rng.normal(0.0, 0.001, p.shape)
    span = Span("Jump", 0.0, 1.0, 0, 91, False, True, False, (0.4, 0.7))
    path, _ = world_path(t, p, [span], 10.0)
    u = t / t[-1]
    before, during, after = u < 0.4, (u > 0.42) & (u < 0.68), u > 0.7
    assert np.ptp(path[before][:, [0, 2]], axis=0).max() < 1e-9 and np.ptp(path[after][:, [0, 2]], axis=0).max() < 1e-9
    speed = np.linalg.norm(np.diff(path[during][:, [0, 2]], axis=0), axis=1)
    assert np.ptp(speed) < 1e-9  # even
    line = path[-1] - path[0]
    d, a = path[during][:, [0, 2]] - path[0, [0, 2]], line[[0, 2]] / np.linalg.norm(line[[0, 2]])
    off = d[:, 0] * a[1] - d[:, 1] * a[0]
    assert np.abs(off).max() < 1e-9  # straight


def test_the_main_example_jump_neither_starts_nor_stops_moving_in_one_frame():
    """The main example's Jump travels 0.7 m: its root stood still until the feet left the
    floor, went at 1.35 m/s through the air, and stopped dead within two frames as they came
    down (the landing crouch sank straight down). Now the push-off gathers the speed and the
    landing sheds it: the root's speed over the ground changes by under 0.3 m/s a frame (9
    m/s², under 1 g)."""
    from retarget.skeleton import forward_kinematics

    results, _ = _checked(load(DEMO))
    r = results[0]
    k = next(i for i, s in enumerate(r.segments) if s.action == "Jump")
    f0, f1 = r.frame_ranges[k]
    pos = forward_kinematics(r.motion)[0]
    ground = np.linalg.norm(np.diff(pos[f0:f1 + 1, 0][:, [0, 2]], axis=0), axis=1) * r.motion.fps
    assert ground.max() > 0.5  # it travels
    assert np.abs(np.diff(ground)).max() < 0.3


def test_a_fast_jump_holds_no_foot_still_for_a_moment_while_it_lands():
    """Asked to jump at 8.6 m/s (the main example at ``--scale 80``, styled by the effort model), the built-in Jump's
    landing held a foot at one spot for the single frame the clip reads its toes on the floor
    as they come down (clip frame 40; 6 frames before the crouch's stance), while the body
    shed its speed over the ground: the foot snapped back at 17 m/s, a pop. A touch between a
    crouch and the flight is not a stance: the body moves over it."""
    _, checks = _checked(load(DEMO), scale=80.0, effort_model=_effort())  # as `doodle compile` does
    assert checks["c0"].passes, checks["c0"].summary()


def test_only_the_stances_at_a_jumps_crouches_hold_its_feet():
    """The built-in Jump's own contacts read each foot on the floor for one frame just before
    its take-off and at its landing (the toes brush it while the ankle slows); the stance it
    springs from and the one it lands into keep every frame, and every frame between them and
    the flight has the foot turning on its toes."""
    from retarget.timing import flight, push_off_contacts, push_off_rolls

    jump = _clip("Jump")
    contacts, ft = jump.contacts, jump.motion.frame_time
    air = flight(contacts)
    times = ((air[0] - 0.5) * ft, (air[-1] + 0.5) * ft)
    height = jump.motion.translations[:, jump.roles["pelvis"], 1]
    low = (int(np.argmin(height[:air[0]])) * ft, (air[-1] + int(np.argmin(height[air[-1]:]))) * ft)
    kept = push_off_contacts(contacts, ft, times, low)
    dropped = contacts & ~kept
    assert dropped.any(axis=1).sum() == 2  # the two one-frame touches, on both feet
    for f in np.flatnonzero(dropped.any(axis=1)):
        assert low[0] / ft < f < air[0] or air[-1] < f < low[1] / ft
    assert (kept <= contacts).all()
    stance = lambda c, at: c[int(round(at / ft))].all()  # noqa: E731
    assert stance(kept, low[0]) and stance(kept, low[1])
    # between the stances and the flight the feet turn on their toes: every frame, on both feet
    rolls = push_off_rolls(kept, ft, times, low)
    assert not (rolls & kept).any() and not rolls[air].any()
    between = np.zeros(len(kept), bool)
    between[int(round(low[0] / ft)):air[0]] = True
    between[air[-1] + 1:int(round(low[1] / ft)) + 1] = True
    assert ((rolls | kept)[between]).all()


def test_a_jumps_toes_stay_put_while_the_body_moves_over_them():
    """The main example's Jump gathers its speed over the ground during the push-off and sheds
    it during the landing; its toes skated along the floor meanwhile (toe joints on the floor
    moving at up to 1.0 m/s at the take-off, 0.6 at the landing: the feet went with the body,
    not held as the heel rose or came down). Now each foot turns on its toes where they are."""
    from retarget.skeleton import forward_kinematics

    results, _ = _checked(load(DEMO))
    r = results[0]
    k = next(i for i, s in enumerate(r.segments) if s.action == "Jump")
    f0, f1 = r.frame_ranges[k]
    pos = forward_kinematics(r.motion)[0]
    names = r.motion.skeleton.names
    root = np.linalg.norm(np.diff(pos[f0:f1 + 1, 0][:, [0, 2]], axis=0), axis=1) * r.motion.fps
    checked = 0
    for toe in (names.index("LeftToeBase"), names.index("RightToeBase")):
        y = pos[f0:f1 + 1, toe, 1]
        speed = np.linalg.norm(np.diff(pos[f0:f1 + 1, toe][:, [0, 2]], axis=0), axis=1) * r.motion.fps
        floor = y <= y.min() + 0.03
        # on the floor the frame before as well (not the step a landing foot comes down in), the body moving
        down = floor[1:] & floor[:-1] & np.concatenate([[False], floor[:-2]]) & (root > 0.1)
        checked += int(down.sum())
        assert speed[down].max() < 0.25, speed[down]
    assert checked >= 8  # the push-off's and the landing's frames are looked at


def test_the_root_stands_still_where_the_character_stands_after_a_jump():
    """The main example's Idle after its Jump stood where the doodle came down a sample before
    the Idle's segment starts, not where the jump had carried the root: the root jolted by a
    few millimetres in one frame as the stand began (0.23 m/s, the body otherwise still)."""
    from retarget.skeleton import forward_kinematics

    results, _ = _checked(load(DEMO))
    r = results[0]
    k = next(i for i, s in enumerate(r.segments) if s.action == "Jump")
    assert r.segments[k + 1].action == "Idle"
    f0, f1 = r.frame_ranges[k + 1]
    root = forward_kinematics(r.motion)[0][:, 0][:, [0, 2]]
    assert np.linalg.norm(np.diff(root[f0 - 6:f1], axis=0), axis=1).max() < 1e-3


def test_strides_lengthen_with_speed_within_range():
    from retarget.sequence import STRIDE_RANGE, stride_scale, travel_curve

    walk = _clip("Walk")
    natural = travel_curve(walk.motion, walk.roles["pelvis"])[-1] / walk.motion.duration
    assert stride_scale(walk.motion, walk.roles["pelvis"], natural) == pytest.approx(1.0)
    assert stride_scale(walk.motion, walk.roles["pelvis"], 1.69 * natural) == pytest.approx(1.3)
    assert stride_scale(walk.motion, walk.roles["pelvis"], 10 * natural) == pytest.approx(STRIDE_RANGE)
    assert stride_scale(walk.motion, walk.roles["pelvis"], 0.01 * natural) == pytest.approx(1 / STRIDE_RANGE)


def test_a_body_jerked_up_from_its_landing_crouch_is_a_pop_and_a_take_off_is_not():
    """The jump clip at its own pace passes the check (its push-off rises fast, but the feet
    leave the ground); the same clip with its landing recovery (crouch to standing, 15
    frames) played in two frames fails it, though no joint comes near the speed limit."""
    from retarget.qa import check
    from retarget.skeleton import Motion, forward_kinematics

    jump = _clip("Jump").motion
    own = check(jump, ground=0.0)
    assert own.passes, own.summary()
    y = forward_kinematics(jump)[0][:, 0, 1]
    crouch = 40 + int(np.argmin(y[40:]))  # the landing's deepest frame
    keep = list(range(crouch + 1)) + [crouch + (jump.frames - 1 - crouch) // 2, jump.frames - 1]
    popped = Motion(jump.skeleton, jump.translations[keep], jump.rotations[keep], jump.frame_time)
    c = check(popped, ground=0.0)
    assert c.fastest < c.limits.pop  # no joint too fast …
    assert not c.passes and c.pops and min(c.pops) > crouch  # … yet the stand-up is a pop


@pytest.mark.parametrize("action", ["Pick up", "Dance"])
def test_an_action_performed_at_a_pace_and_read_sudden_does_not_pop(action):
    """Performed by the synthetic performer, each is read Sudden. The Pick up's segment is
    shorter than the styled clip, and pacing squeezed its rise out of the crouch (both feet
    flat) to 2.9 m/s; pacing now bounds that rise as the stylisation does. The Dance's fastest
    moment is its arms coming down to rest: made Sudden as if it were the execution, they
    whipped into the Idle after it at 16 m/s; a burst ending the clip is not its execution."""
    from doodle.synth.performers import perform

    doodle, _ = perform(("Idle", action, "Idle"), seed=21)
    _, checks = _checked(doodle, effort_model=_effort())
    assert checks["c0"].passes and not checks["c0"].pops, checks["c0"].summary()
