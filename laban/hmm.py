"""HMM effort classifiers (thesis §4.4.2): one left-to-right Gaussian HMM with 6 states per
class — per Drive (8) or per Element (6) — on feature sequences resampled to 512 points
(:func:`laban.features.sequence`, the sets of Table 4.3); a curve goes to the class whose
model gives it the highest likelihood (the forward algorithm, Fig. 4.21).

Training (hmmlearn ``GaussianHMM``, diagonal covariances): the start is state 1, the
transition matrix banded (stay or move one state right) and kept banded by EM; state means
and variances start from a uniform split of each sequence in time (k-means would ignore time
order). Features are standardised by the training frames' mean and deviation.

Scoring is a scaled forward pass written with numpy over many sequences and all models at
once (the same results as hmmlearn's compiled passes, which the tests compare with), so a
model is plain arrays (persisted by :mod:`laban.models`) and scoring needs no hmmlearn.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

STATES = 6
MIN_VARIANCE = 1e-3  # of standardised features: keeps a state that saw a constant from a zero variance


@dataclass(frozen=True, eq=False)
class HMMSet:
    """Left-to-right Gaussian HMMs, one per label, sharing a feature standardisation."""

    labels: tuple[str, ...]
    start: np.ndarray  # (m, S)
    transitions: np.ndarray  # (m, S, S)
    means: np.ndarray  # (m, S, d)
    variances: np.ndarray  # (m, S, d) diagonal
    centre: np.ndarray  # (d,)
    scale: np.ndarray  # (d,)

    def log_likelihoods(self, seq: np.ndarray) -> np.ndarray:
        """(m,) log P(sequence | model) for a (T, d) feature sequence, all models at once."""
        return self.log_likelihoods_many(np.asarray(seq, dtype=float)[None])[0]

    def log_likelihoods_many(self, seqs: np.ndarray, chunk: int = 64) -> np.ndarray:
        """(n, m) log P(sequence | model) for equal-length sequences ``seqs`` (n, T, d), every
        sequence and model at once (in chunks of ``chunk`` sequences, to bound the memory)."""
        seqs = np.asarray(seqs, dtype=float)
        out = np.empty((len(seqs), len(self.labels)))
        for k in range(0, len(seqs), chunk):
            out[k:k + chunk] = self._scores(seqs[k:k + chunk])
        return out

    def _scores(self, seqs: np.ndarray) -> np.ndarray:
        n, T, d = seqs.shape
        z = ((seqs - self.centre) / self.scale).transpose(1, 0, 2)  # time-major
        density = _Densities(self.means, self.variances)
        scale = np.zeros((n, len(self.labels)))  # the emissions' scales: their logs summed over frames

        def scaled():  # emissions BLOCK frames at a time (cache-sized), scaled per frame and model
            for t in range(0, T, BLOCK):
                log_b = density(z[t:t + BLOCK])
                top = _last_max(log_b)
                scale[...] += top.sum(axis=0)
                log_b -= top[..., None]
                yield np.exp(log_b, out=log_b)

        ll, under = _forward(self.start, self.transitions, scaled())
        ll += scale
        if under.any():  # a frame's scaled probabilities underflowed: those pairs again in log space
            i, k = np.nonzero(under)
            log_b = density(z[:, i])[:, np.arange(len(i)), k]
            ll[i, k] = _forward_log(self.start[k], self.transitions[k], log_b)
        return ll


BLOCK = 32  # frames of emissions made at once
MIN_SUM = 1e-300  # a forward step whose probabilities sum below this has underflowed (as hmmlearn's)


class _Densities:
    """Log densities (T, n, m, S) of diagonal Gaussian states ``means``, ``variances`` (m, S, d)
    for standardised frames (T, n, d): ``Σ (x − μ)²/σ²`` expanded, so one matrix product of
    ``(x², x)`` does every state."""

    def __init__(self, means: np.ndarray, variances: np.ndarray):
        m, S, d = means.shape
        inv = (1.0 / variances).reshape(m * S, d)
        mu = means.reshape(m * S, d)
        self.shape = (m, S)
        self.weights = np.vstack([-0.5 * inv.T, (mu * inv).T])  # (2d, m S)
        self.offset = 0.5 * (np.sum(np.log(2 * np.pi * variances), axis=2).ravel() + np.sum(mu * mu * inv, axis=1))

    def __call__(self, z: np.ndarray) -> np.ndarray:
        T, n, d = z.shape
        x = np.concatenate([z * z, z], axis=2).reshape(T * n, 2 * d)
        log_b = x @ self.weights
        log_b -= self.offset
        return log_b.reshape(T, n, *self.shape)


def _last_max(x: np.ndarray) -> np.ndarray:
    """``x.max(axis=-1)`` for a short last axis (numpy's reduction is several times slower there)."""
    top = x[..., 0].copy()
    for s in range(1, x.shape[-1]):
        np.maximum(top, x[..., s], out=top)
    return top


def _forward(start: np.ndarray, A: np.ndarray, blocks) -> tuple[np.ndarray, np.ndarray]:
    """The scaled forward algorithm of models ``start`` (m, S), ``A`` (m, S, S) on the emission
    probabilities of n sequences, given in ``blocks`` of frames (each (k, n, m, S)):
    ``(log P, underflowed)``, both (n, m), without the emissions' scale. A step is two matrix
    products for every sequence and model (the transitions as one block-diagonal matrix, then
    a block of ones giving every state its model's total); ``underflowed`` marks the pairs
    where a step's probabilities summed below :data:`MIN_SUM` (their ``log P`` is then
    meaningless). Equals hmmlearn's ``forward_scaling`` (up to rounding), which raises there
    instead."""
    m, S = start.shape
    block = np.zeros((m * S, m * S))
    for k in range(m):
        block[k * S:(k + 1) * S, k * S:(k + 1) * S] = A[k]
    ones = np.kron(np.eye(m), np.ones((S, S)))
    a, log_p, under = None, 0.0, np.False_
    for b in blocks:
        k, n = b.shape[:2]
        b = b.reshape(k, n, m * S)
        sums = np.empty((k, n, m))
        for t in range(k):
            if a is None:
                a = start.ravel() * b[t]
            else:
                a = a @ block
                a *= b[t]
            total = a @ ones
            sums[t] = total[:, ::S]
            a /= np.maximum(total, MIN_SUM, out=total)  # 0, never NaN, once underflowed
        under = under | (sums < MIN_SUM).any(axis=0)
        with np.errstate(divide="ignore"):
            log_p = log_p + np.log(sums).sum(axis=0)
    return log_p, under


def _forward_log(start: np.ndarray, A: np.ndarray, log_b: np.ndarray) -> np.ndarray:
    """The forward algorithm in log space for p pairs: models ``start`` (p, S), ``A`` (p, S, S)
    on log emission densities ``log_b`` (T, p, S); (p,) log P. Equals hmmlearn's ``forward_log``
    (up to rounding). Left-to-right banded models (all of them, once trained) take the two
    terms of each state at once (``logaddexp``)."""
    with np.errstate(divide="ignore"):
        log_start, log_A = np.log(start), np.log(A)
        a = log_start + log_b[0]
        if np.tril(A, -1).any() or np.triu(A, 2).any():
            for t in range(1, len(log_b)):
                a = _logsumexp(a[:, :, None] + log_A, axis=1) + log_b[t]
        else:
            stay, move = np.diagonal(log_A, axis1=1, axis2=2), np.diagonal(log_A, 1, axis1=1, axis2=2)
            for t in range(1, len(log_b)):
                to = a + stay
                np.logaddexp(to[:, 1:], a[:, :-1] + move, out=to[:, 1:])
                a = to + log_b[t]
    return _logsumexp(a, axis=1)


def _logsumexp(x: np.ndarray, axis: int) -> np.ndarray:
    """log Σ exp along ``axis``; −inf where every term is −inf."""
    top = np.maximum(x.max(axis=axis, keepdims=True), -np.finfo(float).max)  # finite: −inf − top is −inf
    with np.errstate(divide="ignore"):
        return np.log(np.sum(np.exp(x - top), axis=axis)) + np.squeeze(top, axis)


def left_to_right(points: int, states: int = STATES) -> tuple[np.ndarray, np.ndarray]:
    """Start distribution and banded transitions whose expected stay fills ``points`` evenly."""
    stay = 1.0 - states / max(points, states + 1)
    A = np.zeros((states, states))
    for s in range(states - 1):
        A[s, s], A[s, s + 1] = stay, 1.0 - stay
    A[-1, -1] = 1.0
    start = np.zeros(states)
    start[0] = 1.0
    return start, A


def fit(sequences: list[np.ndarray], states: int = STATES, iterations: int = 10):
    """One left-to-right HMM on standardised sequences (each (T, d)); returns
    ``(start, transitions, means, variances)``. Means and variances start from a uniform
    split of every sequence in time; then Baum–Welch (:func:`baum_welch`)."""
    X = np.concatenate(sequences)
    lengths = [len(s) for s in sequences]
    split = np.concatenate([np.minimum((np.arange(n) * states) // n, states - 1) for n in lengths])
    means = np.stack([X[split == s].mean(axis=0) for s in range(states)])
    variances = np.stack([X[split == s].var(axis=0) + MIN_VARIANCE for s in range(states)])
    start, A = left_to_right(int(np.mean(lengths)), states)
    if len(set(lengths)) == 1:
        return baum_welch(np.stack(sequences), start, A, means, variances, iterations)
    return _hmmlearn_fit(X, lengths, start, A, means, variances, iterations)


def _hmmlearn_fit(X, lengths, start, A, means, variances, iterations):
    from hmmlearn.hmm import GaussianHMM

    model = GaussianHMM(n_components=len(start), covariance_type="diag", n_iter=iterations, tol=1e-3,
                        init_params="", params="stmc", min_covar=MIN_VARIANCE, covars_prior=0.0)
    model.startprob_, model.transmat_, model.means_, model.covars_ = start, A, means, variances
    model.fit(X, lengths)
    return model.startprob_.copy(), model.transmat_.copy(), model.means_.copy(), model._covars_.copy()


def baum_welch(X: np.ndarray, start, A, means, variances, iterations: int = 10, tol: float = 1e-3,
               chunk: int = 512):
    """EM for a diagonal Gaussian HMM on equal-length sequences ``X`` (N, T, d), every
    sequence at once (scaled forward–backward, vectorised over sequences): the same
    updates as hmmlearn's ``GaussianHMM.fit`` — which is the reference in the tests and
    trains unequal lengths — without its per-sequence Python loop. Zero transitions stay
    zero, so a left-to-right model stays one. Stops when the log-likelihood gains < tol."""
    start, A, means, variances = (np.array(a, dtype=float) for a in (start, A, means, variances))
    previous = -np.inf
    for _ in range(iterations):
        stats = [_estep(X[k:k + chunk], start, A, means, variances) for k in range(0, len(X), chunk)]
        ll, g0, xi, g, gx, gxx = (sum(s[i] for s in stats) for i in range(6))
        start = g0 / g0.sum()
        A = np.where(A > 0, xi, 0.0)
        A /= np.maximum(A.sum(axis=1, keepdims=True), 1e-300)
        means = gx / np.maximum(g, 1e-300)[:, None]
        variances = np.maximum(gxx / np.maximum(g, 1e-300)[:, None] - means**2, MIN_VARIANCE)
        if ll - previous < tol:
            break
        previous = ll
    return start, A, means, variances


def _estep(X, start, A, means, variances):
    """Sufficient statistics of a batch (n, T, d): total log-likelihood, first-state
    occupancy, expected transitions, and state occupancy with first and second moments.

    Emissions are scaled per frame (their maximum over states is 1, floored at 1e-300),
    alpha is normalised per step (the scale factors give the likelihood), beta is
    normalised by its own maximum per step and every posterior is normalised per step —
    so nothing overflows, whatever the scales."""
    n, T, d = X.shape
    flat = np.ascontiguousarray(X.transpose(1, 0, 2)).reshape(T * n, d)  # time-major: each step contiguous
    log_b = _Densities(means[None], variances[None])(flat.reshape(T, n, d))[:, :, 0]  # (T, n, S)
    top = log_b.max(axis=2, keepdims=True)
    b = np.maximum(np.exp(log_b - top), 1e-300)
    alpha = np.empty_like(b)
    log_c = 0.0
    a = start * b[0]
    for t in range(T):
        if t:
            a = (a @ A) * b[t]
        c = a.sum(axis=1, keepdims=True)
        log_c += float(np.log(c).sum())
        a = a / c
        alpha[t] = a
    beta = np.empty_like(b)
    beta[-1] = 1.0
    xi = np.zeros_like(A)
    for t in range(T - 2, -1, -1):
        nb = b[t + 1] * beta[t + 1]
        back = nb @ A.T
        z = np.maximum(np.sum(alpha[t] * back, axis=1, keepdims=True), 1e-300)  # Σ over the pair posterior
        xi += A * ((alpha[t] / z).T @ nb)
        beta[t] = back / np.maximum(back.max(axis=1, keepdims=True), 1e-300)
    gamma = alpha * beta
    gamma /= np.maximum(gamma.sum(axis=2, keepdims=True), 1e-300)
    g = gamma.sum(axis=(0, 1))
    gf = gamma.reshape(T * n, -1)
    ll = log_c + float(top.sum())
    return ll, gamma[0].sum(axis=0), xi, g, gf.T @ flat, gf.T @ (flat * flat)


def fit_set(labels: tuple[str, ...], sequences: list[np.ndarray], y: list[str], iterations: int = 10,
            progress=None) -> HMMSet:
    """One HMM per label on the sequences labelled with it, a shared standardisation."""
    frames = np.concatenate(sequences)
    centre, scale = frames.mean(axis=0), np.maximum(frames.std(axis=0), 1e-9)
    parts = []
    for k, label in enumerate(labels):
        mine = [(s - centre) / scale for s, lab in zip(sequences, y) if lab == label]
        if not mine:
            raise ValueError(f"no training sequence for {label!r}")
        parts.append(fit(mine, iterations=iterations))
        if progress:
            progress(k + 1, len(labels))
    start, A, means, variances = (np.stack(p) for p in zip(*parts))
    return HMMSet(tuple(labels), start, A, means, variances, centre, scale)
