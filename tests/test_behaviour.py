"""Behaviour states (§6.3.3): pre- and post-conditions from the manifest applied to
recognised segments — a fallen character cannot jump until it gets up, an interaction whose
role is refused is dropped on both tracks — and the manifest's checks."""

import pytest

from doodle.core.errors import DoodleError
from grammar.recognizer import load_actions, recognize
from doodle.synth.strokes import stroke, synth_doodle
from grammar.constraints import Behaviour
from grammar.contexter import InteractionSegment, Refused
from library.manifest import format_library, load_library

FALL, GET_UP = ["T_X_Y", "T_N_X_N_Y", "T_X_Y"], ["T_N_X_Y", "T_X_N_Y", "T_N_X_Y"]
JUMP = ["T_Y", "T_Z", "T_N_Y"]
MANIFEST = '''[library]
name = "story"
states = ["standing"]

[[actions]]
name = "Fall"
expression = "T_X_Y T_N_X_N_Y T_X_Y"
requires = ["standing"]
sets = ["fallen"]
clears = ["standing"]

[[actions]]
name = "Get Up"
expression = "T_N_X_Y T_X_N_Y T_N_X_Y"
requires = ["fallen"]
sets = ["standing"]
clears = ["fallen"]

[[actions]]
name = "Jump"
jumping = true
requires = ["standing"]

[[actions]]
name = "Slap"
interaction_only = true
forbids = ["fallen"]
'''


def _library(tmp_path, text=MANIFEST):
    (tmp_path / "library.toml").write_text(text)
    return tmp_path


def _track(words):
    out = [stroke("T_STILL", 0.4)]
    for w in words:
        out += [stroke(w, 0.3)] if w != "pause" else [stroke("T_STILL", 0.5)]
    return out + [stroke("T_STILL", 0.5)]


def _named(result, track="c0"):
    return [(s.action, getattr(s, "refused", "")) for s in result[track][1] if s.action not in ("Idle",)
            and (s.action != "unknown" or getattr(s, "refused", ""))]


def test_a_fallen_character_jumps_only_after_getting_up(tmp_path):
    compiled = load_actions(_library(tmp_path), True)
    words = JUMP + ["pause"] + FALL + ["pause"] + JUMP + ["pause"] + GET_UP + ["pause"] + JUMP
    result = recognize(synth_doodle({"c0": _track(words)}, seed=3), compiled)
    assert _named(result) == [("Jump", ""), ("Fall", ""), ("unknown", "Jump"), ("Get Up", ""), ("Jump", "")]
    refused = [s for s in result["c0"][1] if isinstance(s, Refused)][0]
    assert refused.reason == "needs standing"
    # without the behaviour the same doodle jumps three times
    plain = recognize(synth_doodle({"c0": _track(words)}, seed=3), load_actions(None, True))
    assert [s.action for s in plain["c0"][1]].count("Jump") == 3


def test_an_interaction_with_a_refused_role_is_dropped_on_every_track(tmp_path):
    """Colombine falls, then performs the Slap gesture with Pierrot still in front of her: a
    fallen character may not slap, so neither track has the interaction."""
    compiled = load_actions(_library(tmp_path), True)
    a = _track(FALL + ["pause", "T_N_Z", "T_Z"])
    b = [stroke("T_STILL", sum(s.duration for s in a))]
    doodle = synth_doodle({"c0": a, "c1": b}, seed=1, start_p={"c0": (0.0, 1.0, 0.0), "c1": (0.0, 1.0, 0.2)},
                          start_q={"c0": (0.0, 0.0, 0.0, 1.0), "c1": (0.0, 1.0, 0.0, 0.0)})
    result = recognize(doodle, compiled)
    assert not any(isinstance(s, InteractionSegment) for _, segs in result.values() for s in segs)
    assert ("unknown", "Slap") in _named(result)
    standing = recognize(synth_doodle({"c0": _track(["T_N_Z", "T_Z"]), "c1": [stroke("T_STILL", 1.5)]}, seed=1,
                                      start_p={"c0": (0.0, 1.0, 0.0), "c1": (0.0, 1.0, 0.2)},
                                      start_q={"c0": (0.0, 0.0, 0.0, 1.0), "c1": (0.0, 1.0, 0.0, 0.0)}), compiled)
    assert any(isinstance(s, InteractionSegment) for s in standing["c0"][1])  # standing, she may


