"""The Contexter (§6.2.1) and interaction constraints (§6.3): constraint formulas, their
parser and manifest fields, and two-character generated scenes — Colombine slapping Pierrot,
the Knight kissing the Witch — recognised only when close enough, overlapping and facing."""

from dataclasses import replace

import numpy as np
import pytest

from doodle.core.errors import DoodleError
from doodle.synth.strokes import stroke, synth_doodle
from grammar.constraints import (Behaviour, Constraint, State, ground_front, mutual_view, parse_constraint,
                                 sees, within, zone_distance)
from grammar.contexter import Contexter, InteractionSegment
from grammar.recognizer import recognize, recognize_interactions
from grammar.library import compile_library, overlaps
from grammar.matcher import Segment
from library.manifest import Interaction, builtin, format_library, load_library

# Here Slap, Slapped and Kiss are made ordinary actions with expressions of their own (Kiss
# the thesis's, §6.2.1), checked below not to overlap the table's; the built-in library's
# interaction-only roles (the thesis's §6.5 expressions) are tested at the end.
EXPRESSIONS = {"Slap": "(T_Y)+ (T_N_X_N_Y)+ (T_X_Z)+", "Slapped": "(T_N_Z)+ (T_X_Y)+ (T_N_X_N_Y)+",
               "Kiss": "(T_N_Z)+ (T_Z)+ (T_N_Z)+ (T_Z)+"}
LIBRARY = builtin()
LIBRARY = replace(LIBRARY, actions=tuple(replace(a, expression=EXPRESSIONS.get(a.name, a.expression),
                                                 interaction_only=False) for a in LIBRARY.actions))
COMPILED = compile_library(LIBRARY)
SLAP, SLAPPED = ["T_Y", "T_N_X_N_Y", "T_X_Z"], ["T_N_Z", "T_X_Y", "T_N_X_N_Y"]
KISS = ["T_N_Z", "T_Z", "T_N_Z", "T_Z"]
FACING = (0.0, 0.0, 0.0, 1.0)  # front +z
BACK = (0.0, 1.0, 0.0, 0.0)  # yawed 180°: front −z


def strokes(words, lead=0.4, tail=0.5):
    return [stroke("T_STILL", lead)] + [stroke(w, 0.3) for w in words] + [stroke("T_STILL", tail)]


def scene(a, b, gap, q0=FACING, q1=BACK, seed=1, lead_b=0.4):
    """c0 at the origin, c1 ``gap`` metres in front of it (+z), both 1 m up."""
    return synth_doodle({"c0": strokes(a), "c1": strokes(b, lead=lead_b)}, seed=seed,
                        start_p={"c0": (0.0, 1.0, 0.0), "c1": (0.0, 1.0, gap)}, start_q={"c0": q0, "c1": q1})


def labels(result):
    return {tr: [(s.action, getattr(s, "interaction", None), getattr(s, "role", None))
                 for s in segs if s.action != "Idle"] for tr, segs in result.items()}


# --- constraint formulas ------------------------------------------------------------------

def test_proxemic_zones_scale_with_the_radii():
    assert zone_distance("Intimate", 0.1, 0.1) == pytest.approx(0.2)
    assert zone_distance("personal", 0.1, 0.2) == pytest.approx(0.6)
    assert zone_distance("Social", 0.1, 0.1) == pytest.approx(0.8)
    assert zone_distance("Public", 0.1, 0.1) == pytest.approx(1.6)
    assert within([0, 0, 0], [0, 0.3, 0.4], 0.5) and not within([0, 0, 0], [0, 0.3, 0.4], 0.49)
    d = Constraint("D", 0, 1, "personal")
    here, there = State(np.zeros(3), np.array([0, 0, 1.0])), State(np.array([0, 0, 0.39]), np.array([0, 0, -1.0]))
    assert d.holds(here, there) and not d.holds(here, replace(there, position=np.array([0, 0, 0.41])))
    assert not Constraint("D", 0, 1, "intimate").holds(here, there)
    assert Constraint("D", 0, 1, "intimate").holds(replace(here, radius=0.3), there)  # bigger character
    assert Constraint("D", 0, 1, 0.5).holds(here, there)  # plain metres


