"""Learning actions from examples (§4.2.5): DTW averaging, the compact expression (accepts
every example — a property), tolerances, `doodle learn` on real Vive recordings, and bad input."""

from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from doodle.app.cli.main import main
from doodle.core.errors import DoodleError
from doodle.synth.strokes import stroke, synth_doodle
from doodle.core.tokens import NAMES
from grammar.learn import _dtw_path, dba, distances, expression_of, learn

VIVE = Path(__file__).resolve().parents[1].parent / "shared" / "data" / "vive-gestures"
MOVES = [n for n in NAMES if n != "T_STILL"]


def compacted(draw_list):
    out = []
    for x in draw_list:
        if not out or out[-1] != x:
            out.append(x)
    return tuple(out)


token_strings = st.lists(st.sampled_from(MOVES[:12]), min_size=1, max_size=12).map(compacted)


@settings(max_examples=60, deadline=None)
@given(st.lists(token_strings, min_size=2, max_size=5))
def test_every_example_is_accepted(strings):
    learned = expression_of(strings)
    for s in strings:
        assert distances([learned.expression], s)[0] == 0, (s, learned.expression)


def test_mandatory_tokens_and_quick_gestures():
    strings = [("T_Y", "T_Z", "R_X", "T_N_Y"), ("T_Y", "T_Z", "T_N_Y"), ("T_Y", "T_X", "T_Z", "T_N_Y"),
               ("T_Y", "T_Z", "T_N_Y")]
    learned = expression_of(strings)
    assert learned.mandatory == {"T_Y", "T_Z", "T_N_Y"}
    assert learned.expression == "T_Y+ (T_X)* T_Z+ (R_X)* T_N_Y+"
    same = expression_of([("T_Y", "R_X", "T_Z")] * 3)  # the same run everywhere: mandatory as it is
    assert same.expression == "T_Y+ R_X+ T_Z+"
    assert distances([learned.expression], ("T_Y", "T_Z", "T_X", "T_N_Y"))[0] == 1.0


def test_dtw_path_is_optimal():
    rng = np.random.default_rng(0)
    a, b = rng.normal(size=(15, 2)), rng.normal(size=(22, 2))
    n, m = len(a), len(b)
    c = ((a[:, None] - b[None]) ** 2).sum(2)
    D = np.full((n + 1, m + 1), np.inf)
    D[0, 0] = 0
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            D[i, j] = c[i - 1, j - 1] + min(D[i - 1, j - 1], D[i - 1, j], D[i, j - 1])
    i, j = _dtw_path(a, b)
    assert ((a[i] - b[j]) ** 2).sum() == pytest.approx(D[n, m])
    assert i[0] == j[0] == 0 and i[-1] == n - 1 and j[-1] == m - 1


def test_average_of_time_warped_copies_keeps_the_shape():
    d = synth_doodle({"c0": [stroke("T_STILL", 0.3), stroke("T_Z", 0.8), stroke("T_Y", 0.6), stroke("T_STILL", 0.3)]},
                     rate=90, seed=3, noise=0.0, tremor=0.0, drift=0.0)
    tr = d.track("c0")
    warped = []
    for k, power in enumerate((1.0, 0.8, 1.25)):
        u = (np.linspace(0, 1, len(tr.t)) ** power) * tr.t[-1]
        warped.append((tr.t, np.column_stack([np.interp(u, tr.t, tr.p[:, c]) for c in range(3)]), tr.q))
    avg = dba(warped)
    assert np.ptp(avg.p[:, 2]) == pytest.approx(np.ptp(tr.p[:, 2]), rel=0.05)
    assert np.ptp(avg.p[:, 1]) == pytest.approx(np.ptp(tr.p[:, 1]), rel=0.05)


def _synthetic(seed):
    d = synth_doodle({"c0": [stroke("T_STILL", 0.4), stroke("T_Z", 0.5), stroke("T_Y", 0.4), stroke("T_N_Z", 0.5),
                             stroke("T_STILL", 0.4)]}, rate=90, seed=seed)
    tr = d.track("c0")
    return tr.t, tr.p, tr.q


