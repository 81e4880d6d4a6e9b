"""The Spotter (grammar.spotter): its windows start anywhere from the anchor; a spot goes on
while a longer window from its start scores better; a window held back is spotted at a pause."""

from types import SimpleNamespace

import numpy as np

from doodle.core.tokens import Token
from grammar.spotter import HELD, Spotter


def _refiner(longest, seconds=10.0, tokens=20, rate=90.0):
    t = np.arange(int(seconds * rate)) / rate
    step = len(t) // tokens
    toks = [Token("T_X", k * step, (k + 1) * step) for k in range(tokens)]
    return SimpleNamespace(shapes=SimpleNamespace(longest=None if longest is None else np.array(longest)),
                           t=t, tokens=toks)


def test_a_spot_goes_on_while_a_longer_window_from_its_start_scores_better():
    """Spotted at boundary 5 (score 10), the window from its start scores 12 to boundary 6,
    8 to 7, 9 to 8: the gesture was going on to 7 — the spot and the anchor reach there, and
    no further; past SPOT_MAX tokens it no longer goes on."""
    from grammar.refiner import SPOT_MAX

    refiner = _refiner(None, tokens=SPOT_MAX + 10)
    refiner.t, refiner.shapes.names = None, ("a", "b")
    table = {6: 12.0, 7: 8.0, 8: 9.0}
    refiner.shapes.automaton = SimpleNamespace(step=lambda state, code: state + 1,
                                               accept_costs=lambda state: np.array([1.0, 2.0]))
    refiner.readable = lambda f, e: True
    refiner.nearest = lambda windows, edits, strict: (None, np.array([[table.get(windows[0][1], 20.0), np.inf]]))
    spotter = Spotter()
    spotter.spotted, spotter.anchor = [(0, 5, 0, 1.0)], 5
    spotter._going = [10.0, 0]
    for k in range(5, 9):
        spotter._go_on(refiner, k, 0)
    assert spotter.spotted == [(0, 7, 0, 1.0)] and spotter.anchor == 7 and spotter._going[0] == 8.0
    table[SPOT_MAX + 2] = 1.0
    for k in range(9, SPOT_MAX + 2):
        spotter._go_on(refiner, k, 0)
    assert spotter._going is None and spotter.spotted == [(0, 7, 0, 1.0)]


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
