"""Effort of one trajectory segment: Time and Weight with a confidence (§4.4.3: Space is not
applied — it would contradict the action the tokens spelled).

``P(Sudden)`` and ``P(Strong)`` come from the model's calibrated Time and Weight classifiers
on the Effort features (:mod:`laban.factors`, :func:`laban.features.effort_features`), which
describe the movement's quality whatever its size (a figurine, an arm, a walking body) and
its tracking rate (30–144 Hz). The quality applied is ``L = 2P − 1`` ∈ [−1, 1] (+1 Sudden /
Strong), or 0 (neutral: abstention) when the confidence ``max(P, 1 − P)`` is under the
model's threshold. The Drive named beside it is the Drive HMM's (§4.4.2) most likely one
among the two with that Time and Weight — the HMM only adds Space.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from laban.efforts import DRIVES, drive_of, element, state_of
from laban.features import effort_features, sequence
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
    return drive_posteriors(model, [(t, p, q)])[0]


SCORED_AT_ONCE = 64  # segments whose feature sequences are made and scored together (a long doodle's
# thousands never all held at once)


def drive_posteriors(model: EffortModel, pieces: list) -> np.ndarray:
    """(n, 8) posteriors over ``model.drives.labels`` of segments ``(t, p, q)``, scored
    together, :data:`SCORED_AT_ONCE` at a time."""
    ll = np.concatenate([model.drives.log_likelihoods_many(
        np.stack([sequence(t, p, q, model.sets, model.points) for t, p, q in pieces[a:a + SCORED_AT_ONCE]]))
        for a in range(0, len(pieces), SCORED_AT_ONCE)]) / model.temperature
    w = np.exp(ll - ll.max(axis=1, keepdims=True))
    return w / w.sum(axis=1, keepdims=True)


def quality(model: EffortModel, t: np.ndarray, p: np.ndarray, q: np.ndarray) -> Quality:
    """Time and Weight of the segment ``(t, p, q)``."""
    return qualities(model, [(t, p, q)])[0]


def _still(t: np.ndarray, p: np.ndarray, q: np.ndarray) -> bool:
    """Too short to tell, or a hand that stayed put: left neutral."""
    if len(t) < MIN_SAMPLES or float(t[-1] - t[0]) <= 0:
        return True
    reach = float(np.linalg.norm(np.ptp(p, axis=0)))
    turn = float(2 * np.arccos(np.clip(np.abs(q @ q[0]), 0.0, 1.0)).max())
    return reach < STILL_REACH and turn < STILL_TURN


def qualities(model: EffortModel, pieces: list) -> list[Quality]:
    """:func:`quality` of each segment ``(t, p, q)`` of ``pieces``; the Drive HMM scores the
    moving ones together (one forward pass for all)."""
    out = [NEUTRAL] * len(pieces)
    moving = [i for i, piece in enumerate(pieces) if not _still(*piece)]
    if not moving:
        return out

    def applied(prob):
        return round(2 * prob - 1, 3) if max(prob, 1 - prob) >= model.threshold else 0.0

    labels = model.drives.labels
    posts = drive_posteriors(model, [pieces[i] for i in moving])
    for i, post in zip(moving, posts):
        t, p, _ = pieces[i]
        x = effort_features(t, p)[None]
        sudden = float(model.factors["time"].probability(x)[0])
        strong = float(model.factors["weight"].probability(x)[0])
        ts, ws = (1 if sudden >= 0.5 else -1), (1 if strong >= 0.5 else -1)
        same = [k for k, d in enumerate(labels) if DRIVES[d][1:] == (ts, ws)]
        best = labels[max(same, key=lambda k: post[k])]
        out[i] = Quality(applied(sudden), applied(strong), sudden, strong, best, state_of(ts, ws))
    return out


def bayes_drive(model: EffortModel, X: np.ndarray) -> list[str]:
    """Drives by the three Naive Bayes classifiers combined (§4.4.1), for summary rows X."""
    signs = {f: model.bayes[f].predict(X) for f in ("space", "time", "weight")}
    return [drive_of(s, t, w) for s, t, w in zip(signs["space"], signs["time"], signs["weight"])]


def element_drive(model: EffortModel, seq: np.ndarray) -> str:
    """The Element HMM method: each Factor by its two Element models, combined as a Drive."""
    return element_drives(model, np.asarray(seq)[None])[0]


def element_drives(model: EffortModel, seqs: np.ndarray) -> list[str]:
    """:func:`element_drive` of each sequence of ``seqs`` (n, T, d), scored together."""
    out = []
    for row in model.elements.log_likelihoods_many(seqs):
        ll = dict(zip(model.elements.labels, row))
        out.append(drive_of(*[1 if ll[element(f, 1)] >= ll[element(f, -1)] else -1
                              for f in ("space", "time", "weight")]))
    return out

