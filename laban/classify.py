"""Effort of one trajectory segment: the Drive HMM's likelihoods (§4.4.2, the thesis's best
method) turned into Time and Weight with a confidence (§4.4.3: Space is not applied — it
would contradict the action the tokens spelled).

The eight Drive log-likelihoods, divided by a temperature calibrated on held-out data (so a
confidence of 0.8 is right about 80 % of the time), give a posterior over Drives under a
uniform prior; summing it over the Drives that are Sudden gives ``P(Sudden)``, likewise
``P(Strong)``. The quality applied is ``L = 2P − 1`` ∈ [−1, 1] (+1 Sudden / Strong), or 0
(neutral) when the confidence ``max(P, 1 − P)`` is under the model's threshold.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from laban.efforts import DRIVES, drive_of, element, state_of
from laban.features import sequence
from laban.models import EffortModel

MIN_SAMPLES = 8  # a segment shorter than this is left neutral
STILL_REACH = 0.03  # m: a hand that stayed within this box diagonal …
STILL_TURN = 0.2  # rad: … and within this angle of its first orientation was still: neutral


@dataclass(frozen=True)
class Quality:
    """What one segment was given: L_t and L_w applied (0 = neutral), the probabilities
    behind them, and the most likely Drive and State."""

    time: float
    weight: float
    p_sudden: float
    p_strong: float
    drive: str
    state: str

    @property
    def time_confidence(self) -> float:
        return max(self.p_sudden, 1.0 - self.p_sudden)

    @property
    def weight_confidence(self) -> float:
        return max(self.p_strong, 1.0 - self.p_strong)


NEUTRAL = Quality(0.0, 0.0, 0.5, 0.5, "", "")


def drive_posterior(model: EffortModel, t: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """(8,) posterior over ``model.drives.labels``."""
    ll = model.drives.log_likelihoods(sequence(t, p, q, model.sets, model.points)) / model.temperature
    w = np.exp(ll - ll.max())
    return w / w.sum()


def quality(model: EffortModel, t: np.ndarray, p: np.ndarray, q: np.ndarray) -> Quality:
    """Time and Weight of the segment ``(t, p, q)``."""
    if len(t) < MIN_SAMPLES or float(t[-1] - t[0]) <= 0:
        return NEUTRAL
    reach = float(np.linalg.norm(np.ptp(p, axis=0)))
    turn = float(2 * np.arccos(np.clip(np.abs(q @ q[0]), 0.0, 1.0)).max())
    if reach < STILL_REACH and turn < STILL_TURN:
        return NEUTRAL
    post = drive_posterior(model, t, p, q)
    labels = model.drives.labels
    sudden = float(sum(w for w, d in zip(post, labels) if DRIVES[d][1] > 0))
    strong = float(sum(w for w, d in zip(post, labels) if DRIVES[d][2] > 0))

    def applied(prob):
        return round(2 * prob - 1, 3) if max(prob, 1 - prob) >= model.threshold else 0.0

    best = labels[int(np.argmax(post))]
    return Quality(applied(sudden), applied(strong), sudden, strong, best, state_of(DRIVES[best][1], DRIVES[best][2]))


def bayes_drive(model: EffortModel, X: np.ndarray) -> list[str]:
    """Drives by the three Naive Bayes classifiers combined (§4.4.1), for summary rows X."""
    signs = {f: model.bayes[f].predict(X) for f in ("space", "time", "weight")}
    return [drive_of(s, t, w) for s, t, w in zip(signs["space"], signs["time"], signs["weight"])]


def element_drive(model: EffortModel, seq: np.ndarray) -> str:
    """The Element HMM method: each Factor by its two Element models, combined as a Drive."""
    ll = dict(zip(model.elements.labels, model.elements.log_likelihoods(seq)))
    signs = [1 if ll[element(f, 1)] >= ll[element(f, -1)] else -1 for f in ("space", "time", "weight")]
    return drive_of(*signs)

