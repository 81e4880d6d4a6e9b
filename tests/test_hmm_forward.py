"""The numpy forward pass of laban.hmm against hmmlearn's compiled one (forward_scaling, and
forward_log where the scaled pass underflows), on random left-to-right models and sequences."""

import numpy as np
import pytest
from hmmlearn._hmmc import forward_log, forward_scaling

from laban.hmm import STATES, HMMSet, left_to_right
from laban.models import load


def _random_set(rng, m=5, d=4, T=60) -> HMMSet:
    start, A = left_to_right(T)
    starts, As = [], []
    for _ in range(m):
        stay = rng.uniform(0.5, 0.99, STATES)
        B = np.diag(stay) + np.diag(1 - stay[:-1], 1)
        B[-1, -1] = 1.0
        s = start.copy() if rng.random() < 0.7 else rng.dirichlet(np.ones(STATES))  # some start anywhere
        starts.append(s)
        As.append(B if rng.random() < 0.7 else rng.dirichlet(np.ones(STATES), STATES))  # some not banded
    return HMMSet(tuple(f"m{k}" for k in range(m)), np.array(starts), np.array(As),
                  rng.normal(size=(m, STATES, d)), rng.uniform(0.05, 2.0, (m, STATES, d)),
                  rng.normal(size=d), rng.uniform(0.5, 2.0, d))


def _reference(hs: HMMSet, seq: np.ndarray) -> np.ndarray:
    """log P per model by hmmlearn's passes, as laban.hmm scored before it had its own."""
    x = (seq - hs.centre) / hs.scale
    out = []
    for k in range(len(hs.labels)):
        log_b = -0.5 * np.sum(np.log(2 * np.pi * hs.variances[k])[None] + (x[:, None] - hs.means[k][None]) ** 2
                              / hs.variances[k][None], axis=2)
        top = log_b.max(axis=1, keepdims=True)
        try:
            out.append(float(top.sum()) + float(forward_scaling(hs.start[k], hs.transitions[k],
                                                                np.exp(log_b - top))[0]))
        except ValueError:  # underflow (hmmlearn 0.3's forward_log takes probabilities, logs of emissions)
            with np.errstate(divide="ignore"):
                out.append(float(forward_log(hs.start[k], hs.transitions[k], log_b)[0]))
    return np.array(out)


@pytest.mark.parametrize("seed", range(4))
def test_batched_forward_equals_hmmlearn(seed):
    rng = np.random.default_rng(seed)
    hs = _random_set(rng)
    seqs = rng.normal(size=(7, 60, 4)) * rng.uniform(0.5, 3.0, (7, 1, 1))
    many = hs.log_likelihoods_many(seqs, chunk=3)  # chunks of 3, 3, 1
    for i, seq in enumerate(seqs):
        ref = _reference(hs, seq)
        np.testing.assert_allclose(many[i], ref, rtol=1e-9)
        np.testing.assert_allclose(hs.log_likelihoods(seq), ref, rtol=1e-9)


def test_underflow_falls_back_to_log_space():
    rng = np.random.default_rng(7)
    hs = _random_set(rng, m=3)
    starts = hs.start.copy()
    starts[:] = 0.0
    starts[:, 0] = 1.0  # every model starts in state 0 …
    means = hs.means.copy()
    means[:, 0] = 0.0
    means[:, 1:] = 40.0  # … which emits near 0, the other states near 40
    variances = np.full_like(hs.variances, 0.05)
    A = np.array([np.eye(STATES) * 0.9 + np.eye(STATES, k=1) * 0.1 for _ in range(3)])
    A[:, -1, -1] = 1.0
    A[2] = rng.dirichlet(np.ones(STATES), STATES)  # not banded: the general log-space step
    hs = HMMSet(hs.labels, starts, A, means, variances, np.zeros(4), np.ones(4))
    seqs = rng.normal(size=(4, 50, 4)) * 0.1
    seqs[1, 0] = 40.0  # first frame far from state 0: its scaled probability underflows to 0
    seqs[3, 10:] = 40.0  # later frames fit the later states: the scaled pass is fine
    for k in range(3):  # the scaled pass does fail for sequence 1: the case is exercised
        x = seqs[1]
        log_b = -0.5 * np.sum(np.log(2 * np.pi * variances[k]) + (x[:, None] - means[k]) ** 2 / variances[k], axis=2)
        with pytest.raises(ValueError):
            forward_scaling(starts[k], A[k], np.exp(log_b - log_b.max(axis=1, keepdims=True)))
    many = hs.log_likelihoods_many(seqs)
    assert np.isfinite(many).all()
    for i, seq in enumerate(seqs):
        np.testing.assert_allclose(many[i], _reference(hs, seq), rtol=1e-9)


def test_shipped_drive_models_equal_hmmlearn():
    model = load()
    rng = np.random.default_rng(3)
    d = model.drives.means.shape[2]
    seqs = model.drives.centre + model.drives.scale * rng.normal(size=(5, 128, d))
    seqs[4] += 30 * model.drives.scale  # far from every state: underflows
    many = model.drives.log_likelihoods_many(seqs)
    for i, seq in enumerate(seqs):
        np.testing.assert_allclose(many[i], _reference(model.drives, seq), rtol=1e-9)