def test_field_of_view_and_mutual_view():
    front = np.array([0.0, 0.0, 1.0])
    assert sees([0, 0, 0], front, [0, 0, 1], 0.99)
    assert sees([0, 0, 0], front, [1, 0, 1], 0.7) and not sees([0, 0, 0], front, [1, 0, 1], 0.72)  # cos 45°
    assert not sees([0, 0, 0], front, [0, 0, -1], 0.0)
    assert sees([0, 0, 0], front, [0, 5, 1], 0.99)  # height does not narrow the view (ground plane)
    assert mutual_view(front, -front, -0.9) and not mutual_view(front, front, -0.9)
    v, mv = Constraint("V", 0, 1, 0.5), Constraint("MV", 0, 1, -0.5)
    a, b = State(np.zeros(3), front), State(np.array([0, 0, 1.0]), -front)
    assert v.holds(a, b) and v.holds(b, a) and mv.holds(a, b)
    assert not mv.holds(a, replace(b, front=front))


def test_ground_front_of_quaternions():
    assert np.allclose(ground_front(FACING), [0, 0, 1])
    assert np.allclose(ground_front(BACK), [0, 0, -1])
    yaw90 = (0.0, np.sin(np.pi / 4), 0.0, np.cos(np.pi / 4))  # +z turned to +x
    assert np.allclose(ground_front(np.array([yaw90, FACING])), [[1, 0, 0], [0, 0, 1]])
    pitch = (-np.sin(np.pi / 8), 0.0, 0.0, np.cos(np.pi / 8))  # nose up 45°: still forward on the ground
    assert np.allclose(ground_front(pitch), [0, 0, 1])
    up = (-np.sin(np.pi / 4), 0.0, 0.0, np.cos(np.pi / 4))  # pointing straight up: no front
    assert np.allclose(ground_front(up), 0.0)


def test_constraints_at_every_sample_are_the_constraints_at_each():
    """The Contexter evaluates a constraint over all the samples of an overlap at once; each
    sample's answer is the one-state constraint's (the same arithmetic)."""
    rng = np.random.default_rng(3)
    p_i, p_j = rng.normal(0, 0.3, (200, 3)), rng.normal(0, 0.3, (200, 3))
    p_j[:5] = p_i[:5]  # at one place: nothing to look towards
    f_i, f_j = ground_front(rng.normal(size=(200, 4))), ground_front(rng.normal(size=(200, 4)))
    for c in (Constraint("D", 0, 1, "personal"), Constraint("D", 0, 1, 0.3), Constraint("V", 0, 1, 0.5),
              Constraint("V", 0, 1, -0.2), Constraint("MV", 0, 1, -0.5)):
        every = c.holds_all(p_i, f_i, 0.1, p_j, f_j, 0.12)
        each = [c.holds(State(a, b, 0.1), State(x, y, 0.12)) for a, b, x, y in zip(p_i, f_i, p_j, f_j)]
        assert every.tolist() == each and 0 < every.sum() < 200


def test_a_contexter_remembers_what_it_worked_out_of_one_doodle_only():
    slap = scene(SLAP, SLAPPED, 0.3)
    far = scene(SLAP, SLAPPED, 3.0)
    contexter = Contexter(COMPILED.library.interactions)
    for doodle, found in ((slap, 1), (far, 0), (slap, 1)):
        segments = {n: segs for n, (_, segs) in recognize(doodle, COMPILED, interactions=False).items()}
        assert len(contexter.select(doodle, segments)) == found


