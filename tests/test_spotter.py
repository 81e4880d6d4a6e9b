"""The Spotter's anchor (grammar.spotter): windows start where the next gesture begins —
at the anchor or a few tokens after it — until no gesture can start there any more."""

from types import SimpleNamespace

import numpy as np

from doodle.core.tokens import Token
from grammar.refiner import TEMPO, TRIM
from grammar.spotter import HELD, Spotter


def _refiner(longest, seconds=10.0, tokens=20, rate=90.0):
    t = np.arange(int(seconds * rate)) / rate
    step = len(t) // tokens
    toks = [Token("T_X", k * step, (k + 1) * step) for k in range(tokens)]
    return SimpleNamespace(shapes=SimpleNamespace(longest=None if longest is None else np.array(longest)),
                           t=t, tokens=toks)


def test_the_anchor_is_lost_once_every_window_from_it_lasts_longer_than_any_action_may():
    refiner = _refiner([1.0, 2.0])  # tokens of 0.5 s each
    limit = TEMPO * 2.0
    for e in range(TRIM + 2, 21):
        span = refiner.t[refiner.tokens[e - 1].end - 1] - refiner.t[refiner.tokens[TRIM].start]
        assert Spotter._lost(refiner, 0, e) == (span > limit)
    assert not Spotter._lost(refiner, 0, TRIM + 2) and Spotter._lost(refiner, 0, 20)


def test_without_the_examples_durations_windows_start_anywhere():
    assert Spotter._lost(_refiner(None), 0, 6)
    assert Spotter._lost(_refiner([np.inf, 2.0]), 0, 6)


def test_a_window_held_back_is_spotted_at_the_pause_that_ends_its_motion():
    """A window held back as a longer action's possible beginning is the gesture once the hand
    pauses: spotted there (kept), and the anchor moves past the pause."""
    refiner = _refiner([2.0, 4.0])
    refiner.shapes.automaton = None  # (a pause steps no automaton)
    refiner.tokens[6] = Token("T_STILL", refiner.tokens[6].start, refiner.tokens[6].end)
    spotter = Spotter()
    spotter._n, spotter.anchor = 6, 1
    held = (1, 6, 0, 0.0)
    spotter._scores[HELD] = (6, held, 1)
    assert spotter._read(refiner, 6, spotter._states, spotter._scores, keep=True) == held
    assert spotter.spotted == [held] and spotter.anchor == 7 and HELD not in spotter._scores
    spotter._scores[HELD] = (6, (0, 6, 0, 0.0), 1)  # (one that starts before the anchor is dropped)
    refiner.tokens[7] = Token("T_STILL", refiner.tokens[7].start, refiner.tokens[7].end)
    assert spotter._read(refiner, 7, spotter._states, spotter._scores, keep=True) is None
