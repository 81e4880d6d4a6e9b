"""Two-handed learned actions (``doodle learn --tracks c0,c1``): one gesture read over both
tracks — ``recognize --json`` names it on both, replay hears it on both and ends where the
batch does — on generated two-hand performances."""

import json

import numpy as np
import pytest

from doodle.app.cli.main import main
from doodle.input.fileformat import write_doodle
from doodle.synth.strokes import stroke, synth_doodle

GESTURES = {  # per hand, the strokes of a two-handed gesture
    "Clap": (["T_X", "T_N_X"], ["T_N_X", "T_X"]),
    "Lift": (["T_Y", "T_Z", "T_N_Y"], ["T_Y", "T_Z", "T_N_Y"]),
}


def _take(name, seed):
    right, left = GESTURES[name]

    def strokes(words):
        return [stroke("T_STILL", 0.4)] + [stroke(w, 0.35) for w in words] + [stroke("T_STILL", 0.4)]

    return synth_doodle({"c0": strokes(right), "c1": strokes(left)}, seed=seed,
                        start_p={"c0": (0.2, 1.0, 0.0), "c1": (-0.2, 1.0, 0.0)})


@pytest.fixture(scope="module")
def library(tmp_path_factory):
    root = tmp_path_factory.mktemp("two")
    lib = root / "lib"
    for name in GESTURES:
        files = []
        for seed in (1, 2, 3):
            path = root / f"{name}_{seed}.doodle"
            write_doodle(path, _take(name, seed))
            files.append(str(path))
        assert main(["learn", name, *files, "--library", str(lib), "--tracks", "c0,c1", "--no-builtin"]) == 0
    held = {}
    for name in GESTURES:
        held[name] = root / f"{name}_held.doodle"
        write_doodle(held[name], _take(name, 11))
    return lib, held


@pytest.mark.parametrize("name", list(GESTURES))
def test_recognize_names_the_two_handed_action_on_both_tracks(library, name, capsys):
    lib, held = library
    capsys.readouterr()
    assert main(["recognize", "--library", str(lib), "--no-builtin", "--json", str(held[name])]) == 0
    segs = json.loads(capsys.readouterr().out)["segments"]
    named = [s for s in segs if s["action"] != "unknown"]
    assert {(s["track"], s["action"], s["interaction"], s["role"]) for s in named} == \
        {("c0", name, name, 0), ("c1", name, name, 1)}
    (a,), (b,) = ([s for s in named if s["track"] == t] for t in ("c0", "c1"))
    assert (a["start"], a["end"]) == (b["start"], b["end"])
    for track in ("c0", "c1"):  # each track's segments still tile it in order
        mine = [s for s in segs if s["track"] == track]
        assert all(x["samples"][1] <= y["samples"][0] for x, y in zip(mine, mine[1:]))


def test_replay_hears_the_pair_on_both_tracks_and_ends_as_recognize(library):
    from doodle.app.replay import replay
    from doodle.input.loader import load
    from grammar.recognizer import load_actions, recognize

    lib, held = library
    compiled = load_actions(lib, False)
    doodle = load(held["Clap"])
    done = replay(doodle, compiled)
    heard = {(r.track, r.action, r.interaction) for r in done.found}
    assert heard == {("c0", "Clap", "Clap"), ("c1", "Clap", "Clap")}
    batch = recognize(doodle, compiled)
    for track, (_, segs) in batch.items():
        assert [(s.action, s.start, s.end) for s in done.result[track][1]] == [(s.action, s.start, s.end) for s in segs]


def test_manifest_tracks_field(tmp_path):
    from doodle.core.errors import DoodleError
    from library.manifest import format_library, load_library

    (tmp_path / "library.toml").write_text('[library]\nname = "x"\n\n[[actions]]\nname = "A"\n'
                                           'expression = "T_X"\ntracks = ["c0", "c1"]\n')
    lib = load_library(tmp_path)
    assert lib.actions[0].track == "c0" and lib.actions[0].tracks == ("c0", "c1")
    (tmp_path / "again").mkdir()
    (tmp_path / "again" / "library.toml").write_text(format_library(lib, tmp_path))
    assert load_library(tmp_path / "again").actions[0].tracks == ("c0", "c1")
    (tmp_path / "library.toml").write_text('[library]\nname = "x"\n\n[[actions]]\nname = "A"\n'
                                           'expression = "T_X"\ntrack = "c1"\ntracks = ["c0", "c1"]\n')
    with pytest.raises(DoodleError, match="'tracks'"):
        load_library(tmp_path)


