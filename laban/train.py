"""Training and evaluating the effort models (§4.4), on labelled trajectories — generated
(:mod:`laban.synth`) or a person's own (``doodle laban train``).

* Naive Bayes: per Factor, features chosen by relevance and accuracy (:func:`laban.bayes.select`).
* HMMs: per Drive (8) and per Element (6); each training curve is augmented by
  **sub-sampling ×16** (§4.4.2): 16 random subsets of its samples (50–90 % kept, in order,
  the ends always kept), each becoming one 512-point feature sequence — the features see
  other sampling instants and other noise, the movement stays the same.
* Time and Weight (the qualities applied): calibrated logistic classifiers on the size- and
  rate-free Effort features (:mod:`laban.factors`), trained on the labelled curves and on any
  further effort-labelled paths given (``extra``: effort applied to real motion capture by
  other procedures, :mod:`laban.procedures`), each presented at several sizes and rates.
* Temperature: the Drive posterior's temperature is fitted on held-out curves by
  minimising their negative log-likelihood (temperature scaling: Guo, Pleiss, Sun &
  Weinberger 2017, "On calibration of modern neural networks", ICML), so confidences mean
  what they say.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import minimize_scalar

from laban import factors as factor_models
from laban.bayes import fit_binary, select
from laban.classify import bayes_drive, element_drives, qualities
from laban.efforts import DRIVES, ELEMENTS, FACTORS, STATES, element, state_of
from laban.features import sequence, summary
from laban.hmm import HMMSet, fit_set
from laban.models import EffortModel
from laban.procedures import Effortful

SETS = ("euclidean", "affine", "moving")
POINTS = 512
AUGMENT = 16
THRESHOLD = 0.6  # a Time or Weight under this confidence is left neutral


@dataclass(frozen=True, eq=False)
class Labelled:
    """One labelled curve: samples, its Drive, and a group (the performer) for held-out splits."""

    t: np.ndarray
    p: np.ndarray
    q: np.ndarray
    drive: str
    group: str = ""


def subsample(t, p, q, rng: np.random.Generator, times: int = AUGMENT) -> list[tuple]:
    """``times`` random in-order subsets of the samples (50–90 % kept, ends kept)."""
    n = len(t)
    out = []
    for _ in range(times):
        keep = max(int(round(n * rng.uniform(0.5, 0.9))), min(n, 4))
        idx = np.sort(rng.choice(np.arange(1, n - 1), size=max(keep - 2, 0), replace=False)) if n > 2 else np.arange(0)
        idx = np.concatenate([[0], idx, [n - 1]]) if n > 1 else np.arange(n)
        out.append((t[idx], p[idx], q[idx]))
    return out


def _sequences(curves, sets, points, augment: int, seed: int, progress=None) -> tuple[list, list]:
    rng = np.random.default_rng(seed)
    seqs, labels = [], []
    for k, c in enumerate(curves):
        variants = subsample(c.t, c.p, c.q, rng, augment) if augment > 1 else [(c.t, c.p, c.q)]
        for t, p, q in variants:
            seqs.append(sequence(t, p, q, sets, points))
            labels.append(c.drive)
        if progress:
            progress(k + 1, len(curves))
    return seqs, labels


def effortful(curves: list[Labelled], source: str = "generator") -> list[Effortful]:
    """Labelled curves as Time / Weight labelled paths."""
    return [Effortful(c.t, c.p, c.q, DRIVES[c.drive][1], DRIVES[c.drive][2], source, c.group) for c in curves]


def train_factors(items: list[Effortful], copies: int = 2, seed: int = 0, report: dict | None = None) -> dict:
    """The calibrated Time and Weight classifiers (:mod:`laban.factors`) of effort-labelled
    paths, each presented ``copies`` times at a random size and rate; ``report`` receives
    the feature sets and regularisation chosen (:func:`laban.factors.fit_factors`)."""
    X, yt, yw, groups = factor_models.features(items, np.random.default_rng([seed, 21]), copies)
    return factor_models.fit_factors(X, yt, yw, groups, seed=seed, report=report)


def train(curves: list[Labelled], held_out: list[Labelled] | None = None, sets=SETS, points: int = POINTS,
          augment: int = AUGMENT, iterations: int = 5, threshold: float = THRESHOLD, seed: int = 0,
          progress=None, info: dict | None = None, extra: list[Effortful] = (), copies: int = 2) -> EffortModel:
    """All classifiers of :class:`EffortModel` from labelled ``curves``; ``held_out`` curves
    (other performers) calibrate the HMM temperature (1 without them); the Time and Weight
    classifiers learn from ``curves`` and the effort-labelled paths ``extra``."""
    unknown = sorted({c.drive for c in curves} - set(DRIVES))
    if unknown:
        raise ValueError(f"unknown Drive label(s) {unknown}; Drives are {sorted(DRIVES)}")
    missing = sorted(set(DRIVES) - {c.drive for c in curves})
    if missing:
        raise ValueError(f"no training curve for the Drive(s) {missing}: every Drive needs examples")
    step = progress or (lambda stage, i, n: None)
    X = np.array([summary(c.t, c.p, c.q) for c in curves])
    groups = np.array([c.group for c in curves])
    bayes = {}
    for k, factor in enumerate(FACTORS):
        y = np.array([DRIVES[c.drive][k] for c in curves])
        cols, _ = select(X, y, groups)
        bayes[factor] = fit_binary(X, y, cols)
    step("Naive Bayes", 1, 1)
    seqs, drives = _sequences(curves, sets, points, augment, seed, lambda i, n: step("sequences", i, n))
    drive_hmms = fit_set(tuple(DRIVES), seqs, drives, iterations, lambda i, n: step("drive HMMs", i, n))
    element_seqs, element_labels = [], []
    for k, factor in enumerate(FACTORS):  # every other sequence: an Element model still sees as many as a Drive's
        for s, d in zip(seqs[::2], drives[::2]):
            element_seqs.append(s)
            element_labels.append(element(factor, DRIVES[d][k]))
    elements = tuple(e for f in FACTORS for e in reversed(ELEMENTS[f]))
    element_hmms = fit_set(elements, element_seqs, element_labels, iterations,
                           lambda i, n: step("element HMMs", i, n))
    temperature = calibrate(drive_hmms, held_out, sets, points) if held_out else 1.0
    chosen: dict = {}
    decided = train_factors(effortful(curves) + list(extra), copies, seed, chosen)
    step("Time and Weight", 1, 1)
    return EffortModel(bayes, drive_hmms, element_hmms, tuple(sets), points, temperature, threshold,
                       {**(info or {}), "time_weight": chosen}, decided)


def calibrate(hmms: HMMSet, curves: list[Labelled], sets=SETS, points: int = POINTS) -> float:
    """The temperature T minimising the negative log-likelihood of the true Drives of
    ``curves`` under softmax(log-likelihood / T)."""
    ll = hmms.log_likelihoods_many(np.stack([sequence(c.t, c.p, c.q, sets, points) for c in curves]))
    truth = np.array([hmms.labels.index(c.drive) for c in curves])

    def nll(log_t):
        z = ll / np.exp(log_t)
        z = z - z.max(axis=1, keepdims=True)
        return float(np.mean(np.log(np.exp(z).sum(axis=1)) - z[np.arange(len(z)), truth]))

    best = minimize_scalar(nll, bounds=(-3.0, 10.0), method="bounded")
    return float(np.exp(best.x))


def evaluate(model: EffortModel, curves: list[Labelled]) -> dict:
    """Accuracy per Factor, State (Time + Weight) and Drive, and Drive/State confusion
    matrices, for the decisions applied (``effort``: the Time and Weight classifiers, Space
    by the Drive HMM) and the Naive Bayes, Drive HMM and Element HMM methods on ``curves``."""
    truth = [c.drive for c in curves]
    seqs = np.stack([sequence(c.t, c.p, c.q, model.sets, model.points) for c in curves])
    X = np.array([summary(c.t, c.p, c.q) for c in curves])
    labels = model.drives.labels
    hmm = [labels[int(k)] for k in np.argmax(model.drives.log_likelihoods_many(seqs), axis=1)]
    applied = [e.drive for e in qualities(model, [(c.t, c.p, c.q) for c in curves])]
    predictions = {
        "effort": [a or h for a, h in zip(applied, hmm)],
        "naive_bayes": bayes_drive(model, X),
        "drive_hmm": hmm,
        "element_hmm": element_drives(model, seqs),
    }
    report = {"curves": len(curves), "methods": {}}
    for method, pred in predictions.items():
        report["methods"][method] = scores(truth, pred)
    return report


def scores(truth: list[str], pred: list[str]) -> dict:
    """Accuracies per Factor, State and Drive, and confusion matrices (rows = truth)."""
    drives = list(DRIVES)
    out = {}
    for k, factor in enumerate(FACTORS):
        out[factor] = float(np.mean([DRIVES[a][k] == DRIVES[b][k] for a, b in zip(truth, pred)]))
    st = [(state_of(*DRIVES[a][1:]), state_of(*DRIVES[b][1:])) for a, b in zip(truth, pred)]
    out["state"] = float(np.mean([a == b for a, b in st]))
    out["drive"] = float(np.mean([a == b for a, b in zip(truth, pred)]))
    out["drive_confusion"] = _confusion(truth, pred, drives)
    out["state_confusion"] = _confusion([a for a, _ in st], [b for _, b in st], list(STATES))
    return out


def _confusion(truth, pred, labels) -> list[list[int]]:
    m = np.zeros((len(labels), len(labels)), dtype=int)
    for a, b in zip(truth, pred):
        m[labels.index(a), labels.index(b)] += 1
    return m.tolist()


# The shipped default model: generated performers, held-out performers for the temperature,
# and others again for `doodle laban eval` (seeds differ, so no curve is shared).
DEFAULT_DATA = {"train": dict(people=4, repeats=1, free=1, seed=1), "calibrate": dict(people=2, repeats=1, seed=2),
                "test": dict(people=3, repeats=1, free=1, seed=3)}


def generated(part: str = "train", **overrides) -> list[Labelled]:
    """Labelled curves from :mod:`laban.synth` for one part of :data:`DEFAULT_DATA`."""
    from laban import synth

    spec = {**DEFAULT_DATA[part], **overrides}
    return [Labelled(e.t, e.p, e.q, e.drive, f"{part}-{spec['seed']}-person{e.person}")
            for e in synth.dataset(**spec)]


def train_default(progress=None, **options) -> EffortModel:
    """The shipped default model (``doodle laban train --synthetic``)."""
    info = {"data": "laban.synth generated curves", "train": DEFAULT_DATA["train"],
            "calibrate": DEFAULT_DATA["calibrate"]}
    return train(generated("train"), generated("calibrate"), progress=progress, info=info, **options)
