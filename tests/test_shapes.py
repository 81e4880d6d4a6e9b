"""Shapes of learned actions (grammar/shapes.py): DTW against many templates at once, the
shape file format, the Refiner (grammar/refiner.py; streaming equals batch), track binding, and recognition of
held-out real performances that tokens alone confuse."""

import json
from math import comb
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from doodle.app.cli.main import main
from doodle.core.errors import DoodleError
from grammar import refiner, shapes
from grammar.learn import _dtw_cost

VIVE = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "vive-gestures"


def _vive(gesture, user="Sub_U001"):
    files = [VIVE / user / gesture / f"ex_{k}_moderate.csv" for k in range(5)]
    if not all(f.exists() for f in files):
        pytest.skip("real Vive recordings not found")
    return [str(f) for f in files]


@settings(max_examples=25, deadline=None)
@given(st.integers(3, 12), st.integers(3, 12), st.integers(1, 4), st.integers(0, 2**31))
def test_batched_dtw_equals_one_by_one(n, m, k, seed):
    rng = np.random.default_rng(seed)
    x, templates = rng.normal(size=(n, 3)), rng.normal(size=(k, m, 3))
    one = shapes.dtw_costs(x, templates)
    assert np.allclose(one * max(n, m), [_dtw_cost(x, t) for t in templates])
    batch = shapes.dtw_costs(np.stack([x, x[::-1]]), templates)
    assert np.allclose(batch[0], one) and np.allclose(batch[1], shapes.dtw_costs(x[::-1], templates))


@settings(max_examples=25, deadline=None)
@given(st.integers(3, 12), st.integers(6, 15), st.integers(1, 4), st.integers(0, 2**31))
def test_a_beginning_is_found_by_open_ended_dtw(n, m, k, seed):
    """Open-ended (``part``): never more than to the whole template, zero for a template's
    own beginning within the part searched, and the cost to the whole when the part is the
    last step alone."""
    rng = np.random.default_rng(seed)
    x, templates = rng.normal(size=(n, 3)), rng.normal(size=(k, m, 3))
    whole = shapes.dtw_costs(x, templates)
    assert np.all(shapes.dtw_costs(x, templates, (0.0, 1.0)) <= whole + 1e-12)
    assert np.allclose(shapes.dtw_costs(x, templates, (1.0, 1.0)), whole)
    j = int(rng.integers((m - 1) // 3 + 1, m))  # a beginning of j steps of the first template
    part = shapes.dtw_costs(templates[0, :j], templates, (1 / 3, 1.0))
    assert part[0] < 1e-9 and part.shape == (k,)


def test_resampled_directions_ignore_speed_and_place():
    s = np.linspace(0, 1, 200)
    path = np.column_stack([np.cos(3 * s), np.sin(3 * s), s])
    slow = path[np.searchsorted(s, s ** 2)]  # the same path, travelled unevenly
    a = shapes.directions(shapes.resample(path))
    b = shapes.directions(shapes.resample(slow + [5.0, -2.0, 1.0]))
    assert a.shape == (shapes.POINTS - 1, 3) and np.allclose(np.linalg.norm(a, axis=1), 1.0)
    assert shapes.dtw_costs(a, b[None])[0] < 0.01
    assert shapes.dtw_costs(a, a[::-1][None])[0] > 1.0  # backwards is far
    assert np.all(shapes.resample(np.zeros((5, 3))) == 0)  # a still hand: no NaN


@settings(max_examples=25, deadline=None)
@given(st.sampled_from([30.0, 60.0, 90.0, 144.0]), st.floats(0.2, 5.0), st.floats(0.01, 10.0), st.integers(0, 2**31))
def test_the_time_gone_by_is_the_motion_s_whatever_its_rate_size_and_place(rate, seconds, size, seed):
    """:func:`shapes.times`: the share of the motion's time gone by at each resampled point
    rises from 0 to 1, and is the same however fast the motion is sampled, however large
    or long it is and wherever it is (within the sampling's resolution)."""
    rng = np.random.default_rng(seed)
    turns = rng.uniform(0.5, 3.0)

    def motion(t):  # uneven speed: slow, fast, slow
        u = t / seconds
        s = u - np.sin(2 * np.pi * u) / (2 * np.pi)
        return size * np.column_stack([np.cos(turns * s), np.sin(turns * s), s]) + rng.normal(size=3)

    def elapsed(r):
        t = np.arange(0.0, seconds + 1e-9, 1.0 / r)
        t = t if t[-1] == seconds else np.append(t, seconds)
        return shapes.times([(motion(t), np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1)))], t)

    fine, e = elapsed(1000.0), elapsed(rate)
    assert e[0] == 0.0 and e[-1] == 1.0 and np.all(np.diff(e) >= 0)
    assert np.abs(e - fine).max() < 0.05
    s = np.linspace(0, 1, shapes.POINTS)
    assert np.abs(fine - s).max() > 0.02  # uneven speed: the share of time is not the share of the path


def test_a_still_stretch_takes_time_not_path():
    """Arc-length resampling alone hardly sees a long still stretch (a hand held with
    tracking noise, then a curve); the time gone by does, and moves the steps after it away
    from the curve performed without it."""
    t = np.linspace(0.0, 3.0, 271)
    a = np.clip(t - 1.0, 0, None) * 1.5
    curve = np.column_stack([np.cos(a), np.sin(a), 0.2 * a]) * 0.3 + np.random.default_rng(0).normal(0, 3e-4, (271, 3))
    q = np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1))

    def read(k, pace):
        poses = [(curve[k:], q[k:])]
        return shapes.features(*shapes.sample(poses), 0.5, shapes.times(poses, t[k:]), pace)

    blind, timed = (shapes.dtw_costs(read(0, pace), read(91, pace)[None])[0] for pace in (0.0, 1.0))
    assert timed > blind + 0.02  # the still third of the time shifts the later steps' shares
    assert np.allclose(read(91, 1.0)[:, -1], (np.arange(shapes.POINTS - 1) + 0.5) / (shapes.POINTS - 1), atol=0.03)


