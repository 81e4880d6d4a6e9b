"""Denoising of doodle channels (thesis §4.1.1): Laplacian smoothing and Savitzky–Golay.

Both are symmetric FIR kernels applied over sample indices with *odd reflection* at the
ends (the signal is mirrored through its end sample, ``x[-j] = 2 x[0] - x[j]``), which keeps
a motion that is linear near an end linear — the end behaviour that made the thesis drop
Savitzky–Golay's polynomial end fits. ``k`` iterations of the Laplacian umbrella step
``x_i += λ ((x_{i-1} + x_{i+1})/2 - x_i)`` equal one pass of the kernel
``[λ/2, 1-λ, λ/2]`` convolved ``k`` times with itself, which is what is applied.

The kernel length is set in seconds and converted to samples per device rate, so a doodle
smooths the same at 90 Hz and at 144 Hz. Quaternions are smoothed on the sphere: signs made
continuous, components filtered, then renormalised (valid because a kernel spans well under
a tenth of a second, over which orientations differ by small angles).

:func:`smooth` (batch) and :class:`StreamingSmoother` (one sample at a time) use the same
arithmetic in the same order and give bit-identical results.
"""

from __future__ import annotations

import copy
from collections import deque

import numpy as np

ITERATED = 2000  # Laplacian iterations computed one by one; beyond, the kernel in closed form


def laplacian_kernel(sigma_s: float, rate: float, lam: float = 0.5) -> np.ndarray:
    """Kernel of ``k`` Laplacian iterations with temporal std close to ``sigma_s`` seconds.

    One iteration has variance ``λ`` samples², so ``k = round(σ² F² / λ)``.
    """
    k = max(0, int(round((sigma_s * rate) ** 2 / lam)))
    if k > ITERATED and lam == 0.5:  # (¼, ½, ¼) k times is the binomial (2k, ½): O(k), not O(k²)
        from scipy.stats import binom

        return binom.pmf(np.arange(2 * k + 1), 2 * k, 0.5)
    kernel = np.array([1.0])
    step = np.array([lam / 2.0, 1.0 - lam, lam / 2.0])
    for _ in range(k):
        kernel = np.convolve(kernel, step)
    return kernel


def savgol_coeffs(window_length: int, polyorder: int) -> np.ndarray:
    """Savitzky–Golay smoothing coefficients: ``scipy.signal.savgol_coeffs(window_length,
    polyorder)`` (value at the window's centre, convolution order), written out.

    The least-squares fit of a polynomial of degree ``polyorder`` to ``window_length``
    samples at offsets ``-h … h`` from the centre, evaluated at 0: the coefficients ``c``
    solve ``A c = e_0`` in the least-squares sense, where ``A[k, i] = x_i ** k`` — scipy's
    own formulation and LAPACK driver (``gelsd``), so the two agree to rounding
    (``tests/test_signal.py`` checks 1e-12) without importing ``scipy.signal`` (half a
    second at start-up).
    """
    if not 0 <= polyorder < window_length:
        raise ValueError("polyorder must be less than window_length.")
    halflen, rem = divmod(window_length, 2)
    pos = halflen if rem else halflen - 0.5
    x = np.arange(-pos, window_length - pos, dtype=float)[::-1]  # reversed: for a convolution
    A = x ** np.arange(polyorder + 1, dtype=float).reshape(-1, 1)
    y = np.zeros(polyorder + 1)
    y[0] = 1.0
    return np.linalg.lstsq(A, y, rcond=np.finfo(float).eps * max(A.shape))[0]


def savgol_kernel(window_s: float, rate: float, order: int = 3) -> np.ndarray:
    """Savitzky–Golay smoothing kernel for a window of about ``window_s`` seconds."""
    n = max(order + 2, int(round(window_s * rate)))
    n += 1 - n % 2  # odd length
    return savgol_coeffs(n, order)


