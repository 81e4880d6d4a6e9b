"""Time and Weight decisions: one calibrated logistic classifier per Factor on the Effort
features (:func:`laban.features.effort_features` — size and rate free).

Each classifier is ``P(+1 | x) = σ((w · z + b) / T)`` with ``z`` the features standardised
by the training set's mean and deviation, ``w, b`` fitted by L2-regularised logistic
regression (scikit-learn ``LogisticRegression``, balanced classes), and the temperature
``T`` fitted afterwards on out-of-fold decisions — each training group (performer or
neutral clip) scored by a classifier that did not see it — by minimising their negative
log-likelihood (temperature scaling, Guo, Pleiss, Sun & Weinberger 2017, "On calibration
of modern neural networks", ICML). So a confidence of 0.8 is right about 80 % of the time
on movements like the training ones, and a quality whose confidence is under the model's
threshold is left neutral (abstention) rather than guessed.

Each Factor reads only the features that mean it (their sources are in
:data:`laban.features.EFFORT_SOURCES`), with strong regularisation: on effort applied by one
procedure and tested on another, every extra feature let the classifier learn the training
procedure's habits instead of the quality (measured: Time 0.65/0.81 with all features,
0.81/0.85 with these four; Weight 0.70/0.69 against 0.71/0.85), and each source of training
data (generator, each real-motion procedure) weighs the same in the fit.

Training presents every path at several sizes (×0.1–×10 of the recorded one, log-uniform)
and tracking rates (30–144 Hz, jittered clock, absolute tracking noise): the features are
invariant by construction, and this keeps the classifier from leaning on what residue of
size or sampling survives (noise does not scale with the figurine).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from laban.features import EFFORT_NAMES, effort_features
from laban.procedures import Effortful, presented

C = 0.05  # inverse L2 strength: strong, so no feature is leaned on beyond what all sources agree on
FEATURES = {
    # Time: how brief and how quick the movement's main stroke is, for its size
    "time": ("Relative Peak Speed", "Peak Stroke Width", "Peak Rise Time", "Peak Fall Time"),
    # Weight: energy concentrated in peaks (Strong) or spread evenly (Light), and a short, fast main stroke
    "weight": ("Speed Variation", "Peak Energy Ratio", "Energy Spread", "Peak Stroke Width", "Relative Peak Speed"),
}
SCALES = (0.1, 10.0)  # training sizes, × the recorded path (log-uniform)
RATE_RANGE = (30.0, 144.0)  # Hz, training tracking rates (uniform)


@dataclass(frozen=True, eq=False)
class Logistic:
    """One Factor's calibrated classifier; +1 is Sudden (Time) or Strong (Weight)."""

    centre: np.ndarray  # (d,)
    scale: np.ndarray  # (d,)
    coef: np.ndarray  # (d,)
    bias: float
    temperature: float = 1.0

    def logit(self, X: np.ndarray) -> np.ndarray:
        """(n,) uncalibrated log-odds of +1 for feature rows ``X`` (n, d)."""
        return ((np.atleast_2d(X) - self.centre) / self.scale) @ self.coef + self.bias

    def probability(self, X: np.ndarray) -> np.ndarray:
        """(n,) calibrated P(+1)."""
        return 1.0 / (1.0 + np.exp(-np.clip(self.logit(X) / self.temperature, -700, 700)))


def fit_logistic(X: np.ndarray, y: np.ndarray, factor: str, weights: np.ndarray | None = None) -> Logistic:
    """The classifier of labels ``y`` ∈ {−1, +1} from rows ``X`` (all Effort features; only
    ``FEATURES[factor]`` get a weight), temperature 1."""
    from sklearn.linear_model import LogisticRegression

    cols = [EFFORT_NAMES.index(n) for n in FEATURES[factor]]
    centre, scale = X.mean(axis=0), np.maximum(X.std(axis=0), 1e-9)
    w = np.ones(len(y)) if weights is None else np.asarray(weights, float)
    for label in (-1, 1):  # balanced classes, on top of the sample weights
        w = np.where(y == label, w / max(w[y == label].sum(), 1e-12), w)
    lr = LogisticRegression(C=C, max_iter=2000).fit(((X - centre) / scale)[:, cols], y, sample_weight=w * len(y) / 2)
    sign = 1.0 if lr.classes_[-1] > 0 else -1.0
    coef = np.zeros(X.shape[1])
    coef[cols] = sign * lr.coef_[0]
    return Logistic(centre, scale, coef, float(sign * lr.intercept_[0]))


def temperature(logits: np.ndarray, y: np.ndarray) -> float:
    """The T minimising the negative log-likelihood of labels ``y`` (±1) under σ(logit / T)."""
    from scipy.optimize import minimize_scalar  # calibration only

    z = np.asarray(logits, float) * np.where(np.asarray(y) > 0, 1.0, -1.0)

    def nll(log_t):
        return float(np.mean(np.logaddexp(0.0, -z / np.exp(log_t))))

    return float(np.exp(minimize_scalar(nll, bounds=(-4.0, 4.0), method="bounded").x))


def features(items: list[Effortful], rng: np.random.Generator, copies: int = 2,
             scales=SCALES, rates=RATE_RANGE) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Effort feature rows of every item presented ``copies`` times at a random size and
    rate; returns ``(X, time labels, weight labels, groups)``."""
    rows, yt, yw, groups = [], [], [], []
    lo, hi = np.log(scales[0]), np.log(scales[1])
    for it in items:
        for _ in range(copies):
            t, p, _ = presented(it.t, it.p, it.q, float(np.exp(rng.uniform(lo, hi))), float(rng.uniform(*rates)), rng)
            rows.append(effort_features(t, p))
            yt.append(it.time)
            yw.append(it.weight)
            groups.append(f"{it.source}/{it.group}")
    return np.array(rows), np.array(yt), np.array(yw), np.array(groups)


def fit_factors(X: np.ndarray, yt: np.ndarray, yw: np.ndarray, groups: np.ndarray, folds: int = 5,
                seed: int = 0) -> dict[str, Logistic]:
    """Time and Weight classifiers on feature rows, each calibrated on out-of-fold logits
    (folds of whole groups); every source (the part of a group before ``/``) weighs the same."""
    sources = np.array([g.split("/", 1)[0] for g in groups])
    kinds, counts = np.unique(sources, return_counts=True)
    weights = 1.0 / counts[np.searchsorted(kinds, sources)]
    names = np.unique(groups)
    order = np.random.default_rng(seed).permutation(len(names))
    fold_of = dict(zip(names[order], np.arange(len(names)) % folds))
    fold = np.array([fold_of[g] for g in groups])
    out = {}
    for factor, y in (("time", yt), ("weight", yw)):
        logits = np.empty(len(y))
        for k in range(folds):
            test = fold == k
            if test.any() and len(np.unique(y[~test])) == 2:
                logits[test] = fit_logistic(X[~test], y[~test], factor, weights[~test]).logit(X[test])
            else:
                logits[test] = 0.0
        full = fit_logistic(X, y, factor, weights)
        out[factor] = Logistic(full.centre, full.scale, full.coef, full.bias, temperature(logits, y))
    return out


def check_names(names) -> bool:
    return list(names) == list(EFFORT_NAMES)
