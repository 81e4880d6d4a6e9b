"""Implicit actions (§6.4): generated minimal doodles are recognised as the action asked
for — every action of the built-in library, from any start pose, aimed at any target."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from doodle.core.errors import DoodleError
from doodle.core.model import Doodle
from grammar.recognizer import load_actions, recognize
from doodle.synth.implicit import implicit_action, intended_tokens, reach

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


@pytest.mark.parametrize("action, turn", [("Walk", 60.0), ("Walk", -90.0), ("Jump", 45.0), ("Side Walk Left", 30.0)])
def test_end_orientation_is_met_without_a_jump(action, turn):
    """§6.4, eq. 6.9: the generated doodle ends in the orientation asked for, turning there
    gradually (no step between samples larger than the curve's own), and is still read as
    the action."""
    from scipy.spatial.transform import Rotation

    from doodle.core.model import Doodle
    from grammar.recognizer import recognize
    from doodle.synth.implicit import end_orientation

    track = implicit_action(COMPILED, action)
    goal_q = (Rotation.from_euler("y", turn, degrees=True) * Rotation.from_quat(track.q[-1])).as_quat()
    turned = end_orientation(track, goal_q)
    assert abs(abs(turned.q[-1] @ goal_q) - 1.0) < 1e-6 and np.allclose(turned.q[0], track.q[0])
    assert np.allclose(turned.p, track.p)
    step = lambda q: np.max(np.arccos(np.clip(np.abs(np.sum(q[1:] * q[:-1], axis=1)), -1, 1)) * 2)
    jumped = track.q.copy()
    jumped[-1] = goal_q
    assert step(turned.q) < step(track.q) + np.radians(abs(turn)) / 10 < step(jumped)
    segs = recognize(Doodle((turned,), 90.0), COMPILED)["c0"][1]
    assert [s.action for s in segs if s.action not in ("Idle", "unknown")] == [action]