def test_shape_files_round_trip_and_bad_files(tmp_path):
    paths = np.random.default_rng(0).normal(size=(3, shapes.POINTS, 3))
    good = tmp_path / "a.npz"
    shapes.save_paths(good, paths)
    assert np.array_equal(shapes.load_paths(good), paths)
    with pytest.raises(DoodleError, match="no such file"):
        shapes.load_paths(tmp_path / "missing.npz", "Wave")
    (tmp_path / "junk.npz").write_text("not a zip")
    with pytest.raises(DoodleError, match="junk.npz: not a valid .npz archive \\(not a zip archive\\)"):
        shapes.load_paths(tmp_path / "junk.npz")
    np.savez(tmp_path / "obj.npz", paths=np.array([{"x": 1}], dtype=object))
    with pytest.raises(DoodleError, match="obj.npz: not a valid .npz archive .*Python objects"):  # pickled objects are refused, never loaded
        shapes.load_paths(tmp_path / "obj.npz")
    np.savez(tmp_path / "flat.npz", paths=np.zeros((4, 3)))
    with pytest.raises(DoodleError, match="flat.npz.*examples, points"):
        shapes.load_paths(tmp_path / "flat.npz")
    bad = paths.copy()
    bad[0, 3, 1] = np.nan
    np.savez(tmp_path / "nan.npz", paths=bad)
    with pytest.raises(DoodleError, match="nan.npz.*NaN"):
        shapes.load_paths(tmp_path / "nan.npz", "Wave")


def _learn_all(tmp_path, gestures, user="Sub_U001"):
    lib = tmp_path / "mine"
    files = {}
    for g in gestures:
        files[g] = _vive(g, user)
        assert main(["learn", g, *files[g][:3], "--library", str(lib), "--convention", "unity", "--no-builtin"]) == 0
    return lib, files


ALL_GESTURES = ["backflip", "cartwheel_left", "cartwheel_right", "fly_eagle", "golf_swing", "hook_left", "hook_right",
                "left_right_left_combo", "right_left_right_combo", "uppercut_left", "uppercut_right"]  # every user's
CONFUSED = ["hook_right", "golf_swing", "uppercut_left", "uppercut_right", "left_right_left_combo",
            "right_left_right_combo"]  # Sub_U005's: token strings alone mistake five of their held-out takes


def test_held_out_performances_recognised_by_shape(tmp_path, capsys):
    """Six gestures of one person whose token strings are close (uppercuts, a hook, a golf
    swing and the combos of either hand): each held-out performance is reported as its
    action, covering most of it."""
    lib, files = _learn_all(tmp_path, CONFUSED, "Sub_U005")
    text = (lib / "library.toml").read_text()
    assert text.count("shape = \"shapes/") == len(CONFUSED) and (lib / "shapes" / "hook_right.npz").exists()
    capsys.readouterr()
    named_right = covering = 0
    for g in CONFUSED:
        for path in files[g][3:]:
            assert main(["recognize", "--library", str(lib), "--no-builtin", "--convention", "unity", "--json",
                         "--tracks", "c0", path]) == 0
            segs = json.loads(capsys.readouterr().out)["segments"]
            named = [s for s in segs if s["action"] != "unknown"]
            longest = max(named, key=lambda s: s["end"] - s["start"], default=None)
            named_right += longest is not None and longest["action"] == g
            covering += longest is not None and longest["action"] == g and \
                longest["end"] - longest["start"] > 0.5 * (segs[-1]["end"] - segs[0]["start"])
    assert named_right == 12
    assert covering >= 10  # 11 before groups stopped sharing runs (one take now covers less); token
    # expressions alone: 6 of 12 named and covering (measured in development)


def test_streaming_refiner_equals_batch(tmp_path):
    from doodle.input.loader import load
    from grammar.recognizer import load_actions, recognize
    from doodle.app.replay import replay

    lib, files = _learn_all(tmp_path, ["hook_left", "hook_right", "golf_swing"])
    compiled = load_actions(lib, False)
    assert compiled.shapes is not None and set(compiled.shapes.names) == {"hook_left", "hook_right", "golf_swing"}
    for path in (files["hook_left"][3], files["golf_swing"][4]):
        doodle = load(path, convention="unity")
        found = replay(doodle, compiled).found
        batch = recognize(doodle, compiled)
        expected = sorted((name, s.action, float(doodle.track(name).t[s.start]))
                          for name, (_, segs) in batch.items() for s in segs if s.action != "unknown")
        assert sorted((r.track, r.action, r.start) for r in found) == expected
        assert any(a in path for _, a, _ in expected)


def test_live_recording_reads_learned_shapes_as_recognize_does(tmp_path):
    """``doodle record`` goes through the one Recognizer: a learned gesture replayed through
    the recording loop is recognised live as ``doodle recognize`` reads the file it wrote."""
    from doodle.app.recorder import record
    from doodle.input.loader import load
    from doodle.input.sources import SyntheticSource
    from grammar.recognizer import load_actions, recognize

    lib, files = _learn_all(tmp_path, ["hook_left", "golf_swing"])
    compiled = load_actions(lib, False)
    doodle = load(files["hook_left"][3], convention="unity")
    now = [0.0]
    result = record(SyntheticSource(doodle), tmp_path / "live.doodle", clock=lambda: now[0],
                    sleep=lambda s: now.__setitem__(0, now[0] + max(s, 0.0)), compiled=compiled)
    on_file = recognize(load(result.path), compiled)
    want = [s.action for s in on_file["c0"][1] if s.action != "unknown"]
    assert "hook_left" in want
    assert [a for a, _, _ in result.actions["c0"]] == want
    assert [s.action for s in result.recognised["c0"][1]] == [s.action for s in on_file["c0"][1]]