def test_behaviour_pre_and_post_conditions():
    fall = Behaviour(requires=frozenset({"standing"}), sets=frozenset({"fallen"}), clears=frozenset({"standing"}))
    assert fall.allowed(frozenset({"standing"})) and not fall.allowed(frozenset({"fallen"}))
    assert fall.after(frozenset({"standing", "angry"})) == {"fallen", "angry"}
    get_up = Behaviour(requires=frozenset({"fallen"}), sets=frozenset({"standing"}), clears=frozenset({"fallen"}))
    assert get_up.after(fall.after(frozenset({"standing"}))) == {"standing"}  # invertible (§6.3.3)


# --- parser and manifest ----------------------------------------------------------------------

@pytest.mark.parametrize("text, expected", [
    ("D(0, 1, Personal)", Constraint("D", 0, 1, "personal")),
    ("D(1,0,intimate)", Constraint("D", 1, 0, "intimate")),
    ("D(0, 1, 0.35)", Constraint("D", 0, 1, 0.35)),
    (" V( 1 , 0 , 0.5 ) ", Constraint("V", 1, 0, 0.5)),
    ("MV(0, 1, -0.5)", Constraint("MV", 0, 1, -0.5)),
])
def test_parse_good_constraints(text, expected):
    assert parse_constraint(text, "Slap", 2) == expected
    assert parse_constraint(str(expected), "Slap", 2) == expected  # str writes it back


@pytest.mark.parametrize("text, message", [
    ("D(0, 1, Near)", "not a number or a zone"),
    ("X(0, 1, 0.5)", "unknown kind 'X'"),
    ("V(0, 1)", "expected KIND(i, j, value)"),
    ("V(0, 0, 0.5)", "itself"),
    ("V(0, 2, 0.5)", "out of range"),
    ("V(a, 1, 0.5)", "whole numbers"),
    ("V(0, 1, 1.5)", "[-1, 1]"),
    ("D(0, 1, -1)", "negative"),
    ("D(0, 1, Personal", "expected KIND"),
])
def test_parse_malformed_constraints_name_the_interaction(text, message):
    with pytest.raises(DoodleError) as e:
        parse_constraint(text, "Slap", 2)
    assert "interaction 'Slap'" in str(e.value) and repr(text) in str(e.value) and message in str(e.value)


def test_builtin_interactions_carry_the_thesis_constraints():
    inter = {i.name: i for i in builtin().interactions}
    assert inter["Slap"].constraints == ("D(0, 1, Personal)", "V(0, 1, 0.5)", "V(1, 0, 0.5)")
    assert inter["Kiss"].constraints == ("D(0, 1, Intimate)", "V(0, 1, 0.5)", "V(1, 0, 0.5)")
    assert inter["Slap"].contact == ("right_hand", "head") and inter["Kiss"].contact == ("head", "head")


def _manifest(tmp_path, constraints):
    (tmp_path / "library.toml").write_text(
        '[library]\nname = "mine"\n\n[[actions]]\nname = "Hug"\nexpression = "(T_Z)+"\n\n'
        '[[actions]]\nname = "Hugged"\nexpression = "(T_N_Z)+"\n\n'
        f'[[interactions]]\nname = "Hug"\nactions = ["Hug", "Hugged"]\nconstraints = {constraints}\n')
    return tmp_path


def test_manifest_constraints_load_and_round_trip(tmp_path):
    lib = load_library(_manifest(tmp_path, '["D(0, 1, Intimate)", "MV(0, 1, -0.5)"]'))
    assert lib.interactions == (Interaction("Hug", ("Hug", "Hugged"), ("D(0, 1, Intimate)", "MV(0, 1, -0.5)")),)
    again = tmp_path / "again"
    again.mkdir()
    (again / "library.toml").write_text(format_library(lib, again))
    assert load_library(again).interactions == lib.interactions


@pytest.mark.parametrize("value, message", [('["D(0, 1, Near)"]', "constraint 'D(0, 1, Near)'"),
                                            ('["V(0, 3, 0.5)"]', "out of range"),
                                            ('"D(0, 1, Personal)"', "must be a list of strings")])
