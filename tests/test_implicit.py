"""Implicit actions (§6.4): generated minimal doodles are recognised as the action asked
for — every action of the built-in library, from any start pose, aimed at any target."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from doodle.errors import DoodleError
from doodle.model import Doodle
from doodle.pipeline import load_actions, recognize
from grammar.implicit import implicit_action, intended_tokens, reach

COMPILED = load_actions()
ACTIONS = COMPILED.library.names


def recognised(track):
    _, segs = recognize(Doodle((track,), 90.0), COMPILED)["c0"]
    return [s.action for s in segs if s.action != "Idle"] or [s.action for s in segs]


@settings(max_examples=40, deadline=None)
@given(st.sampled_from(ACTIONS), st.floats(-np.pi, np.pi), st.floats(-3, 3), st.floats(-3, 3),
       st.floats(0.7, 3.0), st.floats(-np.pi, np.pi))
def test_generated_doodles_are_recognised_as_intended(action, yaw, x, z, reach_scale, reach_turn):
    q = (0.0, np.sin(yaw / 2), 0.0, np.cos(yaw / 2))
    track = implicit_action(COMPILED, action, start_p=(x, 1.0, z), start_q=q)
    chord = track.p[-1] - track.p[0]
    if np.linalg.norm(chord) > 0.05:  # travelling actions: aim them elsewhere
        c, s = np.cos(reach_turn), np.sin(reach_turn)
        goal = track.p[0] + reach_scale * np.array([c * chord[0] + s * chord[2], chord[1], -s * chord[0] + c * chord[2]])
        track = reach(track, goal)
        assert np.allclose(track.p[-1], goal, atol=1e-9)
    assert recognised(track) == [action]


def test_every_action_has_an_intended_string():
    for action in ACTIONS:
        assert intended_tokens(COMPILED, action), action


def test_reach_rotates_and_scales_about_the_start():
    track = implicit_action(COMPILED, "Walk")
    goal = track.p[0] + np.array([1.0, 0.0, -0.5])
    moved = reach(track, goal)
    assert np.allclose(moved.p[0], track.p[0]) and np.allclose(moved.p[-1], goal)
    assert np.allclose(np.linalg.norm(moved.q, axis=1), 1.0)
    with pytest.raises(DoodleError, match="no action 'Fly'"):
        intended_tokens(COMPILED, "Fly")