def test_learn_from_synthetic_examples_and_bad_input():
    examples = [_synthetic(s) for s in (1, 2, 3)]
    learned = learn(examples, 90.0)
    for s in learned.strings:
        assert distances([learned.expression], s)[0] == 0
    assert {"T_Z", "T_Y", "T_N_Z"} <= learned.mandatory
    assert 2.0 <= learned.tolerance <= 12.0
    t, p, q = examples[0]
    long = (np.concatenate([t, t[-1] + 0.01 + np.arange(11 * len(t)) / 90.0]),
            np.concatenate([p, np.repeat(p[-1:], 11 * len(t), 0)]), np.concatenate([q, np.repeat(q[-1:], 11 * len(t), 0)]))
    with pytest.raises(DoodleError, match="more than 10×"):
        learn([long, examples[1], examples[2]], 90.0)
    still = (t, np.repeat(p[:1], len(t), 0), np.repeat(q[:1], len(t), 0))
    with pytest.raises(DoodleError, match="example 2 is all still"):
        learn([examples[0], still, examples[2]], 90.0)
    with pytest.raises(DoodleError, match="at least 2 examples"):
        learn(examples[:1], 90.0)


def _vive(gesture, user="Sub_U001"):
    files = [VIVE / user / gesture / f"ex_{k}_moderate.csv" for k in range(5)]
    if not all(f.exists() for f in files):
        pytest.skip("real Vive recordings not found")
    return [str(f) for f in files]


def test_doodle_learn_then_recognize_a_held_out_performance(tmp_path, capsys):
    files = _vive("hook_left")
    lib = tmp_path / "mine"
    assert main(["learn", "Hook", *files[:3], "--library", str(lib), "--convention", "unity"]) == 0
    out = capsys.readouterr().out
    assert "Hook (c0" in out and "average" in out and (lib / "library.toml").exists()
    assert main(["recognize", "--library", str(lib), "--no-builtin", "--convention", "unity", "--json",
                 "--tracks", "c0", files[4]]) == 0
    import json

    segs = json.loads(capsys.readouterr().out)["segments"]
    hook = [s for s in segs if s["action"] == "Hook"]
    assert hook and sum(s["end"] - s["start"] for s in hook) > 0.6 * (segs[-1]["end"] - segs[0]["start"])
    assert main(["learn", "Hook", *files[:3], "--library", str(lib), "--convention", "unity"]) == 1
    assert "'Hook' exists already" in capsys.readouterr().err
    assert main(["learn", "Hook", *files[:3], "--library", str(lib), "--convention", "unity", "--replace"]) == 0
    capsys.readouterr()


def test_two_tracks_learn_one_two_handed_action(tmp_path, capsys):
    """``--tracks c0,c1`` learns one action performed with both hands; ``recognize --json``
    reports a held-out performance as that one action on both tracks, its name also the
    ``interaction`` (one decision over both tracks, not two halves that must both succeed)."""
    from library.manifest import load_library

    files = _vive("golf_swing")
    lib = tmp_path / "pair"
    assert main(["learn", "Golf", *files[:3], "--library", str(lib), "--convention", "unity",
                 "--tracks", "c0,c1"]) == 0
    library = load_library(lib)
    assert [(a.name, a.track, a.tracks) for a in library.actions] == [("Golf", "c0", ("c0", "c1"))]
    assert not library.interactions and library.actions[0].tolerance >= 2
    out = capsys.readouterr().out
    assert "Golf (c0+c1" in out and "overlap" in out
    import json

    assert main(["recognize", "--library", str(lib), "--no-builtin", "--convention", "unity", "--json",
                 files[4]]) == 0
    segs = json.loads(capsys.readouterr().out)["segments"]
    named = {(s["track"], s["action"], s["interaction"], s["role"]) for s in segs if s["action"] != "unknown"}
    assert named == {("c0", "Golf", "Golf", 0), ("c1", "Golf", "Golf", 1)}
    golf = {s["track"]: (s["start"], s["end"]) for s in segs if s["action"] == "Golf"}
    assert golf["c0"] == golf["c1"]  # the same moments on both hands
    assert main(["recognize", "--library", str(lib), "--no-builtin", "--convention", "unity", "--json",
                 "--tracks", "c0", files[4]]) == 0  # one hand alone is not the two-handed gesture
    assert all(s["action"] == "unknown" for s in json.loads(capsys.readouterr().out)["segments"])


