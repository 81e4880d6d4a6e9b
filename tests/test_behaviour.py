"""Behaviour states (§6.3.3): pre- and post-conditions from the manifest applied to
recognised segments — a fallen character cannot jump until it gets up, an interaction whose
role is refused is dropped on both tracks — and the manifest's checks."""

import pytest

from doodle.core.errors import DoodleError
from doodle.app.pipeline import load_actions, recognize
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
