"""Piecewise cubic interpolation in numpy: the parts of ``scipy.interpolate`` the program
uses (:class:`CubicSpline` with "not-a-knot" or "natural" ends, :class:`PchipInterpolator`,
both :class:`CubicHermiteSpline` s) — importing ``scipy.interpolate`` costs about half a
second at start-up.

scipy's formulas: the same slopes at the knots, the same polynomial coefficients and the
same evaluation, extrapolating past the ends; the spline's tridiagonal system is solved by
the Thomas algorithm instead of LAPACK, so results agree to rounding
(``tests/test_numpy_standins.py``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["CubicHermiteSpline", "CubicSpline", "PchipInterpolator"]


def _prepared(x, y, axis: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``(x, dx, y with axis first, axis)``, checked as scipy checks them."""
    x = np.asarray(x, dtype=float)
    y = np.asarray(y, dtype=float)
    axis = axis % y.ndim
    if x.ndim != 1:
        raise ValueError("`x` must be 1-dimensional.")
    if len(x) < 2:
        raise ValueError("`x` must contain at least 2 elements.")
    if len(x) != y.shape[axis]:
        raise ValueError(f"The length of `y` along `axis`={axis} doesn't match the length of `x`")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("`x` and `y` must contain only finite values.")
    dx = np.diff(x)
    if np.any(dx <= 0):
        raise ValueError("`x` must be strictly increasing sequence.")
    return x, dx, np.moveaxis(y, axis, 0), axis


class CubicHermiteSpline:
    """The piecewise cubic through values ``y`` with slopes ``dydx`` at the knots ``x``
    (``scipy.interpolate.CubicHermiteSpline``); called at points, it gives the values there."""

    def __init__(self, x, y, dydx, axis: int = 0):
        x, dx, y, axis = _prepared(x, y, axis)
        dydx = np.moveaxis(np.asarray(dydx, dtype=float), axis, 0)
        if dydx.shape != y.shape:
            raise ValueError("The shapes of `y` and `dydx` must be identical.")
        self._set(x, dx, y, dydx, axis)

    def _set(self, x, dx, y, dydx, axis: int) -> None:
        dxr = dx.reshape((-1,) + (1,) * (y.ndim - 1))
        slope = np.diff(y, axis=0) / dxr
        t = (dydx[:-1] + dydx[1:] - 2 * slope) / dxr
        self.x, self.axis = x, axis
        # scipy's coefficients per piece, highest power first: (n - 1, 4, ...)
        self._pieces = np.stack((t / dxr, (slope - dydx[:-1]) / dxr - t, dydx[:-1], y[:-1]), axis=1)

    def __call__(self, xnew) -> np.ndarray:
        xnew = np.asarray(xnew, dtype=float)
        flat = xnew.ravel()
        i = np.searchsorted(self.x, flat, side="right") - 1
        np.clip(i, 0, len(self.x) - 2, out=i)
        tail = self._pieces.shape[2:]
        s = (flat - self.x[i]).reshape((-1,) + (1,) * len(tail))
        c = self._pieces[i]
        s2 = s * s  # scipy's order: c3 + c2 s + c1 s² + c0 s³, the powers built up
        out = ((c[:, 3] + c[:, 2] * s) + c[:, 1] * s2) + c[:, 0] * (s2 * s)
        out = out.reshape(xnew.shape + tail)
        if self.axis:
            k = xnew.ndim
            order = list(range(out.ndim))
            out = out.transpose(order[k:k + self.axis] + order[:k] + order[k + self.axis:])
        return out