def test_manifest_shape_and_track_fields(tmp_path):
    from library.manifest import format_library, load_library

    (tmp_path / "library.toml").write_text('[library]\nname = "x"\n\n[[actions]]\nname = "A"\n'
                                           'expression = "T_X T_Y"\nshape = "shapes/a.npz"\ntrack = "c1"\n')
    lib = load_library(tmp_path)
    assert lib.actions[0].shape == str(tmp_path / "shapes" / "a.npz") and lib.actions[0].track == "c1"
    (tmp_path / "again").mkdir()
    (tmp_path / "again" / "library.toml").write_text(format_library(lib, tmp_path))
    again = load_library(tmp_path / "again")
    assert again.actions[0].track == "c1" and again.actions[0].shape.endswith("shapes/a.npz")
    for field, value, message in (("shape", "1", "'shape' must be the path of a .npz"),
                                  ("shape", '"a.txt"', "'shape' must be"),
                                  ("track", '""', "'track' must be a track name")):
        (tmp_path / "library.toml").write_text(f'[library]\nname = "x"\n\n[[actions]]\nname = "A"\n'
                                               f'expression = "T_X"\n{field} = {value}\n')
        with pytest.raises(DoodleError, match=message):
            load_library(tmp_path)
    # a shape file that is not there: named when the library is compiled
    (tmp_path / "library.toml").write_text('[library]\nname = "x"\n\n[[actions]]\nname = "A"\n'
                                           'expression = "T_X T_Y"\nshape = "shapes/a.npz"\n')
    from grammar.library import compile_library

    with pytest.raises(DoodleError, match="a.npz \\(shape of action 'A'\\): no such file"):
        compile_library(load_library(tmp_path))


@settings(max_examples=25, deadline=None)
@given(st.integers(0, 2**31))
def test_turn_features_ignore_how_the_controller_is_held(seed):
    """The controller's turn is read relative to the window (``q(s) q̄⁻¹``): a grip offset
    (every orientation times one constant rotation on the right) changes nothing, while a
    different turn of the hand does."""
    from doodle.core import quat

    rng = np.random.default_rng(seed)
    n = 40
    path = np.cumsum(rng.normal(size=(n, 3)), axis=0)
    axis = rng.normal(size=3)
    spin = np.linspace(0, 2.0, n)[:, None] * axis / np.linalg.norm(axis)
    q = np.column_stack([np.sin(np.linalg.norm(spin, axis=1) / 2)[:, None] * spin
                         / np.maximum(np.linalg.norm(spin, axis=1, keepdims=True), 1e-12),
                         np.cos(np.linalg.norm(spin, axis=1) / 2)])
    grip = quat.normalise(rng.normal(size=(1, 4)))[0]
    held = quat.multiply(q, np.broadcast_to(grip, q.shape))
    a = shapes.features(*shapes.sample([(path, q)]), 0.5)
    b = shapes.features(*shapes.sample([(path, held)]), 0.5)
    assert a.shape == (shapes.POINTS - 1, 12) and np.allclose(a, b, atol=1e-9)
    still = np.tile([0.0, 0.0, 0.0, 1.0], (n, 1))
    assert not np.allclose(a, shapes.features(*shapes.sample([(path, still)]), 0.5), atol=1e-3)


def _twisted_arcs(rng, bend, twist, wobble, actions=6, per=5, n=40):
    """Examples of actions along arcs bent each its own way by ``bend``, the controller
    turned about an axis of its own by ``twist`` radians over the path, plus a random walk
    of its orientation (``wobble`` radians per sample: a controller held loosely)."""
    s = np.linspace(0.0, 1.0, n)
    out = []
    for a in range(actions):
        angle = 2 * np.pi * a / actions
        axis = np.array([np.cos(angle + 1), 0.3, np.sin(angle + 1)])
        paths, quats = [], []
        for _ in range(per):
            side = bend * np.array([np.cos(angle), np.sin(angle), 0.0])
            p = np.outer(s, [0.0, 0.0, 1.0]) + np.outer(np.sin(np.pi * s), side)
            p += rng.normal(scale=0.01, size=p.shape)
            spin = (twist * np.outer(s, axis / np.linalg.norm(axis))
                    + np.cumsum(rng.normal(scale=wobble, size=(n, 3)), axis=0))
            angles = np.linalg.norm(spin, axis=1, keepdims=True)
            q = np.column_stack([np.sin(angles / 2) * spin / np.maximum(angles, 1e-12), np.cos(angles / 2)])
            pp, qq = shapes.sample([(p, q)])
            paths.append(pp)
            quats.append(qq)
        out.append((a, np.array(paths), np.array(quats)))
    return out, np.repeat(np.arange(actions), per)


@pytest.mark.parametrize("bend, twist, wobble, expected", [
    (0.4, 1.0, 0.0, shapes.TURN),  # path and turn agree: nothing to gain, the default stays
    (0.4, 0.0, 0.5, 0.0),  # the turn is noise (held loosely): the path alone reads them
    (0.05, 0.5, 0.0, 1.0),  # the paths nearly alike, the turns tell them apart: more turn
])
def test_turn_weight_leaves_the_default_only_on_clear_evidence(bend, twist, wobble, expected):
    examples, owner = _twisted_arcs(np.random.default_rng(1), bend, twist, wobble)
    assert shapes.choose_turn(examples, owner) == expected