def test_manifest_rejects_bad_constraints_naming_file_and_interaction(tmp_path, value, message):
    with pytest.raises(DoodleError) as e:  # the library loader reads them; compiling checks their syntax
        compile_library(load_library(_manifest(tmp_path, value)))
    text = str(e.value)
    assert "library.toml" in text and "interaction 'Hug'" in text and message in text


# --- scenes ----------------------------------------------------------------------------------

def test_scene_expressions_do_not_overlap_the_table():
    assert not [o for o in overlaps(COMPILED) if {o.first, o.second} & set(EXPRESSIONS)]


def test_colombine_slaps_pierrot():
    """Close (0.3 m < Personal 0.4 m), overlapping, Colombine facing Pierrot: the interaction."""
    got = labels(recognize_interactions(scene(SLAP, SLAPPED, 0.3), COMPILED))
    assert got == {"c0": [("Slap", "Slap", 0)], "c1": [("Slapped", "Slap", 1)]}


@pytest.mark.parametrize("gap, q0, q1, why", [(0.6, FACING, BACK, "beyond Personal"),
                                              (0.3, BACK, BACK, "Colombine turned away: V(0, 1) fails")])
def test_slap_not_recognised_when_a_constraint_fails(gap, q0, q1, why):
    got = labels(recognize_interactions(scene(SLAP, SLAPPED, gap, q0, q1), COMPILED))
    assert got == {"c0": [("Slap", None, None)], "c1": [("Slapped", None, None)]}, why


def test_with_view_constraints_of_one_side_only():
    """An interaction whose only view constraint is the slapper's: Pierrot turned away is
    still slapped."""
    one_way = replace(LIBRARY, interactions=(Interaction("Slap", ("Slap", "Slapped"),
                                                          ("D(0, 1, Personal)", "V(0, 1, 0.5)")),))
    got = labels(recognize_interactions(scene(SLAP, SLAPPED, 0.3, FACING, FACING), compile_library(one_way)))
    assert got == {"c0": [("Slap", "Slap", 0)], "c1": [("Slapped", "Slap", 1)]}


def test_roles_follow_the_actions_whatever_the_track_order():
    got = labels(recognize_interactions(scene(SLAPPED, SLAP, 0.3, FACING, BACK), COMPILED))
    assert got == {"c0": [("Slapped", "Slap", 1)], "c1": [("Slap", "Slap", 0)]}


def test_actions_at_different_times_are_independent():
    late = 0.4 + 0.3 * len(SLAP) + 0.6  # Pierrot starts after Colombine is done
    got = labels(recognize_interactions(scene(SLAP, SLAPPED, 0.3, lead_b=late), COMPILED))
    assert got == {"c0": [("Slap", None, None)], "c1": [("Slapped", None, None)]}


def test_the_knight_kisses_the_witch():
    result = recognize_interactions(scene(KISS, KISS, 0.15, seed=2), COMPILED)
    assert labels(result) == {"c0": [("Kiss", "Kiss", 0)], "c1": [("Kiss", "Kiss", 1)]}
    kiss = [s for s in result["c0"] if s.action == "Kiss"][0]
    assert isinstance(kiss, InteractionSegment) and isinstance(kiss, Segment) and kiss.exact


@pytest.mark.parametrize("gap, q1, why", [(0.3, BACK, "beyond Intimate (0.2 m), within Personal"),
                                          (0.15, FACING, "the Witch turned away: V(1, 0) fails")])
def test_kiss_not_recognised_when_a_constraint_fails(gap, q1, why):
    got = labels(recognize_interactions(scene(KISS, KISS, gap, FACING, q1, seed=2), COMPILED))
    assert got == {"c0": [("Kiss", None, None)], "c1": [("Kiss", None, None)]}, why