def _recurrence(alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
    """``y`` with ``y[0] = beta[0]`` and ``y[i] = alpha[i] y[i-1] + beta[i]`` (``beta`` (n, c)),
    by recursive doubling: log2(n) steps over whole arrays instead of n steps over rows."""
    y, a = beta.copy(), alpha.copy()
    a[0] = 0.0
    shift = 1
    while shift < len(y):
        y[shift:] += a[shift:, None] * y[:-shift]
        a[shift:] = a[shift:] * a[:-shift]
        shift *= 2
    return y


def _tridiagonal(lower: np.ndarray, diag: np.ndarray, upper: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The solution of the tridiagonal system whose row i is ``lower[i] x[i-1] + diag[i] x[i]
    + upper[i] x[i+1] = b[i]`` (``b`` (n, ...): one right-hand side per column): Thomas's
    LU factors without pivoting, as for a diagonally dominant system such as a spline's,
    then the two substitutions (:func:`_recurrence`)."""
    n = len(diag)
    lo, di, up = lower.tolist(), diag.tolist(), upper.tolist()
    pivot, factor = [di[0]] * n, [0.0] * n
    for i in range(1, n):
        factor[i] = lo[i] / pivot[i - 1]
        pivot[i] = di[i] - factor[i] * up[i - 1]
    pivot = np.array(pivot)
    z = _recurrence(-np.array(factor), b.reshape(n, -1))  # L z = b
    x = _recurrence(-(upper / pivot)[::-1], (z / pivot[:, None])[::-1])[::-1]  # U x = z
    return x.reshape(b.shape)


class CubicSpline(CubicHermiteSpline):
    """The C² cubic spline through ``y`` at the knots ``x`` (``scipy.interpolate.CubicSpline``),
    ``bc_type`` "not-a-knot" (scipy's default) or "natural" (no curvature at the ends)."""

    def __init__(self, x, y, axis: int = 0, bc_type: str = "not-a-knot"):
        if bc_type not in ("not-a-knot", "natural"):
            raise ValueError(f"bc_type must be 'not-a-knot' or 'natural', not {bc_type!r}")
        x, dx, y, axis = _prepared(x, y, axis)
        n = len(x)
        dxr = dx.reshape((-1,) + (1,) * (y.ndim - 1))
        slope = np.diff(y, axis=0) / dxr
        knot = bc_type == "not-a-knot"
        if knot and n == 2:  # a line
            s = np.stack([slope[0], slope[0]])
        elif knot and n == 3:  # the parabola through the three points
            a = np.array([[1.0, 1.0, 0.0], [dx[1], 2 * (dx[0] + dx[1]), dx[0]], [0.0, 1.0, 1.0]])
            b = np.stack([2 * slope[0], 3 * (dxr[0] * slope[1] + dxr[1] * slope[0]), 2 * slope[1]])
            s = np.linalg.solve(a, b.reshape(3, -1)).reshape(b.shape)
        else:
            lower, diag, upper = np.zeros(n), np.zeros(n), np.zeros(n)
            b = np.empty_like(y)
            diag[1:-1] = 2 * (dx[:-1] + dx[1:])
            upper[1:-1] = dx[:-1]
            lower[1:-1] = dx[1:]
            b[1:-1] = 3 * (dxr[1:] * slope[:-1] + dxr[:-1] * slope[1:])
            if knot:
                d = x[2] - x[0]
                diag[0], upper[0] = dx[1], d
                b[0] = ((dxr[0] + 2 * d) * dxr[1] * slope[0] + dxr[0] ** 2 * slope[1]) / d
                d = x[-1] - x[-3]
                diag[-1], lower[-1] = dx[-2], d
                b[-1] = (dxr[-1] ** 2 * slope[-2] + (2 * d + dxr[-1]) * dxr[-2] * slope[-1]) / d
            else:  # natural: second derivative 0 at both ends
                diag[0], upper[0] = 2 * dx[0], dx[0]
                b[0] = 3 * (y[1] - y[0])
                diag[-1], lower[-1] = 2 * dx[-1], dx[-1]
                b[-1] = 3 * (y[-1] - y[-2])
            s = _tridiagonal(lower, diag, upper, b)
        self._set(x, dx, y, s, axis)


class PchipInterpolator(CubicHermiteSpline):
    """The monotone piecewise cubic through ``y`` at ``x`` (``scipy.interpolate.PchipInterpolator``):
    slopes by Fritsch–Butland's weighted harmonic mean, zero at a local extremum, one-sided
    three-point estimates at the ends."""

    def __init__(self, x, y, axis: int = 0):
        x, dx, y, axis = _prepared(x, y, axis)
        h = dx.reshape((-1,) + (1,) * (y.ndim - 1))
        m = np.diff(y, axis=0) / h
        d = np.zeros_like(y)
        if len(x) == 2:
            d[0] = d[1] = m[0]
        else:
            sign = np.sign(m)
            flat = (sign[1:] != sign[:-1]) | (m[1:] == 0) | (m[:-1] == 0)
            w1, w2 = 2 * h[1:] + h[:-1], h[1:] + 2 * h[:-1]
            with np.errstate(divide="ignore", invalid="ignore"):
                mean = (w1 / m[:-1] + w2 / m[1:]) / (w1 + w2)
            d[1:-1] = np.where(flat, 0.0, 1.0 / np.where(flat, 1.0, mean))
            d[0] = _pchip_end(h[0], h[1], m[0], m[1])
            d[-1] = _pchip_end(h[-1], h[-2], m[-1], m[-2])
        self._set(x, dx, y, d, axis)


def _pchip_end(h0, h1, m0, m1) -> np.ndarray:
    """The slope at an end: the one-sided three-point estimate, kept shape-preserving."""
    d = ((2 * h0 + h1) * m0 - h0 * m1) / (h0 + h1)
    wrong_sign = np.sign(d) != np.sign(m0)
    overshoot = (np.sign(m0) != np.sign(m1)) & (np.abs(d) > 3.0 * np.abs(m0))
    return np.where(wrong_sign, 0.0, np.where(overshoot, 3.0 * m0, d))
