"""As-rigid-as-possible deformation of a curve (thesis §6.2.2 eq. 6.4–6.7, reused by §6.4
eq. 6.9): every interior point is written in its neighbours' frame,
``p_i = p_{i−1} + α_i A_i + β_i B_i`` with ``A_i`` the unit ``p_{i+1} − p_{i−1}``, and a
deformed curve keeps each ``(α_i, β_i)`` while some of its points are pinned to targets. The
curve may be positions (a hand's path) or rotation vectors (a figurine's orientations).
"""

from __future__ import annotations

import numpy as np

GAMMA = 1e4  # weight of a pinned point against the shape terms
STAY = 1e-3  # a little weight on staying put: (α, β) do not see a twist about A_i
MAX_POINTS = 32  # longer curves are solved on this many of their points


def local_coordinates(p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(α_i, β_i)`` of the interior points of a curve (n, 3) in their neighbours' frame
    (eq. 6.4–6.6): n − 2 values each."""
    d = p[1:-1] - p[:-2]
    a = p[2:] - p[:-2]
    a = a / np.maximum(np.linalg.norm(a, axis=1, keepdims=True), 1e-9)
    return np.sum(d * a, axis=1), np.linalg.norm(np.cross(d, a), axis=1)


def deform(curve: np.ndarray, pins: dict, start: np.ndarray | None = None, laplacian: float = 0.0) -> np.ndarray:
    """The curve (n, 3) with ``pins`` ({index: point}) met and its first and last points
    kept (unless pinned), every other point free, minimising
    ``Σ ‖(α, β)₀ − (α, β)‖² + γ Σ ‖p_k − pin_k‖²`` (eq. 6.7) by least squares from
    ``start`` (default: the curve itself). ``laplacian`` > 0 adds that weight on keeping
    each point's second difference ``p_{i−1} − 2p_i + p_{i+1}`` (Laplacian coordinates):
    ``(α, β)`` do not see a step where a curve stands still (its ``A_i`` is undefined), so a
    still curve pinned away from itself would keep a jump at the pin; this spreads it."""
    from scipy.optimize import least_squares

    curve = np.asarray(curve, dtype=float)
    n = len(curve)
    if n > MAX_POINTS:  # solved on a coarse copy, the displacement spread back over every point
        keep = np.unique(np.concatenate([np.round(np.linspace(0, n - 1, MAX_POINTS)).astype(int),
                                         np.array(sorted(pins), dtype=int)]))
        coarse = deform(curve[keep], {int(np.searchsorted(keep, k)): v for k, v in pins.items()},
                        None if start is None else np.asarray(start, dtype=float)[keep], laplacian)
        moved = coarse - curve[keep]
        out = curve + np.column_stack([np.interp(np.arange(n), keep, moved[:, c]) for c in range(3)])
        for k, v in pins.items():
            out[k] = v
        return out
    if n < 3:
        out = curve.copy()
        for k, v in pins.items():
            out[k] = v
        return out
    alpha0, beta0 = local_coordinates(curve)
    lap0 = curve[:-2] - 2.0 * curve[1:-1] + curve[2:]
    fixed = curve.copy()
    for k in (0, n - 1):
        if k in pins:
            fixed[k] = pins[k]
    inner = {k: np.asarray(v, dtype=float) for k, v in pins.items() if 0 < k < n - 1}
    idx = np.array(sorted(inner), dtype=int)
    want = np.array([inner[k] for k in idx]).reshape(-1, 3)

    def residuals(x):
        p = fixed.copy()
        p[1:-1] = x.reshape(-1, 3)
        alpha, beta = local_coordinates(p)
        smooth = np.sqrt(laplacian) * (p[:-2] - 2.0 * p[1:-1] + p[2:] - lap0).ravel() if laplacian else []
        return np.concatenate([alpha - alpha0, beta - beta0, np.sqrt(GAMMA) * (p[idx] - want).ravel(),
                               np.sqrt(STAY) * (p[1:-1] - curve[1:-1]).ravel(), smooth])

    x0 = (curve if start is None else np.asarray(start, dtype=float))[1:-1]
    solved = least_squares(residuals, x0.ravel(), method="lm", xtol=1e-5, ftol=1e-5)
    out = fixed.copy()
    out[1:-1] = solved.x.reshape(-1, 3)
    return out