def test_radius_and_mode_parameters():
    doodle = scene(KISS, KISS, 0.3, seed=2)
    assert labels(recognize_interactions(doodle, COMPILED, radius=0.2))["c0"] == [("Kiss", "Kiss", 0)]
    # the gesture moves the figurines back and forth: within Intimate at some sample, not all
    close = scene(KISS, KISS, 0.15, seed=2)
    assert labels(recognize_interactions(close, COMPILED, mode="all"))["c0"] == [("Kiss", None, None)]
    with pytest.raises(ValueError):
        Contexter(LIBRARY.interactions, mode="sometimes")


def test_a_segment_joins_at_most_one_interaction():
    """Three characters kissing side by side: the first pair found takes c1's kiss."""
    doodle = synth_doodle({n: strokes(KISS) for n in ("c0", "c1", "c2")}, seed=3,
                          start_p={"c0": (0, 1, 0), "c1": (0, 1, 0.15), "c2": (0.02, 1, 0.0)},
                          start_q={"c0": FACING, "c1": BACK, "c2": FACING})
    got = labels(recognize_interactions(doodle, COMPILED))
    roles = [got[n][0][1] for n in ("c0", "c1", "c2")]
    assert roles.count("Kiss") == 2 and got["c1"][0][1] == "Kiss"


# --- the built-in library: interaction-only roles (thesis §6.5) ----------------------------

BUILTIN = compile_library(builtin())


def test_builtin_slap_is_recognised_only_as_an_interaction():
    """Colombine performs the thesis's Slap ``(T_N_Z)+ T_Z`` (alone it reads as a step back
    and a step forward) while Pierrot keeps still in front of her, facing her: the Slap
    interaction; apart, the same motion stays two steps and a pause."""
    slap, still = ["T_N_Z", "T_Z"], []
    close = labels(recognize_interactions(scene(slap, still, 0.3), BUILTIN))
    assert close["c0"] == [("Slap", "Slap", 0)]
    assert ("Slapped", "Slap", 1) in [(a, i, r) for a, i, r in
                                      [(s.action, getattr(s, "interaction", None), getattr(s, "role", None))
                                       for s in recognize_interactions(scene(slap, still, 0.3), BUILTIN)["c1"]]]
    apart = labels(recognize_interactions(scene(slap, still, 1.0), BUILTIN))
    assert [a for a, i, _ in apart["c0"]] == ["Walk Back", "Walk"] and all(i is None for _, i, _ in apart["c0"])
    assert "Slap" not in BUILTIN.library.names and "Slap" in BUILTIN.roles.library.names


def test_the_slapping_hand_meets_the_head():
    """Placement and contact (§6.2.2): the characters are brought within reach, and at the
    contact frame the slapper's right hand is on the slapped character's head (the surfaces
    of their capsules within 1 cm)."""
    from doodle.app.pipeline import compile_doodle
    from retarget.analysis import guess_roles
    from retarget.qa import contact_gap

    a, b = compile_doodle(scene(["T_N_Z", "T_Z"], [], 0.3))
    (contact,) = a.contacts
    k = next(k for k, s in enumerate(a.segments) if getattr(s, "interaction", None) == "Slap")
    assert a.frame_ranges[k][0] < contact.frame < a.frame_ranges[k][1]
    gap = contact_gap(a.motion, b.motion, guess_roles(a.motion.skeleton)["right_hand"],
                      guess_roles(b.motion.skeleton)["head"], contact.frame)
    assert abs(gap) < 0.01


