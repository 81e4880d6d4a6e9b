"""Peaks of a 1-D signal: :func:`find_peaks`, the part of ``scipy.signal.find_peaks`` the
program uses, in numpy — importing ``scipy.signal`` costs about half a second at start-up.

Same peaks, same properties, same order as scipy 1.17 for the options here (``height``,
``prominence``, ``distance``, ``plateau_size``, each a lower bound or a ``(min, max)``
pair) — ``tests/test_signal.py`` compares them on random signals with plateaus and on
real clips. The algorithm is scipy's:

1. local maxima: every run of equal samples whose neighbours on both sides are lower
   (a run touching either end is not a peak); the peak is the run's middle sample (left
   of centre for an even run);
2. kept by plateau size, then by height, then by distance — peaks in order of height
   (``numpy.argsort``, as scipy sorts them), each removing the lower peaks closer than
   ``distance`` samples — then by prominence: a peak's height above the higher of the
   lowest samples on either side before the signal rises above the peak (or ends).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["find_peaks"]


def _bounds(condition, x: np.ndarray, peaks: np.ndarray) -> tuple:
    """``(min, max)`` of a condition given as a number, an array per sample or a pair of
    those (scipy's ``_unpack_condition_args``)."""
    try:
        lo, hi = condition
    except (TypeError, ValueError):
        lo, hi = condition, None
    for name, v in (("lower", lo), ("upper", hi)):
        if isinstance(v, np.ndarray) and v.size != x.size:
            raise ValueError(f"array size of {name} interval border must match x")
    lo = lo[peaks] if isinstance(lo, np.ndarray) else lo
    hi = hi[peaks] if isinstance(hi, np.ndarray) else hi
    return lo, hi


def _keep(prop: np.ndarray, lo, hi) -> np.ndarray:
    keep = np.ones(len(prop), dtype=bool)
    if lo is not None:
        keep &= lo <= prop
    if hi is not None:
        keep &= prop <= hi
    return keep


def local_maxima(x: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Midpoints, left and right edges of the local maxima of ``x`` (flat ones included)."""
    n = len(x)
    if n < 3:
        empty = np.empty(0, dtype=np.intp)
        return empty, empty, empty
    new = np.flatnonzero(~(x[1:] == x[:-1])) + 1  # where a run of equal samples starts (NaN: its own run)
    starts = np.concatenate([[0], new])
    ends = np.concatenate([new - 1, [n - 1]])
    inner = (starts >= 1) & (ends <= n - 2)
    starts, ends = starts[inner], ends[inner]
    peak = (x[starts - 1] < x[starts]) & (x[ends + 1] < x[ends])
    left, right = starts[peak].astype(np.intp), ends[peak].astype(np.intp)
    return (left + right) // 2, left, right


def prominences(x: np.ndarray, peaks: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Prominence, left base and right base of each peak (scipy's ``peak_prominences``
    without a window)."""
    prom = np.empty(len(peaks))
    left_bases = np.empty(len(peaks), dtype=np.intp)
    right_bases = np.empty(len(peaks), dtype=np.intp)
    for k, p in enumerate(peaks):
        top = x[p]
        higher = np.flatnonzero(~(x[:p] <= top))  # the scan to the left stops at the first of these
        lo = higher[-1] + 1 if len(higher) else 0
        left = x[lo:p + 1]
        i = len(left) - 1 - int(np.argmin(left[::-1]))  # the lowest, nearest the peak
        higher = np.flatnonzero(~(x[p + 1:] <= top))
        hi = p + 1 + higher[0] if len(higher) else len(x)
        right = x[p:hi]
        j = int(np.argmin(right))
        left_bases[k], right_bases[k] = lo + i, p + j
        prom[k] = top - max(left[i], right[j])
    return prom, left_bases, right_bases


def _by_distance(peaks: np.ndarray, priority: np.ndarray, distance: float) -> np.ndarray:
    """Which peaks to keep so that none is closer than ``distance`` to a higher kept one."""
    reach = math.ceil(distance)
    keep = np.ones(len(peaks), dtype=bool)
    order = np.argsort(priority)  # scipy's order, ties included
    for i in range(len(peaks) - 1, -1, -1):
        j = order[i]
        if not keep[j]:
            continue
        k = j - 1
        while k >= 0 and peaks[j] - peaks[k] < reach:
            keep[k] = False
            k -= 1
        k = j + 1
        while k < len(peaks) and peaks[k] - peaks[j] < reach:
            keep[k] = False
            k += 1
    return keep


def find_peaks(x, height=None, prominence=None, distance=None, plateau_size=None) -> tuple[np.ndarray, dict]:
    """Peaks of the 1-D signal ``x`` and their properties, as ``scipy.signal.find_peaks``
    with these options (see the module docstring): ``(peaks, properties)`` with
    ``plateau_sizes``, ``left_edges``, ``right_edges`` (given ``plateau_size``),
    ``peak_heights`` (given ``height``), ``prominences``, ``left_bases``, ``right_bases``
    (given ``prominence``)."""
    x = np.asarray(x, dtype=np.float64)
    if x.ndim != 1:
        raise ValueError("`x` must be a 1-D array")
    if distance is not None and distance < 1:
        raise ValueError("`distance` must be greater or equal to 1")
    peaks, left_edges, right_edges = local_maxima(x)
    props: dict = {}
    if plateau_size is not None:
        sizes = right_edges - left_edges + 1
        props.update(plateau_sizes=sizes, left_edges=left_edges, right_edges=right_edges)
        keep = _keep(sizes, *_bounds(plateau_size, x, peaks))
        peaks = peaks[keep]
        props = {key: v[keep] for key, v in props.items()}
    if height is not None:
        heights = x[peaks]
        props["peak_heights"] = heights
        keep = _keep(heights, *_bounds(height, x, peaks))
        peaks = peaks[keep]
        props = {key: v[keep] for key, v in props.items()}
    if distance is not None:
        keep = _by_distance(peaks, x[peaks], distance)
        peaks = peaks[keep]
        props = {key: v[keep] for key, v in props.items()}
    if prominence is not None:
        prom, left_bases, right_bases = prominences(x, peaks)
        props.update(prominences=prom, left_bases=left_bases, right_bases=right_bases)
        keep = _keep(prom, *_bounds(prominence, x, peaks))
        peaks = peaks[keep]
        props = {key: v[keep] for key, v in props.items()}
    return peaks, props