def test_learn_command_bad_input(tmp_path, capsys):
    assert main(["learn", "X", "--library", str(tmp_path / "l"), "--record"]) == 1
    assert "SteamVR" in capsys.readouterr().err
    assert main(["learn", "X", str(tmp_path / "missing.doodle"), str(tmp_path / "m2.doodle"),
                 "--library", str(tmp_path / "l")]) == 1
    assert "missing.doodle" in capsys.readouterr().err
    assert not (tmp_path / "l" / "library.toml").exists()


def test_tolerance_field_and_per_action_limits(tmp_path):
    from grammar.library import compile_library
    from grammar.matcher import match
    from doodle.core.tokens import Token
    from library.manifest import format_library, load_library

    folder = tmp_path / "lib"
    folder.mkdir()
    (folder / "library.toml").write_text('[library]\nname = "t"\nformat = 1\n\n[[actions]]\nname = "Zig"\n'
                                         'expression = "T_X T_Y T_N_X T_Y T_X T_Y T_N_X T_Y"\ntolerance = 3\n')
    lib = load_library(folder)
    assert lib.action("Zig").tolerance == 3.0
    assert "tolerance = 3" in format_library(lib, folder)
    three_off = ["T_X", "T_Z", "T_N_X", "T_N_Z", "T_X", "R_Y", "T_N_X", "T_Y"]  # three substitutions
    tokens = [Token(n, k, k + 1) for k, n in enumerate(three_off)]
    assert [s.action for s in match(tokens, compile_library(lib).automaton())] == ["Zig"]
    strict = load_library(folder)
    strict = type(strict)(strict.name, (type(strict.actions[0])(**{**strict.actions[0].__dict__, "tolerance": None}),),
                          strict.source)
    assert [s.action for s in match(tokens, compile_library(strict).automaton())] == ["unknown"]
    (folder / "library.toml").write_text('[library]\nname = "t"\nformat = 1\n\n[[actions]]\nname = "Zig"\n'
                                         'expression = "T_X"\ntolerance = -1\n')
    with pytest.raises(DoodleError, match="action 'Zig': field 'tolerance' must be a number of edits"):
        load_library(folder)


def test_record_wizard_with_a_synthetic_source(tmp_path, monkeypatch, capsys):
    """`doodle learn NAME --record` through the recording loop: three takes, each between two
    trigger presses, then learned and saved (a synthetic source stands in for SteamVR)."""
    from doodle.app.cli import learn as cli_learn
    from doodle.input.sources import SyntheticSource

    seeds = iter(range(11, 30))

    def fake_source():
        d = synth_doodle({"c0": [stroke("T_STILL", 0.5), stroke("T_Z", 0.5), stroke("T_Y", 0.4), stroke("T_N_Z", 0.5),
                                 stroke("T_STILL", 0.5)]}, rate=90, seed=next(seeds))
        return SyntheticSource(d, triggers=[0.2, float(d.t[-1]) - 0.2])

    class OneTakePerSource:  # each take reads from a fresh performance
        def __init__(self):
            self.current = fake_source()
            self.tracks, self.rate, self.device = self.current.tracks, self.current.rate, self.current.device

        def read(self):
            frame = self.current.read()
            if frame is None:
                return None
            return frame

        def close(self):
            pass

    sources = OneTakePerSource()
    real_record = __import__("doodle.app.recorder", fromlist=["record"]).record

    def record_fresh(source, path, **kw):
        sources.current = fake_source()
        return real_record(sources, path, clock=lambda: 0.0, sleep=lambda s: None, **kw)

    monkeypatch.setattr(cli_learn, "open_source", lambda: sources)
    monkeypatch.setattr("doodle.app.recorder.record", record_fresh)
    monkeypatch.setattr(cli_learn, "COUNTDOWN", 0)
    lib = tmp_path / "wiz"
    assert main(["learn", "Hop", "--record", "--library", str(lib)]) == 0
    out = capsys.readouterr().out
    assert out.count("perform the gesture") == 3 and "Hop (c0" in out
    assert sorted(p.name for p in (lib / "takes").iterdir()) == ["Hop_1.doodle", "Hop_2.doodle", "Hop_3.doodle"]
    from library.manifest import load_library

    assert load_library(lib).names == ["Hop"]
    monkeypatch.undo()
    assert main(["learn", "X", "--record", "--library", str(tmp_path / "none")]) == 1
    assert "SteamVR" in capsys.readouterr().err


# --- the quick learning gives what the plain algorithms give -------------------------------