def test_a_two_character_slap_scene_compiles_with_the_interaction(tmp_path, capsys):
    """Colombine and Pierrot: one BVH per character on one timeline, the slap played by the
    Slap and Slapped clips, the interaction in report.json and in `doodle recognize`."""
    import json

    from doodle.app.cli.main import main
    from doodle.input.fileformat import write_doodle
    from doodle.app.pipeline import meet_distance
    from doodle.app.pipeline import load_for_compile

    path = tmp_path / "slap.doodle"
    write_doodle(path, scene(["T_N_Z", "T_Z"], [], 0.3))
    out = tmp_path / "out"
    assert main(["compile", str(path), "-o", str(out), "--no-effort"]) == 0
    report = json.loads((out / "report.json").read_text())
    c0 = [s for s in report["tracks"]["c0"]["segments"] if s["interaction"]]
    c1 = [s for s in report["tracks"]["c1"]["segments"] if s["interaction"]]
    assert [(s["action"], s["role"]) for s in c0] == [("Slap", 0)] and c0[0]["clip"].endswith("slap.bvh")
    assert [(s["action"], s["role"]) for s in c1] == [("Slapped", 1)] and c1[0]["clip"].endswith("slapped.bvh")
    assert report["tracks"]["c0"]["frames"] == report["tracks"]["c1"]["frames"]
    from retarget.bvh import read_bvh

    roots = [read_bvh(out / f"{tr}.bvh", unit=1.0).translations[0, 0] for tr in ("c0", "c1")]
    gap = np.linalg.norm((roots[1] - roots[0])[[0, 2]])
    actions = load_for_compile()
    want = meet_distance(next(i for i in actions.library.interactions if i.name == "Slap"), "Slap", "Slapped", actions)
    assert 0.4 < want < 0.9 and gap == pytest.approx(want, abs=0.01)  # 0.3 m of prop (2.5 m) brought within reach
    assert [i["interaction"] for i in report["interactions"]] == ["Slap"]
    capsys.readouterr()
    assert main(["recognize", str(path)]) == 0
    assert "Slap [Slap, role 0]" in capsys.readouterr().out


@pytest.mark.parametrize("compiled", ["ordinary roles", "builtin interaction-only roles"])
def test_streaming_contexter_equals_batch(compiled):
    """Tracks read in parallel (``doodle replay``): the interactions reported as the streams
    go are those the batch Contexter finds, each after both roles have ended, and none when
    the characters are apart."""
    from doodle.app.replay import replay

    lib = COMPILED if compiled == "ordinary roles" else BUILTIN
    # ordinary roles: three slaps in a row, so segments decided long ago are forgotten on the way
    a, b = ((SLAP + ["T_STILL"]) * 3, (SLAPPED + ["T_STILL"]) * 3) if lib is COMPILED else (["T_N_Z", "T_Z"], [])
    for gap, expect in ((0.3, True), (1.0, False)):
        doodle = scene(a, b, gap)
        batch = recognize_interactions(doodle, lib)
        want = sorted((tr, s.action, s.interaction, s.role) for tr, segs in batch.items() for s in segs
                      if isinstance(s, InteractionSegment))
        found = replay(doodle, lib).found
        got = sorted((r.track, r.action, r.interaction, r.role) for r in found if r.interaction)
        assert got == want and bool(got) == expect
        assert all(r.at >= r.end for r in found if r.interaction)


def test_replay_command_shows_interactions(tmp_path, capsys):
    from doodle.app.cli.main import main
    from doodle.input.fileformat import write_doodle

    path = tmp_path / "slap.doodle"
    write_doodle(path, scene(["T_N_Z", "T_Z"], [], 0.3))
    assert main(["replay", str(path), "--speed", "0"]) == 0
    out = capsys.readouterr().out
    assert "[Slap, role 0]" in out and "[Slap, role 1]" in out and "1 interaction(s)" in out


