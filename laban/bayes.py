"""Naive Bayes effort classifiers (thesis §4.4.1): one binary Gaussian classifier per Factor
(Space, Time, Weight) with uniform priors (eq. 4.10–4.12), each on the features that the
relevance factor (eq. 4.13–4.17) ranks highest for it — the number kept chosen by accuracy.

Training uses scikit-learn's ``GaussianNB`` (``priors=[0.5, 0.5]``); the fitted means and
variances are kept as plain arrays so a model persists without pickle, and prediction is
eq. 4.10 written out (the same joint log-likelihood as ``GaussianNB``'s).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from laban.selection import normalise, ranking


@dataclass(frozen=True, eq=False)
class Binary:
    """One Factor's classifier: classes (−1, +1), selected feature columns, their [0, 1]
    normalisation bounds, and per-class means and variances of the normalised features."""

    features: np.ndarray  # (k,) column indices into the summary vector
    lo: np.ndarray  # (k,)
    hi: np.ndarray  # (k,)
    means: np.ndarray  # (2, k): class −1, class +1
    variances: np.ndarray  # (2, k)

    def log_likelihoods(self, X: np.ndarray) -> np.ndarray:
        """(n, 2) log P(f | class) of summary rows ``X`` (n, d), eq. 4.9 and 4.12."""
        Z, _, _ = normalise(np.atleast_2d(X)[:, self.features], self.lo, self.hi)
        diff = Z[:, None, :] - self.means[None]
        return -0.5 * np.sum(np.log(2 * np.pi * self.variances)[None] + diff**2 / self.variances[None], axis=2)

    def probability(self, X: np.ndarray) -> np.ndarray:
        """(n,) posterior of class +1 under uniform priors (eq. 4.10, 4.11)."""
        ll = self.log_likelihoods(X)
        return 1.0 / (1.0 + np.exp(np.clip(ll[:, 0] - ll[:, 1], -700, 700)))

    def predict(self, X: np.ndarray) -> np.ndarray:
        return np.where(self.probability(X) >= 0.5, 1, -1)


def fit_binary(X: np.ndarray, y: np.ndarray, features: np.ndarray) -> Binary:
    """Eq. 4.12's means and variances on the chosen columns, normalised to [0, 1]."""
    from sklearn.naive_bayes import GaussianNB  # training only: scoring needs no scikit-learn

    features = np.asarray(features, dtype=int)
    Z, lo, hi = normalise(X[:, features])
    nb = GaussianNB(priors=[0.5, 0.5]).fit(Z, y)
    order = np.argsort(nb.classes_)  # −1 first
    return Binary(features, lo, hi, nb.theta_[order].copy(), nb.var_[order].copy())


def select(X: np.ndarray, y: np.ndarray, groups: np.ndarray, most: int | None = None) -> tuple[np.ndarray, list[float]]:
    """Features for one Factor (§4.4.1): rank by relevance, then keep the M best for the M
    (1…``most``) with the highest accuracy, measured leave-one-group-out (one performer held
    out at a time) so M is not chosen on the data it is scored on. Returns the columns and
    the accuracy for every M."""
    most = min(most or X.shape[1], X.shape[1])
    folds = [(groups != g, groups == g) for g in np.unique(groups)]
    folds = [(tr, te) for tr, te in folds if len(np.unique(y[tr])) == 2]
    orders = [ranking(normalise(X[tr])[0], y[tr]) for tr, _ in folds]
    scores = []
    for m in range(1, most + 1):
        right = sum(int(np.sum(fit_binary(X[tr], y[tr], order[:m]).predict(X[te]) == y[te]))
                    for (tr, te), order in zip(folds, orders))
        scores.append(right / max(sum(int(te.sum()) for _, te in folds), 1))
    best = int(np.argmax(scores)) + 1
    return ranking(normalise(X)[0], y)[:best], scores