def _plain_dtw_paths(a, bs):
    """DTW alignments as learning first computed them: the cost matrix summed over the last
    axis, the rows' recurrence with fresh arrays, the walk back reading the costs."""
    k, m, _ = bs.shape
    n = len(a)
    cost = ((a[None, :, None, :] - bs[:, None, :, :]) ** 2).sum(axis=3)
    D = np.empty((k, n, m))
    D[:, 0] = np.cumsum(cost[:, 0], axis=1)
    for i in range(1, n):
        base = np.empty((k, m))
        base[:, 0] = cost[:, i, 0] + D[:, i - 1, 0]
        base[:, 1:] = cost[:, i, 1:] + np.minimum(D[:, i - 1, :-1], D[:, i - 1, 1:])
        c = np.cumsum(cost[:, i], axis=1)
        D[:, i] = np.minimum.accumulate(base - c, axis=1) + c
    out = []
    for Dk in D.tolist():
        i, j = n - 1, m - 1
        path = [(i, j)]
        while i > 0 or j > 0:
            if i == 0:
                j -= 1
            elif j == 0:
                i -= 1
            else:
                diag, up, left = Dk[i - 1][j - 1], Dk[i - 1][j], Dk[i][j - 1]
                if diag <= up and diag <= left:
                    i, j = i - 1, j - 1
                elif up <= left:
                    i -= 1
                else:
                    j -= 1
            path.append((i, j))
        ij = np.array(path[::-1])
        out.append((ij[:, 0], ij[:, 1]))
    return out


def _plain_dba(examples, points=128, iterations=8):
    """The DTW barycenter average as learning first computed it (one example at a time)."""
    from doodle.core import quat
    from grammar.learn import LEVER, _resample, canonical
    from grammar.shapes import dtw_costs

    feats, quats = [], []
    for t, p, q in examples:
        t, p, q = canonical(t, p, q)
        qs = _resample(t, q, points)
        quats.append(qs / np.linalg.norm(qs, axis=1, keepdims=True))
        feats.append(np.column_stack([_resample(t, p, points), LEVER * quat.log(quats[-1])]))
    stacked = np.array(feats)
    medoid = int(np.argmin(np.array([dtw_costs(f, stacked) for f in feats]).sum(axis=1)))
    avg, avg_q = feats[medoid].copy(), quats[medoid].copy()
    for _ in range(iterations):
        sums, qsum, counts = np.zeros_like(avg), np.zeros_like(avg_q), np.zeros(points)
        for f, qq, (i, j) in zip(feats, quats, _plain_dtw_paths(avg, stacked)):
            np.add.at(sums, i, f[j])
            signs = np.where(np.sum(qq[j] * avg_q[i], axis=1) < 0, -1.0, 1.0)
            np.add.at(qsum, i, qq[j] * signs[:, None])
            np.add.at(counts, i, 1)
        new = sums / counts[:, None]
        avg_q = qsum / np.linalg.norm(qsum, axis=1, keepdims=True)
        done = np.allclose(new, avg, atol=1e-6)
        avg = new
        if done:
            break
    return avg, avg_q


def _plain_tolerance(strings, examples):
    """Leave-one-out tolerance through the expressions' text, parsed and compiled to minimal DFAs."""
    from grammar.automata import compile_expression
    from grammar.expr import parse
    from grammar.learn import MAX_TOLERANCE, MIN_TOLERANCE, _edit_distance

    held = [k for k in range(examples) if any(s for j, s in enumerate(strings) if j != k)]
    worst = max(_edit_distance(compile_expression(parse(expression_of([s for j, s in enumerate(strings)
                                                                        if j != k]).expression)),
                               strings[k], MAX_TOLERANCE) for k in held)
    return float(np.clip(worst + 1.0, MIN_TOLERANCE, MAX_TOLERANCE))


def test_quick_dtw_paths_are_the_plain_ones():
    from grammar.learn import _dtw_paths

    rng = np.random.default_rng(5)
    for trial in range(60):
        n, m, k, d = rng.integers(2, 30), rng.integers(2, 30), rng.integers(1, 4), rng.integers(1, 10)
        a, bs = rng.normal(size=(n, d)), rng.normal(size=(k, m, d))
        if trial % 3 == 0:  # ties everywhere
            a, bs = np.round(a), np.round(bs)
        for (i, j), (pi, pj) in zip(_dtw_paths(a, bs), _plain_dtw_paths(a, bs), strict=True):
            assert np.array_equal(i, pi) and np.array_equal(j, pj)