def test_placement_walks_in_and_back_with_time_inserted(tmp_path, capsys):
    """§6.2.2, first method: with ``placement = [0, 0.8, 180]`` Pierrot walks to 0.8 m in front
    of Colombine, turned to face her, before the slap and back afterwards; the walks' time is
    inserted into both characters' timelines, which stay in step."""
    import json

    from doodle.app.cli.main import main
    from doodle.input.fileformat import write_doodle
    from retarget.bvh import read_bvh

    lib = tmp_path / "lib"
    lib.mkdir()
    (lib / "library.toml").write_text('[library]\nname = "placed"\n\n[[interactions]]\nname = "Slap"\n'
                                      'actions = ["Slap", "Slapped"]\n'
                                      'constraints = ["D(0, 1, Personal)", "V(0, 1, 0.5)", "V(1, 0, 0.5)"]\n'
                                      'placement = [0, 0.8, 180]\n')
    path = tmp_path / "slap.doodle"
    doodle = scene(["T_N_Z", "T_Z"], [], 0.3)
    write_doodle(path, doodle)
    plain, placed = tmp_path / "plain", tmp_path / "placed"
    assert main(["compile", str(path), "-o", str(plain), "--no-effort"]) == 0
    assert main(["compile", str(path), "-o", str(placed), "--no-effort", "--library", str(lib)]) == 0
    report = json.loads((placed / "report.json").read_text())
    assert report["tracks"]["c0"]["frames"] == report["tracks"]["c1"]["frames"]
    frames = {d: json.loads((d / "report.json").read_text())["tracks"]["c0"]["frames"] for d in (plain, placed)}
    assert frames[placed] > frames[plain] + 30  # two walks of 2.5 − 0.8 m at 1 m/s, about 1.7 s each, at 30 fps
    roles = {tr: [s for s in report["tracks"][tr]["segments"] if s["interaction"]] for tr in ("c0", "c1")}
    assert [s["action"] for s in roles["c0"]] == ["Slap"] and [s["action"] for s in roles["c1"]] == ["Slapped"]
    motions = [read_bvh(placed / f"{tr}.bvh", unit=1.0) for tr in ("c0", "c1")]
    start = int(round(roles["c1"][0]["start"] * 30))
    a, b = (m.translations[start + 2, 0] for m in motions)
    assert np.linalg.norm((b - a)[[0, 2]]) == pytest.approx(0.8, abs=0.08)
    first, last = (m.translations[0, 0] for m in motions), (m.translations[-1, 0] for m in motions)
    gaps = [np.linalg.norm((y - x)[[0, 2]]) for x, y in (first, last)]
    assert gaps[0] == pytest.approx(2.55, abs=0.2) and gaps[1] == pytest.approx(2.55, abs=0.3)  # back where it was
    capsys.readouterr()


def test_place_moves_turns_and_keeps_tracks_in_step():
    from doodle.app.placement import interaction_pairs
    from grammar.recognizer import recognize
    from doodle.app.placement import place

    doodle = scene(["T_N_Z", "T_Z"], [], 0.3, q1=(0.0, 0.9239, 0.0, -0.3827))  # Pierrot turned 45° from her
    recognised = recognize(doodle, BUILTIN)
    assert interaction_pairs(recognised)
    placed = place(doodle, recognised, 8.5, {"Slap": (0.0, 0.8, 180.0)})
    c0, c1 = placed.tracks
    assert len(c0.t) == len(c1.t) > len(doodle.t) and np.all(np.diff(c0.t) > 0) and np.array_equal(c0.t, c1.t)
    again = recognize(placed, BUILTIN)
    (_, a, _, b), = interaction_pairs(again)
    i = b.start + 3
    assert np.linalg.norm((c1.p[i] - c0.p[i])[[0, 2]]) == pytest.approx(0.8 / 8.5, abs=0.01)
    assert ground_front(c1.q[i]) @ ground_front(c0.q[i]) == pytest.approx(-1.0, abs=0.02)  # face to face
    assert np.allclose(c1.p[-1], doodle.tracks[1].p[-1]) and np.allclose(c0.p[-1], doodle.tracks[0].p[-1])
    assert np.allclose(np.abs(c1.q[-1] @ doodle.tracks[1].q[-1]), 1.0)  # turned back as the doodle has it