def test_prediction_bound_is_students_t():
    """The bound on a new draw from the root mean square of n: Student's t quantiles
    (tables: 12.706, 4.303, 3.182 at 95 % for 1, 2, 3 degrees of freedom; 5.841 at 99 % for
    3), falling towards the normal's 1.96 as the draws grow; nothing at level 0."""
    bound = shapes.prediction_bound
    assert [round(bound(0.95, n), 3) for n in (1, 2, 3)] == [12.706, 4.303, 3.182]
    assert round(bound(0.99, 3), 3) == 5.841 and abs(bound(0.95, 2000) - 1.96) < 0.002
    assert all(bound(0.95, n) > bound(0.95, n + 1) for n in range(1, 40))
    assert bound(0.0, 3) == 0.0
    rng = np.random.default_rng(0)  # and what it claims: a new draw falls within it 95 % of the time
    draws = rng.normal(size=(20000, 4))
    rms = np.sqrt(np.mean(draws[:, :3] ** 2, axis=1))
    assert abs(np.mean(np.abs(draws[:, 3]) <= bound(0.95, 3) * rms) - 0.95) < 0.005


def test_the_sign_test_behind_the_turn_weight():
    """A few more examples read right is chance (five of five: 1/32, not under 0.05 / 3)."""
    assert shapes._sign_test(5, 5) == pytest.approx(1 / 32)
    assert shapes._sign_test(0, 7) == 1.0 and shapes._sign_test(0, 0) == 1.0
    assert shapes._sign_test(8, 8) < shapes.EVIDENCE / 3 < shapes._sign_test(5, 5)
    assert shapes._sign_test(7, 10) == pytest.approx(sum(comb(10, j) for j in (7, 8, 9, 10)) / 1024)


def test_two_gestures_back_to_back_are_read_as_two(tmp_path):
    """Sub_U007's hook and uppercut performed without a pause between them: one motion,
    which the uppercut's examples fit as a whole — but the hook and the uppercut fit its two
    parts better than the uppercut fits it all, so both are read (in either order)."""
    from bench.learning_protocol import stream
    from doodle.input.loader import load
    from grammar.recognizer import load_actions, recognize

    gestures = ["hook_left", "hook_right", "golf_swing", "uppercut_left", "backflip"]
    lib, files = _learn_all(tmp_path, gestures, "Sub_U007")
    compiled = load_actions(lib, False)
    pieces = [(g, load(files[g][k], convention="unity").select(["c0"])) for g, k in (("hook_left", 4), ("uppercut_left", 3))]
    for order in (pieces, pieces[::-1]):
        doodle, spans = stream(order, np.random.default_rng(0), False)
        named = [s.action for s in recognize(doodle, compiled)["c0"][1] if s.action != "unknown"]
        assert named == [g for g, _, _ in spans]


def test_the_whole_motion_wins_over_a_part_nearer_another_gesture(tmp_path):
    """Sub_U007's held-out uppercuts: a part of each comes nearer the hook than the whole
    comes to the uppercut, and the Refiner once took that part for a hook. A window that
    leaves out motion between the pauses pays for it, so the whole is read, as the uppercut."""
    from doodle.input.loader import load
    from grammar.recognizer import load_actions, recognize

    gestures = ["hook_left", "uppercut_left", "hook_right", "uppercut_right"]
    lib, files = _learn_all(tmp_path, gestures, "Sub_U007")
    compiled = load_actions(lib, False)
    for path in files["uppercut_left"][3:]:
        doodle = load(path, convention="unity").select(["c0"])
        segs = [s for s in recognize(doodle, compiled)["c0"][1] if s.action != "unknown"]
        longest = max(segs, key=lambda s: s.end - s.start)
        assert longest.action == "uppercut_left"
        assert longest.end - longest.start > 0.6 * len(doodle.t)


def test_learned_gestures_read_as_built_in_pieces_are_the_learned_ones(tmp_path):
    """Sub_U001's held-out takes with the built-in actions beside the learned ones (what
    ``doodle recognize --library DIR`` loads): the Matcher reads some as pieces of built-in
    actions (a cartwheel as Dodge then Block, an uppercut as Punch then Walk Back); the
    motion between the pauses fits the learned action's shape, so it is that action."""
    from doodle.input.loader import load
    from grammar.recognizer import load_actions, recognize

    gestures = ["cartwheel_right", "hook_right", "uppercut_left", "uppercut_right"]
    lib, files = _learn_all(tmp_path, gestures)
    compiled = load_actions(lib, True)
    for g in gestures:
        for path in files[g][3:]:
            doodle = load(path, convention="unity").select(["c0"])
            assert [s.action for s in recognize(doodle, compiled)["c0"][1] if s.action not in ("unknown", "Idle")] == [g]


def test_built_in_actions_performed_whole_stay_built_in_beside_learned_ones(tmp_path):
    """Sub_U007's left hook hardly moves the right controller (c0), so its rejection
    distance is loose: read over any motion it would take built-in actions. A motion the
    Matcher reads whole as one built-in action stays that action."""
    from doodle.synth.performers import perform, style_grid
    from grammar.recognizer import load_actions, recognize

    lib, _ = _learn_all(tmp_path, ["hook_left"], "Sub_U007")
    compiled = load_actions(lib, True)
    for action in ("Pick up", "Dance", "Raise Arms"):
        for seed, style in enumerate(style_grid()[:6]):
            doodle, _ = perform(("Idle", action, "Idle"), style, seed)
            assert [s.action for s in recognize(doodle, compiled)["c0"][1] if s.action != "Idle"] == [action]