def smooth(x: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """Filter the columns of ``x`` (n, c) with a symmetric kernel, odd reflection at the ends.

    A signal with no more samples than the kernel's half width is returned unchanged.
    """
    h = len(kernel) // 2
    n = len(x)
    if h == 0 or n <= h:
        return x.copy()
    left = 2.0 * x[0] - x[h:0:-1]
    right = 2.0 * x[-1] - x[-2 : -h - 2 : -1]
    padded = np.concatenate([left, x, right])
    acc = kernel[0] * padded[0:n]
    for j in range(1, len(kernel)):
        acc = acc + kernel[j] * padded[j : j + n]
    return acc


class StreamingSmoother:
    """:func:`smooth` one row at a time: ``push`` returns the rows that became final.

    Output row i is known once row ``i + h`` has arrived; :meth:`close` returns the tail.
    Rows go into a long buffer so the current window is always one contiguous slice.
    """

    BUFFER = 4096

    def __init__(self, kernel: np.ndarray, channels: int):
        self.h = len(kernel) // 2
        self.width = len(kernel)
        self.weights = kernel[:, None]
        self.buf = np.zeros((max(self.BUFFER, 4 * self.width), channels))
        self.tmp = np.zeros((self.width, channels))
        self.fill = 0  # rows of the virtual sequence (left padding + real rows) now in buf
        self.head: list = []  # the first h+1 rows, kept for the start reflection
        self.last: deque = deque(maxlen=self.h + 1)  # the latest rows, for the end reflection
        self.n = 0  # real rows pushed

    def _feed(self, row) -> np.ndarray | None:
        if self.fill == len(self.buf):  # slide the last width-1 rows to the front
            keep = self.width - 1
            self.buf[:keep] = self.buf[self.fill - keep : self.fill]
            self.fill = keep
        self.buf[self.fill] = row
        self.fill += 1
        if self.fill < self.width:
            return None
        window = self.buf[self.fill - self.width : self.fill]
        # Row-by-row accumulation over axis 0 of a C-contiguous array: the same order of
        # additions as the loop in :func:`smooth`, hence bit-identical results.
        return np.add.reduce(np.multiply(self.weights, window, out=self.tmp), axis=0)

    def push(self, row) -> list[np.ndarray]:
        """Add one row (a sequence of ``channels`` floats)."""
        self.n += 1
        if self.h == 0:
            return [np.array(row, dtype=float)]
        self.last.append(row)
        if self.n > self.h + 1:
            return [self._feed(row)]
        self.head.append(row)
        if self.n < self.h + 1:
            return []
        head = np.array(self.head, dtype=float)
        for j in range(self.h, 0, -1):
            self._feed(2.0 * head[0] - head[j])
        return [y for y in map(self._feed, head) if y is not None]

    def fork(self) -> "StreamingSmoother":
        """An independent copy (what it is pushed, or closing it, leaves this one as it is)."""
        other = copy.copy(self)
        keep = min(self.fill, self.width - 1)  # all a window can still read
        other.buf = np.zeros_like(self.buf[: max(4 * self.width, keep + 1)])
        other.buf[:keep] = self.buf[self.fill - keep: self.fill]
        other.fill, other.tmp = keep, np.zeros_like(self.tmp)
        other.head, other.last = list(self.head), deque(self.last, maxlen=self.last.maxlen)
        return other

    def close(self) -> list[np.ndarray]:
        """Rows not yet returned, using the end reflection (or unsmoothed if too short)."""
        if self.h == 0:
            return []
        if self.n <= self.h:
            return [np.array(r, dtype=float) for r in self.head]
        last = np.array(self.last, dtype=float)
        reflected = 2.0 * last[-1] - last[-2::-1][: self.h]
        rows = np.concatenate([self.buf[self.fill - (self.width - 1): self.fill], reflected])
        # every tail window at once, (h, width, channels) C-contiguous: reduced over the
        # width axis row by row as _feed does, hence bit-identical
        windows = rows[np.arange(self.h)[:, None] + np.arange(self.width)[None, :]]
        return list(np.add.reduce(self.weights[None] * windows, axis=1))