def test_behaviour_fields_round_trip_and_checks(tmp_path):
    lib = load_library(_library(tmp_path))
    fall = lib.action("Fall")
    assert lib.states == ("standing",) and fall.requires == ("standing",) and fall.sets == ("fallen",)
    assert Behaviour.of(fall) == Behaviour(frozenset({"standing"}), frozenset(), frozenset({"fallen"}),
                                           frozenset({"standing"}))
    assert Behaviour.of(lib.action("Jump")).why(frozenset({"fallen"})) == "needs standing"
    (tmp_path / "again").mkdir()
    (tmp_path / "again" / "library.toml").write_text(format_library(lib, tmp_path))
    again = load_library(tmp_path / "again")
    assert again.states == lib.states and again.action("Get Up").clears == ("fallen",)
    for text, message in (
            (MANIFEST.replace('requires = ["fallen"]', 'requires = ["fallen"]\nforbids = ["fallen"]'),
             "state 'fallen' is in both 'requires' and 'forbids'"),
            (MANIFEST.replace('sets = ["fallen"]', 'sets = "fallen"'), "field 'sets': must be a list of state names"),
            (MANIFEST.replace('states = ["standing"]', 'states = ["a b"]'), "states: must be a list"),
    ):
        with pytest.raises(DoodleError, match=message):
            load_library(_library(tmp_path, text))
    # not invertible: nothing gets a fallen character up
    stuck = MANIFEST.replace('sets = ["standing"]\nclears = ["fallen"]', '')
    with pytest.raises(DoodleError, match="action 'Fall' sets state 'fallen' but no action clears it"):
        load_actions(_library(tmp_path, stuck), True)


def _heard(found):
    return [(r.track, r.action, round(r.start, 4)) for r in found if not r.interaction]


def _batch(doodle, result):
    return [(name, s.action, round(float(doodle.track(name).t[s.start]), 4)) for name, (_, segs) in result.items()
            for s in segs if s.action != "unknown"]


def _recorded(tmp_path, doodle, compiled):
    from doodle.app.recorder import record
    from doodle.input.sources import SyntheticSource

    now = [0.0]

    def sleep(s):
        now[0] += max(s, 0.0)

    events = []
    result = record(SyntheticSource(doodle), tmp_path / "live.doodle", clock=lambda: now[0], sleep=sleep,
                    compiled=compiled, on_event=lambda kind, e: events.append((kind, e)))
    return result, events


def test_replay_and_record_refuse_what_recognize_refuses(tmp_path):
    """The one Recognizer: ``doodle replay`` and ``doodle record`` apply behaviour states as
    ``doodle recognize`` does — the jump of a fallen character is refused on every path."""
    from doodle.app.replay import replay
    from doodle.input.loader import load

    compiled = load_actions(_library(tmp_path), True)
    words = JUMP + ["pause"] + FALL + ["pause"] + JUMP + ["pause"] + GET_UP + ["pause"] + JUMP
    doodle = synth_doodle({"c0": _track(words)}, seed=3)
    batch = recognize(doodle, compiled)
    replayed = replay(doodle, compiled)
    assert sorted(_heard(replayed.found)) == sorted(_batch(doodle, batch))
    assert [r.action for r in replayed.found].count("Jump") == 2
    assert _named(replayed.result) == _named(batch)
    result, events = _recorded(tmp_path, doodle, compiled)
    on_file = recognize(load(result.path), compiled)
    assert [a for a, _, _ in result.actions["c0"]] == [s.action for s in on_file["c0"][1] if s.action != "unknown"]
    assert _named(result.recognised) == _named(on_file) == _named(batch)
    refused = [e for kind, e in events if kind == "refused"]
    assert [(e["action"], e["reason"]) for e in refused] == [("Jump", "needs standing")]


def test_replay_and_record_drop_an_interaction_as_recognize_does(tmp_path):
    """Two tracks: the interaction a standing character may perform is reported live by
    replay and record, and their final reading equals recognize's."""
    from doodle.app.replay import replay

    compiled = load_actions(_library(tmp_path), True)
    doodle = synth_doodle({"c0": _track(["T_N_Z", "T_Z"]), "c1": [stroke("T_STILL", 1.5)]}, seed=1,
                          start_p={"c0": (0.0, 1.0, 0.0), "c1": (0.0, 1.0, 0.2)},
                          start_q={"c0": (0.0, 0.0, 0.0, 1.0), "c1": (0.0, 1.0, 0.0, 0.0)})
    batch = recognize(doodle, compiled)
    want = sorted((name, s.action, s.interaction, s.role) for name, (_, segs) in batch.items() for s in segs
                  if isinstance(s, InteractionSegment))
    assert want
    replayed = replay(doodle, compiled)
    assert sorted((r.track, r.action, r.interaction, r.role) for r in replayed.found if r.interaction) == want
    result, events = _recorded(tmp_path, doodle, compiled)
    live = sorted((e["track"], e["action"], e["interaction"], e["role"]) for kind, e in events
                  if kind == "action" and "interaction" in e)
    assert live == want
    final = sorted((name, s.action, s.interaction, s.role) for name, (_, segs) in result.recognised.items()
                   for s in segs if isinstance(s, InteractionSegment))
    assert final == want