def test_a_motion_read_whole_as_a_built_in_action_is_the_learned_one_that_reads_it_as_well(tmp_path):
    """Sub_U001's uppercut (ex_1), the uppercut learned from ex_0, ex_2 and ex_3: the Matcher
    reads the whole motion as Stop, two edits from Stop's expression — and two from the
    uppercut's, whose shape fits it. The tokens do not prefer the built-in action, the shape
    is the user's: it is the uppercut (it was Stop)."""
    from bench.learning_protocol import load as load_vive, make_library
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U001"]
    gestures = ["uppercut_right", "uppercut_left", "hook_right", "hook_left"]
    lib = make_library(tmp_path / "mine", {g: [user[g][i] for i in (0, 2, 3)] for g in gestures}, ("c0",))
    compiled = load_actions(lib, True)
    named = [s.action for s in recognize(user["uppercut_right"][1].select(["c0"]), compiled)["c0"][1]
             if s.action not in ("unknown", "Idle")]
    assert named == ["uppercut_right"]


@pytest.mark.parametrize("name, gesture, take, trained", [("Sub_U001", "hook_left", 2, (0, 1, 4)),
                                                           ("Sub_U002", "uppercut_right", 0, (1, 2, 4))])
def test_a_motion_read_whole_as_a_built_in_action_is_the_learned_one_that_fits_it_closely(tmp_path, name, gesture,
                                                                                         take, trained):
    """Sub_U001's left hook read whole as Crescent Kick, Sub_U002's right uppercut as Flip,
    two edits from the built-in expression and three from the learned one's — whose shape
    fits the motion within SURE of its rejection distance: at one edit more, a shape that
    close is the user's (they were the built-in actions)."""
    from bench.learning_protocol import load as load_vive, make_library
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)[name]
    lib = make_library(tmp_path / "mine", {g: [user[g][i] for i in trained] for g in sorted(user)}, ("c0",))
    compiled = load_actions(lib, True)
    named = [s.action for s in recognize(user[gesture][take].select(["c0"]), compiled)["c0"][1]
             if s.action not in ("unknown", "Idle")]
    assert named == [gesture]


def test_two_learned_gestures_among_built_in_pieces(tmp_path):
    """Sub_U004's fly_eagle, left_right_left_combo, hook_left, right_left_right_combo and
    cartwheel_left back to back with both hands, the built-in actions beside the learned
    ones: the Matcher reads the hook and the start of the combo after it as built-in
    pieces, and the window over those pieces that fits best — the combo's — swallowed the
    hook. The hook and the combo fit the window's two parts better than the combo fits it
    whole: both are read (:meth:`Refiner._two`, as over a shaped segment's motion)."""
    from bench.learning_protocol import load as load_vive, make_library, stream
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U004"]
    lib = make_library(tmp_path / "mine", {g: user[g][:3] for g in sorted(user)}, ("c0", "c1"))

    class InOrder:
        def permutation(self, n):
            return np.arange(n)

    takes = (("fly_eagle", 3), ("left_right_left_combo", 3), ("hook_left", 4), ("right_left_right_combo", 3),
             ("cartwheel_left", 3))
    doodle, _ = stream([(g, user[g][k]) for g, k in takes], InOrder(), False)
    named = [s.action for s in recognize(doodle, load_actions(lib, True))["c0"][1] if s.action not in ("unknown", "Idle")]
    assert named == [g for g, _ in takes]


def test_a_gesture_read_as_a_built_in_piece_before_a_learned_segment(tmp_path):
    """Sub_U001's held-out takes back to back (the bench's first stream order), the built-in
    actions beside the learned ones: the Matcher reads the middle of a hook_right as
    Despair, one token, and the hook's end as the start of the fly_eagle after it. The
    windows around Despair may end where a learned segment's own windows may begin
    (within TRIM tokens of its start): the hook is read, and the fly_eagle after it."""
    from bench.learning_protocol import load as load_vive, make_library, stream
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U001"]
    lib = make_library(tmp_path / "mine", {g: user[g][:3] for g in sorted(user)}, ("c0",))
    pieces = [(g, d.select(["c0"])) for g in sorted(user) for d in user[g][3:5]]
    doodle, spans = stream(pieces, np.random.default_rng(0), False)
    found = recognize(doodle, load_actions(lib, True))["c0"][1]
    t = doodle.t
    for name, a, b in spans:
        if name in ("hook_right", "fly_eagle") and 36.0 < a < 40.0:  # the hook at 36.8 s, the fly_eagle after it
            assert any(s.action == name and t[s.start] < b and a < t[s.end - 1] for s in found), name


def test_a_gesture_the_matcher_cut_in_two_with_tokens_between(tmp_path):
    """Sub_U007's held-out takes back to back, one controller, the built-in actions beside
    the learned ones: the Matcher reads an uppercut_left (after a pause of the combo before
    it) as Despair, hook_right, one unknown token and hook_right again. A window may end
    where the second half ends — the Matcher may cut one gesture in two, with a few tokens
    between the halves as well as none —: the uppercut is read whole, not as two hook_lefts;
    live as in the batch."""
    from bench.learning_protocol import load as load_vive, make_library, stream
    from doodle.app.replay import replay
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")

    class InOrder:
        def permutation(self, n):
            return np.arange(n)

    user = load_vive(VIVE)["Sub_U007"]
    compiled = load_actions(make_library(tmp_path / "mine", {g: user[g][:3] for g in sorted(user)}, ("c0",)), True)
    takes = (("golf_swing", 4), ("left_right_left_combo", 3), ("uppercut_left", 3), ("hook_right", 4), ("fly_eagle", 3))
    doodle, _ = stream([(g, user[g][k].select(["c0"])) for g, k in takes], InOrder(), False)
    found = [s for s in recognize(doodle, compiled)["c0"][1] if s.action not in ("unknown", "Idle")]
    assert [s.action for s in found] == [g for g, _ in takes]
    live = [(r.action, r.start) for r in replay(doodle, compiled).found if r.action not in ("unknown", "Idle")]
    assert live == [(s.action, float(doodle.t[s.start])) for s in found]


@pytest.mark.parametrize("user,trained,gesture,take", [("Sub_U001", (0, 1, 4), "hook_left", 2),
                                                      ("Sub_U005", (0, 2, 3), "hook_right", 1)])