def test_derived_rejection_separates_own_examples_from_straddles():
    """The rejection distance is at least the examples' own spread, and a window across two
    performances (the end of one, the start of another) is farther than it."""
    from grammar import shapes

    rng = np.random.default_rng(0)
    t = np.linspace(0, 1, 60)
    named = {}
    for k, (name, f) in enumerate({"arc": lambda t: np.column_stack([np.sin(np.pi * t), 1 - np.cos(np.pi * t), 0 * t]),
                                   "zig": lambda t: np.column_stack([t, np.abs(((4 * t) % 2) - 1), 0 * t])}.items()):
        takes = []
        for _ in range(3):
            p = f(t) + rng.normal(0, 0.005, (len(t), 3))
            takes.append(shapes.sample([(p, np.tile([0.0, 0.0, 0.0, 1.0], (len(t), 1)))]))
        named[name] = (np.array([a for a, _ in takes]), np.array([b for _, b in takes]))
    ss = shapes.shape_set(named, {"arc": "T_X", "zig": "T_Y"})
    assert (ss.reject > 0).all()
    for k, name in enumerate(ss.names):
        paths, quats = named[name]
        group = ss.groups[0]  # the features as the library reads them (its chosen weight of the turn)
        own = np.array([shapes.features(paths[j], quats[j] if group.oriented else None, group.turn) for j in range(3)])
        assert ss.distances(own)[:, k].max() <= ss.reject[k] + 1e-9


def test_shape_distances_kept_only_once_every_track_read_has_reached_them(library):
    """The Refiner keeps a window's shape distances by the samples it spans (they never
    change once recorded) — but not while a track a two-handed action reads has not
    reached the window's end: live, the other hand's samples come a frame apart. Its
    distances are then worked out again once they have, and equal a fresh Refiner's."""
    from doodle.input.loader import load
    from doodle.input.segmenter import tokenize_doodle
    from grammar.recognizer import load_actions
    from grammar.refiner import Refiner

    lib, held = library
    shapes = load_actions(lib, False).shapes
    doodle = load(held["Clap"])
    tokens = tokenize_doodle(doodle)["c0"]
    c0, c1 = doodle.track("c0"), doodle.track("c1")
    moving = [i for i, k in enumerate(tokens) if k.name != "T_STILL"]
    window = (moving[0], moving[-1] + 1)
    end = tokens[window[1] - 1].end

    def refiner(c1_samples):
        r = Refiner(shapes, c0.p, c0.valid, "c0", c0.q, {"c1": (c1.p[:c1_samples], c1.q[:c1_samples],
                                                                  c1.valid[:c1_samples])}, c0.t)
        r.tokens.extend(tokens)
        return r

    live = refiner(end - 1)  # the other hand one sample short of the window's end
    early = live.distances([window])
    assert not np.isfinite(early).any()  # the two-handed actions cannot be read yet
    live.others["c1"] = (c1.p, c1.q, c1.valid)
    fresh = refiner(len(c1.t)).distances([window])
    assert np.isfinite(fresh).any()
    assert np.array_equal(live.distances([window]), fresh)
    assert np.array_equal(live.distances([window]), fresh)  # and now kept


def test_shape_distances_forgotten_beyond_the_limit_are_worked_out_again(library, monkeypatch):
    """The Refiner keeps at most SEEN windows' distances: forgetting the oldest, even one
    the same call read as kept, changes no answer."""
    from doodle.input.loader import load
    from doodle.input.segmenter import tokenize_doodle
    from grammar import refiner as refiner_module
    from grammar.recognizer import load_actions
    from grammar.refiner import Refiner

    lib, held = library
    shapes = load_actions(lib, False).shapes
    doodle = load(held["Lift"])
    tokens = tokenize_doodle(doodle)["c0"]
    c0, c1 = doodle.track("c0"), doodle.track("c1")

    def refiner():
        r = Refiner(shapes, c0.p, c0.valid, "c0", c0.q, {"c1": (c1.p, c1.q, c1.valid)}, c0.t)
        r.tokens.extend(tokens)
        return r

    windows = [(f, e) for f in range(len(tokens)) for e in range(f + 1, len(tokens) + 1)]
    assert len(windows) >= 4
    monkeypatch.setattr(refiner_module, "SEEN", 2)
    small = refiner()
    small.distances(windows[:2])
    for chosen in (windows[:1] + windows[2:4], windows[1:4], windows):
        assert np.array_equal(small.distances(chosen), refiner().distances(chosen), equal_nan=True)
        assert len(small._seen) <= 2 * len(chosen)