@pytest.mark.parametrize("value", ['[0, 0.6]', '"near"', '[0, 0.6, true]', '[0, 0.6, nan]'])
def test_bad_placement_is_refused(tmp_path, value):
    (tmp_path / "library.toml").write_text('[library]\nname = "x"\n\n[[actions]]\nname = "A"\nexpression = "T_X"\n\n'
                                           '[[actions]]\nname = "B"\nexpression = "T_Y"\n\n[[interactions]]\n'
                                           f'name = "AB"\nactions = ["A", "B"]\nplacement = {value}\n')
    with pytest.raises(DoodleError, match="interaction 'AB': field 'placement' must be \\[x, z, turn\\]"):
        load_library(tmp_path)


def _pair_clip(folder, gap=0.9):
    """A two-character Slap clip: the built-in Slap, and Slapped standing ``gap`` m in
    front of it, turned to face it."""
    from scipy.spatial.transform import Rotation

    from retarget.bvh import write_bvh
    from retarget.clips import load_clips
    from retarget.pair import heading

    clips = load_clips(builtin())
    a, b = clips["Slap"][0].motion, clips["Slapped"][0].motion
    fa, fb = heading(a.rotations[0, 0]), heading(b.rotations[0, 0])
    yaw = Rotation.from_euler("y", np.arctan2(-fa[0], -fa[2]) - np.arctan2(fb[0], fb[2]))
    rots, trans = b.rotations.copy(), b.translations.copy()
    rots[:, 0] = (yaw * Rotation.from_quat(rots[:, 0])).as_quat()
    root = yaw.apply(trans[:, 0] - trans[0, 0]) + trans[0, 0]
    target = a.translations[0, 0] + gap * fa
    trans[:, 0] = root + (target - trans[0, 0]) * [1.0, 0.0, 1.0]
    write_bvh(folder / "pair_slap.bvh", a)
    write_bvh(folder / "pair_slapped.bvh", replace(b, rotations=rots, translations=trans))
    return a, replace(b, rotations=rots, translations=trans)


def test_placement_read_from_a_two_character_clip(tmp_path):
    """§6.2.2: the characters' relative placement at the first frame of a stored
    two-character clip (one BVH per character) places them when the interaction is played."""
    import json

    from doodle.app.cli.main import main
    from doodle.input.fileformat import write_doodle
    from retarget.bvh import read_bvh
    from retarget.pair import placement

    lib = tmp_path / "lib"
    lib.mkdir()
    first, second = _pair_clip(lib)
    x, z, turn = placement(first, second)
    assert x == pytest.approx(0.0, abs=1e-6) and z == pytest.approx(0.9, abs=1e-6) and abs(turn) == pytest.approx(180)
    (lib / "library.toml").write_text('[library]\nname = "paired"\n\n[[interactions]]\nname = "Slap"\n'
                                      'actions = ["Slap", "Slapped"]\n'
                                      'constraints = ["D(0, 1, Personal)", "V(0, 1, 0.5)", "V(1, 0, 0.5)"]\n'
                                      'pair = ["pair_slap.bvh", "pair_slapped.bvh"]\n')
    assert load_library(lib).interactions[0].pair == (str(lib / "pair_slap.bvh"), str(lib / "pair_slapped.bvh"))
    path = tmp_path / "slap.doodle"
    write_doodle(path, scene(["T_N_Z", "T_Z"], [], 0.3))
    out = tmp_path / "out"
    assert main(["compile", str(path), "-o", str(out), "--no-effort", "--library", str(lib)]) == 0
    report = json.loads((out / "report.json").read_text())
    role = [s for s in report["tracks"]["c1"]["segments"] if s["interaction"]][0]
    motions = [read_bvh(out / f"{tr}.bvh", unit=1.0) for tr in ("c0", "c1")]
    k = int(round(role["start"] * 30)) + 2
    assert np.linalg.norm((motions[1].translations[k, 0] - motions[0].translations[k, 0])[[0, 2]]) == \
        pytest.approx(0.9, abs=0.1)