def test_a_two_handed_gesture_is_not_taken_by_built_in_readings_of_one_hand(tmp_path, user, trained, gesture, take):
    """Gestures learned with both hands, the built-in actions beside them; a held-out take
    read, batch and live, as its two-handed action on both tracks. Sub_U001's hook_left:
    the right hand reads whole as Crescent Kick at two edits, the hook's own expression at
    three — but the hook's shape fits both hands, and the left hand's Matcher read its
    movement there as no action: the two-handed action explains both hands. Sub_U005's
    hook_right starts with the tokens of the built-in Slap role (``(T_N_Z)+ T_Z``) while
    the left hand is still (Slapped, ``T_STILL+``): a role matched on the tokens alone does
    not take the place of the shape-decided gesture the user taught."""
    from bench.learning_protocol import load as load_vive, make_library
    from doodle.app.replay import replay
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    examples = load_vive(VIVE)[user]
    lib = make_library(tmp_path / "mine", {g: [examples[g][i] for i in trained] for g in sorted(examples)},
                       ("c0", "c1"))
    compiled = load_actions(lib, True)
    doodle = examples[gesture][take]
    batch = recognize(doodle, compiled)
    for track in ("c0", "c1"):
        assert [getattr(s, "interaction", s.action) for s in batch[track][1]
                if s.action not in ("unknown", "Idle")] == [gesture]
    expected = sorted((name, s.action, float(doodle.track(name).t[s.start]))
                      for name, (_, segs) in batch.items() for s in segs if s.action != "unknown")
    assert sorted((r.track, r.action, r.start) for r in replay(doodle, compiled).found) == expected


def test_a_character_at_rest_holds_back_no_other_characters_actions(tmp_path):
    """Live, beside a two-handed library (Sub_U001's gestures on c0+c1): a track the
    two-handed actions also read has its final actions heard once the first track has
    decided past them — but a first track at rest, whose pause goes on, decides nothing
    until it moves again. No two-handed action can start in a pause: the other character's
    actions are final as they end, not when the stream does (they were held to its end)."""
    from bench.learning_protocol import load as load_vive, make_library
    from doodle.app.replay import replay
    from doodle.core.model import Doodle, Track
    from doodle.synth.performers import perform, style_grid
    from grammar.recognizer import load_actions

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U001"]
    lib = make_library(tmp_path / "mine", {g: user[g][:3] for g in sorted(user)}, ("c0", "c1"))
    acting, _ = perform(("Idle", "Kick", "Idle", "Punch", "Idle", "Jump", "Idle"), style_grid()[0], 5, name="c1")
    b = acting.tracks[0]
    n = len(b.t)
    noise = np.random.default_rng(0).normal(0.0, 0.0003, (n, 3))
    resting = Track("c0", b.t, np.array([0.3, 1.0, 0.0]) + noise, np.tile([0.0, 0.0, 0.0, 1.0], (n, 1)), np.ones(n, bool))
    found = replay(Doodle((resting, b), acting.rate), load_actions(lib, True)).found
    heard = {f.action: f for f in found if f.track == "c1" and f.action != "Idle"}
    assert list(heard) == ["Kick", "Punch", "Jump"]
    assert heard["Kick"].at < heard["Jump"].start and heard["Punch"].at < b.t[-1] - 0.5


def test_two_performers_of_built_in_actions_beside_a_two_handed_library(tmp_path):
    """Two characters each performing built-in actions (generated performers, one per
    track), Sub_U007's gestures learned with both hands beside them: a two-handed action
    whose shape fits both hands does not take a motion one hand's Matcher reads whole as a
    built-in action while the other hand's movement is read as built-in actions too (each
    character doing its own): every action of the first character is read."""
    from bench.learning_protocol import load as load_vive, make_library
    from doodle.synth.performers import perform_two, style_grid
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U007"]
    lib = make_library(tmp_path / "mine", {g: user[g][:3] for g in sorted(user)}, ("c0", "c1"))
    compiled = load_actions(lib, True)
    style = next(s for s in style_grid() if s.label() == "size×0.7")
    first = ("Idle", "Despair", "Back Flip", "Dance", "Idle")
    doodle = perform_two(first, ("Idle", "Kick", "Pick up", "Side Walk Right", "Idle"), style, 920)
    named = [s.action for s in recognize(doodle, compiled)["c0"][1] if s.action not in ("unknown", "Idle")]
    assert named == [x for x in first if x != "Idle"]


def test_learned_gestures_back_to_back_beside_built_in_ones(tmp_path):
    """Sub_U005's held-out takes back to back, with the built-in actions beside the learned
    ones: with no pause to bound a motion, the Matcher read a combo as Cast Fireball, Side
    Walk Left, Walk Back and Dodge, and the end of a fly_eagle with an uppercut as Cast
    Fireball. A window that holds a built-in segment and more, cutting no other, and fits
    a learned action is that action: all three gestures of each stream are read, in order."""
    from bench.learning_protocol import stream
    from doodle.input.loader import load
    from grammar.recognizer import load_actions, recognize

    gestures = ALL_GESTURES
    lib, files = _learn_all(tmp_path, gestures, "Sub_U005")
    compiled = load_actions(lib, True)
    for takes in ((("right_left_right_combo", 4), ("cartwheel_right", 4), ("hook_right", 4)),
                  (("fly_eagle", 3), ("hook_right", 4), ("uppercut_right", 4))):
        pieces = [(g, load(files[g][k], convention="unity").select(["c0"])) for g, k in takes]
        doodle, spans = stream(pieces, np.random.default_rng(0), False)
        named = [s.action for s in recognize(doodle, compiled)["c0"][1] if s.action not in ("unknown", "Idle")]
        assert named == [g for g, _, _ in spans]