@settings(max_examples=80, deadline=None)
@given(st.lists(token_strings, min_size=1, max_size=5))
def test_expression_tree_is_what_its_text_parses_to(strings):
    from grammar.expr import parse
    from grammar.learn import _expression

    learned, tree = _expression(strings)
    assert parse(learned.expression) == tree


@pytest.mark.parametrize("user,gesture,track,expression,tol", [
    ("Sub_U001", "hook_left", "c0",
     "((R_N_Y_Z T_N_X_N_Z R_X_Y))* (T_N_X | T_N_X_N_Z)+ (R_X_Y | (R_Y_N_Z R_X_N_Z) | T_N_X)* R_N_Z+ (R_N_X_N_Z)* "
     "T_N_X+ ((R_N_X_N_Z R_N_X_N_Y R_N_X_N_Y_Z R_N_Y_Z) | R_N_X_Z | T_N_X_Y)* R_Z+ T_X+ ((T_X_N_Y R_X_N_Z))* "
     "R_N_Z* ((R_N_Y_N_Z R_X_N_Z R_Y_N_Z T_N_X))*", 11.0),
    ("Sub_U004", "left_right_left_combo", "c0",
     "(R_X_Y | (R_Y_N_Z R_N_Z))* R_X_N_Z+ ((R_N_Z R_Y_N_Z R_X_Y) | (R_N_Z R_Y_N_Z R_Y R_X_Y) | R_X_Y_N_Z | "
     "(R_Y_N_Z R_X_Y R_X_Y_N_Z))* R_Y+ T_N_Y+ ((R_N_Y T_Y) | (R_N_Y T_Y R_N_Y R_N_X_Y R_N_X))* R_N_Y+ "
     "((R_N_Y_Z T_X R_Y R_N_X_Y) | (T_X R_Y R_N_X))* T_N_X+ ((T_N_X_Z R_N_X_Z R_Z) | (T_N_Y R_N_Y_Z R_N_Y R_X) | "
     "(T_N_Y_Z R_N_Y R_N_Y_Z))* (R_N_Y | R_N_Z | R_X_N_Z)+ (R_N_X_N_Z | R_N_Y_N_Z)* R_N_X+ "
     "(R_N_X_Z | (R_N_X_Z R_Z R_N_X_Z))*", 11.0),
])
def test_learning_real_gestures_as_before(user, gesture, track, expression, tol):
    """Learning was made quicker (alignments, automata, no parsing) without changing what it
    learns: on real recordings the average is the plain algorithm's to the bit, and the
    expression and tolerance are the ones learned before."""
    from doodle.core import quat
    from doodle.input.csvimport import read_csv

    doodles = [read_csv(f, convention="unity") for f in _vive(gesture, user)[:3]]
    examples = [(d.track(track).t, d.track(track).p, d.track(track).q) for d in doodles]
    avg, avg_q = _plain_dba(examples)
    quick = dba(examples)
    assert np.array_equal(quick.p, avg[:, :3])
    assert np.array_equal(quick.q, quat.make_continuous(avg_q))
    learned = learn(examples, doodles[0].rate)
    assert learned.expression == expression and learned.tolerance == tol
    assert _plain_tolerance(learned.strings, 3) == tol


def test_a_two_handed_action_compiles_where_it_was_performed(tmp_path, capsys):
    """Compiled, a learned two-handed action stays that action on both tracks: its
    characters are not walked up to each other as a Slap's are (nothing says they touch;
    moved, the second hand no longer made the gesture and the scene read c0 unknown, c1 Jump),
    and the missing clip is said, with where clips are listed."""
    import json

    files = _vive("backflip")
    lib = tmp_path / "pair"
    assert main(["learn", "Backflip", *files[:3], "--library", str(lib), "--convention", "unity",
                 "--tracks", "c0,c1"]) == 0
    capsys.readouterr()
    assert main(["compile", files[3], "--library", str(lib), "--convention", "unity", "-o", str(tmp_path / "out")]) == 0
    err = capsys.readouterr().err
    report = json.loads((tmp_path / "out" / "report.json").read_text())
    for track in ("c0", "c1"):
        assert [s["action"] for s in report["tracks"][track]["segments"]] == ["Backflip"], report["tracks"][track]
    assert "no clip of Backflip" in err and "clips = [" in err, err
