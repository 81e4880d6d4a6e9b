"""Sliding-window filters in numpy: the parts of ``scipy.ndimage`` the program uses
(:func:`gaussian_filter1d`, :func:`maximum_filter1d`, :func:`minimum_filter1d`,
:func:`minimum_filter`) — importing ``scipy.ndimage`` costs about half a second at start-up.

Same results as scipy's to rounding (``tests/test_numpy_standins.py``), for the modes
used: ``"reflect"`` (scipy's default: ``d c b a | a b c d | d c b a``, repeated when the
window is longer than the signal) and ``"nearest"`` (the end samples repeated). The
signal is padded once (a gather through folded indices) and every sample's window is a
strided view of it, so a filter is one reduction over that view.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["gaussian_filter1d", "maximum_filter1d", "minimum_filter", "minimum_filter1d"]

MODES = ("reflect", "nearest")


@lru_cache(maxsize=64)
def _padding(n: int, before: int, after: int, mode: str) -> np.ndarray:
    """Indices ``-before … n - 1 + after`` of a signal of ``n`` samples folded back inside
    it as ``mode`` extends the signal."""
    if mode not in MODES:
        raise ValueError(f"mode must be one of {MODES}, not {mode!r}")
    i = np.arange(-before, n + after)
    if mode == "nearest":
        i = np.clip(i, 0, n - 1)
    else:
        i %= 2 * n
        i = np.where(i < n, i, 2 * n - 1 - i)
    i.flags.writeable = False
    return i


def _filtered(x: np.ndarray, axis: int, before: int, after: int, mode: str, reduce) -> np.ndarray:
    """``reduce(windows)`` of ``x`` along ``axis``: ``windows`` (n, columns, taps) is a view
    of the padded signal whose last axis runs over samples ``i - before … i + after``."""
    moved = x.swapaxes(0, axis)
    n = len(moved)
    if n == 0 or moved.size == 0:
        return x.copy()
    padded = moved.reshape(n, -1).take(_padding(n, before, after, mode), axis=0)
    rows, columns = padded.strides
    windows = np.ndarray((n, padded.shape[1], before + 1 + after), padded.dtype, padded, 0, (rows, columns, rows))
    return np.ascontiguousarray(reduce(windows).reshape(moved.shape).swapaxes(0, axis))


@lru_cache(maxsize=32)
def _gaussian(sigma: float, radius: int) -> np.ndarray:
    """scipy's Gaussian kernel: exp(-x²/2σ²) for x in -radius … radius, summing to 1."""
    x = np.arange(-radius, radius + 1)
    phi = np.exp(-0.5 / (sigma * sigma) * x**2)
    phi = phi / phi.sum()
    phi.flags.writeable = False
    return phi


def gaussian_filter1d(x, sigma: float, axis: int = -1, mode: str = "reflect", truncate: float = 4.0) -> np.ndarray:
    """``x`` smoothed along ``axis`` by a Gaussian of ``sigma`` samples cut at ``truncate``
    sigmas (``scipy.ndimage.gaussian_filter1d``; floats out)."""
    sigma = float(sigma)
    radius = int(truncate * sigma + 0.5)
    weights = _gaussian(sigma, radius)
    return _filtered(np.asarray(x, dtype=float), axis, radius, radius, mode, lambda windows: windows @ weights)


def _extreme(ufunc):
    """A reduction over the taps by ``ufunc`` (np.maximum, np.minimum), one tap at a time:
    numpy reduces a short strided axis slowly."""
    def reduce(windows: np.ndarray) -> np.ndarray:
        out = windows[..., 0].copy()
        for k in range(1, windows.shape[-1]):
            ufunc(out, windows[..., k], out=out)
        return out
    return reduce


def maximum_filter1d(x, size: int, axis: int = -1, mode: str = "reflect") -> np.ndarray:
    """The largest of ``size`` samples around each (``scipy.ndimage.maximum_filter1d``:
    samples ``i - size // 2 … i + (size - 1) // 2``)."""
    if size < 1:
        raise ValueError("size must be at least 1")
    return _filtered(np.asarray(x), axis, size // 2, (size - 1) // 2, mode, _extreme(np.maximum))


def minimum_filter1d(x, size: int, axis: int = -1, mode: str = "reflect") -> np.ndarray:
    """The smallest of ``size`` samples around each (``scipy.ndimage.minimum_filter1d``)."""
    if size < 1:
        raise ValueError("size must be at least 1")
    return _filtered(np.asarray(x), axis, size // 2, (size - 1) // 2, mode, _extreme(np.minimum))


def minimum_filter(x, size: int, mode: str = "reflect") -> np.ndarray:
    """The smallest value in the ``size``-wide box around each element, along every axis
    (``scipy.ndimage.minimum_filter`` with a scalar ``size``)."""
    out = np.asarray(x)
    for axis in range(out.ndim):
        out = minimum_filter1d(out, size, axis, mode)
    return out