def test_two_learned_gestures_in_one_motion_of_built_in_pieces(tmp_path):
    """Gestures back to back, the built-in actions beside the learned ones, where one
    learned action's window held two gestures: Sub_U002's two uppercuts after a backflip,
    a motion the Matcher read in built-in pieces and a backflip's shape fitted whole;
    Sub_U005's hook_left and golf_swing, which the golf swing's window over the Matcher's
    two segments fitted. The two gestures fit the window's two parts better than one fits
    it: both are read (:meth:`Refiner._two`), as a shaped segment's motion is."""
    from bench.learning_protocol import stream
    from doodle.input.loader import load
    from grammar.recognizer import load_actions, recognize

    gestures = ALL_GESTURES

    class InOrder:
        def permutation(self, n):
            return np.arange(n)

    for user, takes in (("Sub_U002", (("hook_left", 3), ("backflip", 3), ("uppercut_left", 4), ("uppercut_right", 4))),
                        ("Sub_U005", (("uppercut_right", 3), ("cartwheel_left", 4), ("hook_left", 4),
                                      ("golf_swing", 3)))):
        lib, files = _learn_all(tmp_path / user, gestures, user)
        pieces = [(g, load(files[g][k], convention="unity").select(["c0"])) for g, k in takes]
        doodle, spans = stream(pieces, InOrder(), False)
        found = recognize(doodle, load_actions(lib, True))["c0"][1]
        assert [s.action for s in found if s.action not in ("unknown", "Idle")] == [g for g, _ in takes], user


@pytest.mark.parametrize("idle,builtin", [(True, False), (False, False), (True, True), (False, True)])
def test_streaming_refiner_equals_batch_across_gestures(tmp_path, idle, builtin):
    """Several performances in one stream, with pauses between them or back to back (and
    with the built-in actions beside the learned ones): the Refiner waits until the motion
    a segment lies in has ended, so live equals batch."""
    from bench.learning_protocol import stream
    from doodle.app.replay import replay
    from doodle.input.loader import load
    from grammar.recognizer import load_actions, recognize

    gestures = ["hook_left", "hook_right", "golf_swing", "uppercut_left"]
    lib, files = _learn_all(tmp_path, gestures)
    compiled = load_actions(lib, builtin)
    pieces = [(g, load(files[g][k], convention="unity").select(["c0"])) for g in gestures for k in (3, 4)]
    doodle, spans = stream(pieces, np.random.default_rng(1), idle)
    found = replay(doodle, compiled).found
    batch = recognize(doodle, compiled)
    expected = sorted((name, s.action, float(doodle.track(name).t[s.start]))
                      for name, (_, segs) in batch.items() for s in segs if s.action != "unknown")
    assert sorted((r.track, r.action, r.start) for r in found) == expected
    assert len(expected) >= len(spans) - 2


def test_gestures_back_to_back_in_a_long_unknown_run_are_all_found(tmp_path):
    """Sub_U002's punches and combos performed back to back with both hands, learned from
    ex_2..4 of every gesture: the Matcher leaves most of the stream to the Refiner as one
    unknown run longer than SPOT_MAX tokens, the gestures a short pause apart. It is
    searched a part at a time and, around each gesture found, for more: all four are read,
    in order (an unknown run once gave one action at most, and none past SPOT_MAX tokens),
    and live equals batch."""
    from bench.learning_protocol import load as load_vive, make_library, stream
    from doodle.app.replay import replay
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    data = load_vive(VIVE)
    user = data["Sub_U002"]
    lib = make_library(tmp_path / "mine", {g: user[g][2:5] for g in sorted(user)}, ("c0", "c1"))
    compiled = load_actions(lib, False)
    pieces = [(g, user[g][k]) for g, k in (("left_right_left_combo", 0), ("right_left_right_combo", 0),
                                           ("uppercut_left", 1), ("uppercut_right", 0))]
    doodle, spans = stream(pieces, np.random.default_rng(0), False)
    batch = recognize(doodle, compiled)
    assert [s.action for s in batch["c0"][1] if s.action != "unknown"] == [g for g, _, _ in spans]
    expected = sorted((name, s.action, float(doodle.track(name).t[s.start]))
                      for name, (_, segs) in batch.items() for s in segs if s.action != "unknown")
    assert sorted((r.track, r.action, r.start) for r in replay(doodle, compiled).found) == expected


def test_a_segment_with_no_pause_near_is_tried_as_two_gestures(tmp_path):
    """Sub_U005's golf swing, uppercut and combo back to back with both hands: the Matcher
    gives the golf swing a segment that runs on into the uppercut with no pause within
    SPOT_MAX tokens, so there is no motion between pauses to split. The segment's own
    tokens are tried as two gestures back to back, and the uppercut is read (it was lost)."""
    from bench.learning_protocol import load as load_vive, make_library, stream
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U005"]
    lib = make_library(tmp_path / "mine", {g: user[g][:3] for g in sorted(user)}, ("c0", "c1"))
    pieces = [(g, user[g][k]) for g, k in (("golf_swing", 4), ("uppercut_right", 4), ("left_right_left_combo", 3))]
    doodle, spans = stream(pieces, np.random.default_rng(1), False)
    named = [s.action for s in recognize(doodle, load_actions(lib, False))["c0"][1] if s.action != "unknown"]
    assert named == [g for g, _, _ in spans]


