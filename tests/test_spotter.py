"""The Spotter's anchor (grammar.spotter): windows start where the next gesture begins —
at the anchor or a few tokens after it — until no gesture can start there any more."""

from types import SimpleNamespace

import numpy as np

from doodle.core.tokens import Token
from grammar.refiner import TEMPO, TRIM
from grammar.spotter import Spotter


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
