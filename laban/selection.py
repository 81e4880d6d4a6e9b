"""Relevance-factor feature selection (thesis §4.4.1, eq. 4.13–4.17, after Pink & Ramanathan).

For a feature f normalised to [0, 1], n classes with ``m_i`` examples ``f_ij`` each:

* grand mean            ``f̄   = Σ_i Σ_j f_ij / Σ_i m_i``                 (4.14)
* class means           ``f̄_i = Σ_j f_ij / m_i``                           (4.15)
* inter-class variance  ``σ²_inter = Σ_i m_i (f̄_i − f̄)² / Σ_i m_i``        (4.16)
* intra-class variance  ``σ²_intra = Σ_i Σ_j (f_ij − f̄_i)² / Σ_i m_i``     (4.17)
* relevance             ``Rel(f) = σ²_inter / σ²_intra``                   (4.13)

A feature constant within every class but separating them (σ²_intra = 0 < σ²_inter) has
relevance ``inf`` and ranks first; a feature with no spread between classes (a constant one
included) has relevance 0.
"""

from __future__ import annotations

import numpy as np

ZERO = 1e-15  # variances (on the [0, 1] scale) at or below this are rounding noise


def normalise(
    X: np.ndarray, lo: np.ndarray | None = None, hi: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Min–max scale the columns of ``X`` (m, d) to [0, 1]: ``(X01, lo, hi)``.

    Bounds default to the columns' min and max (training data); pass the training ``lo``,
    ``hi`` to scale test data, which is then clipped to [0, 1]. Constant columns map to 0.
    """
    X = np.asarray(X, float)
    lo = X.min(axis=0) if lo is None else np.asarray(lo, float)
    hi = X.max(axis=0) if hi is None else np.asarray(hi, float)
    span = hi - lo
    ok = span > 0
    X01 = np.where(ok, (X - lo) / np.where(ok, span, 1.0), 0.0)
    return np.clip(X01, 0.0, 1.0), lo, hi


def relevance(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """(d,) relevance factors of the columns of ``X`` (m, d) for the labels ``y`` (m,)."""
    F, _, _ = normalise(X)
    classes, idx, counts = np.unique(np.asarray(y), return_inverse=True, return_counts=True)
    total = float(len(F))
    grand = F.sum(axis=0) / total  # (4.14)
    sums = np.zeros((len(classes), F.shape[1]))
    np.add.at(sums, idx, F)
    means = sums / counts[:, None]  # (4.15)
    inter = (counts[:, None] * (means - grand) ** 2).sum(axis=0) / total  # (4.16)
    intra = ((F - means[idx]) ** 2).sum(axis=0) / total  # (4.17)
    inter = np.where(inter > ZERO, inter, 0.0)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(intra > ZERO, inter / intra, np.where(inter > 0, np.inf, 0.0))


def ranking(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Column indices of ``X``, most relevant first; ties keep column order."""
    return np.argsort(-relevance(X, y), kind="stable")