def test_a_small_gesture_after_a_long_one_is_not_taken_in_by_it(tmp_path, monkeypatch):
    """Sub_U004's left-right-left combo, then a left hook, back to back, read on c0 (the
    right hand, which the hook barely moves): shapes are resampled by arc length, so the
    combo's window run on over the hook fits the combo as well as its own span does, and
    the hook was lost. The combo's examples last under 3.5 s, that window over 5: it is not
    the combo (:data:`grammar.refiner.TEMPO`), and both are read."""
    from bench.learning_protocol import load as load_vive, make_library, stream
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U004"]
    lib = make_library(tmp_path / "mine", {g: [user[g][k] for k in (0, 1, 3)] for g in sorted(user)}, ("c0",))
    compiled = load_actions(lib, False)
    assert compiled.shapes.longest[compiled.shapes.names.index("left_right_left_combo")] < 3.5
    pieces = [(g, user[g][4]) for g in ("left_right_left_combo", "hook_left")]
    doodle, spans = stream(pieces, np.random.default_rng(0), False)

    def named():
        return [s.action for s in recognize(doodle, compiled)["c0"][1] if s.action != "unknown"]

    assert named() == [g for g, _, _ in spans]
    monkeypatch.setattr(refiner, "TEMPO", np.inf)  # durations not compared: the hook is taken in
    assert named() == ["left_right_left_combo"]


def test_gestures_in_a_pending_run_with_what_a_window_gave_up_are_searched(tmp_path, monkeypatch):
    """Sub_U004 on c0, back to back: a left hook, a left uppercut, fly_eagle. The Matcher
    reads the first two as one unknown run going on, with no pause, into fly_eagle, whose
    window then gives up its first tokens (the uppercut's end). The pending run, with what
    the window gave up, is searched whole once that window is chosen, and all three are
    read; without that search only fly_eagle is."""
    from bench.learning_protocol import load as load_vive, make_library, stream
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U004"]
    compiled = load_actions(make_library(tmp_path / "mine", {g: user[g][:3] for g in sorted(user)}, ("c0",)), False)
    gestures = ["hook_left", "uppercut_left", "fly_eagle"]
    doodle, _ = stream([(g, user[g][k]) for g, k in zip(gestures, (3, 3, 4))], np.random.default_rng(554), False)

    def named():
        return [s.action for s in recognize(doodle, compiled)["c0"][1] if s.action != "unknown"]

    assert named() == gestures
    monkeypatch.setattr(refiner.Refiner, "_spot_pending", lambda self, done, known: [])
    assert named() == ["fly_eagle"]


def test_a_small_gesture_after_a_large_one_is_not_swallowed_by_it(tmp_path, monkeypatch):
    """Sub_U007's held-out golf swing and then a left hook back to back (c0, where the hook
    moves the hand 10 cm against the swing's 1.5 m): by arc length alone the swing's window
    running on over the hook reads as the swing (the hook a few steps of path); with the
    share of time gone by (the hook lasts two of the window's five seconds), both are read.
    Shape files written without the times (libraries learned before) are read as before."""
    from bench.learning_protocol import load as load_vive, make_library, stream
    from grammar.recognizer import load_actions, recognize

    if not VIVE.is_dir():
        pytest.skip("real Vive recordings not found")
    user = load_vive(VIVE)["Sub_U007"]
    lib = make_library(tmp_path / "mine", {g: user[g][:3] for g in sorted(user)}, ("c0",))
    gestures = ["golf_swing", "hook_left"]
    doodle, _ = stream([(g, user[g][k]) for g, k in zip(gestures, (3, 4))], np.random.default_rng(0), False)

    def named():
        return [s.action for s in recognize(doodle, load_actions(lib, True))["c0"][1] if s.action not in ("unknown", "Idle")]

    assert named() == gestures
    monkeypatch.setattr(shapes, "PACE", 0.0)
    assert named() == ["golf_swing"]
    monkeypatch.undo()  # a library learned before times were kept is read as before, time left out
    for file in (lib / "shapes").glob("*.npz"):
        with np.load(file) as kept:
            arrays = {k: kept[k] for k in kept.files if k != "elapsed"}
        np.savez(file, **arrays)
    assert shapes.PACE > 0 and named() == ["golf_swing"]


def test_shape_files_keep_how_long_each_example_lasted(tmp_path):
    """``doodle learn`` writes each example's motion in seconds (its still ends left out)
    beside its shape, and the share of that time gone by at each point; files without them
    still load (no durations or times compared), and bad ones are refused with the file
    named."""
    lib, files = _learn_all(tmp_path, ["hook_right"])
    paths, quats, seconds, elapsed = shapes.load_shape(lib / "shapes" / "hook_right.npz")
    assert elapsed.shape == (3, shapes.POINTS) and np.all(np.diff(elapsed, axis=1) >= 0)
    assert np.all(elapsed[:, 0] < 0.2) and np.all(elapsed[:, -1] > 0.8)
    from doodle.input.csvimport import read_csv

    recorded = [read_csv(f, convention="unity").t for f in files["hook_right"][:3]]
    assert seconds.shape == (3,) and np.all(seconds > 0.5)
    assert np.all(seconds <= [t[-1] - t[0] for t in recorded])
    old = tmp_path / "old.npz"
    shapes.save_paths(old, paths, quats)
    assert shapes.load_shape(old)[2] is None and shapes.load_shape(old)[3] is None
    for bad in (np.array([1.0, -1.0, 2.0]), np.array([1.0, 2.0]), np.array([1.0, np.nan, 2.0])):
        np.savez(tmp_path / "bad.npz", paths=paths, quats=quats, format=np.array(2), seconds=bad)
        with pytest.raises(DoodleError, match="bad.npz.*'seconds' must be one positive duration per example"):
            shapes.load_shape(tmp_path / "bad.npz", "hook_right")
    for bad in (elapsed[:, ::-1], elapsed * 2, elapsed[:2], np.where(elapsed > 0.5, np.nan, elapsed)):
        np.savez(tmp_path / "bad.npz", paths=paths, quats=quats, format=np.array(2), seconds=seconds, elapsed=bad)
        with pytest.raises(DoodleError, match="bad.npz.*'elapsed' must be a float array"):
            shapes.load_shape(tmp_path / "bad.npz", "hook_right")
