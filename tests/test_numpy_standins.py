"""The numpy stand-ins for scipy.ndimage and scipy.interpolate (doodle.core.filters,
doodle.core.splines) give scipy's results, to rounding, on random inputs of many shapes and
on the edge cases: one or two samples, a window longer than the signal, extrapolation."""

import numpy as np
import pytest
import scipy.interpolate as si
import scipy.ndimage as nd

from doodle.core import filters, splines

TOL = 1e-12


def _close(ours, theirs) -> bool:
    ours, theirs = np.asarray(ours), np.asarray(theirs)
    scale = max(float(np.max(np.abs(theirs), initial=0.0)), 1e-300)
    return ours.shape == theirs.shape and float(np.max(np.abs(ours - theirs), initial=0.0)) <= TOL * scale


SHAPES = [(1,), (2,), (3,), (5,), (17,), (120,), (1, 3), (2, 3), (7, 3), (259, 3), (4, 2, 4), (33, 5, 4)]


@pytest.mark.parametrize("mode", ["reflect", "nearest"])
def test_gaussian_filter1d_equals_scipys(mode):
    rng = np.random.default_rng(0)
    for shape in SHAPES:
        for axis in range(-1, len(shape)):
            for sigma in (0.05, 0.3, 0.5, 1.0, 1.5, 2.0, 3.7, 4.803, 6.0, 12.5):  # radius 0 … 50, past short signals
                x = rng.normal(size=shape) * 10.0 ** rng.integers(-3, 4)
                ours = filters.gaussian_filter1d(x, sigma, axis=axis, mode=mode)
                assert _close(ours, nd.gaussian_filter1d(x, sigma, axis=axis, mode=mode)), (shape, axis, sigma)
                assert ours.flags.c_contiguous
    x = rng.normal(size=(40, 3))
    assert _close(filters.gaussian_filter1d(x, 2.0, axis=0, truncate=2.0), nd.gaussian_filter1d(x, 2.0, axis=0, truncate=2.0))
    assert _close(filters.gaussian_filter1d(np.arange(9), 1.0), nd.gaussian_filter1d(np.arange(9.0), 1.0))


def test_the_comparison_can_tell_the_modes_apart():
    x = np.random.default_rng(1).normal(size=30)
    assert not _close(filters.gaussian_filter1d(x, 3.0, mode="reflect"), nd.gaussian_filter1d(x, 3.0, mode="nearest"))
    assert not _close(filters.gaussian_filter1d(x, 3.0), nd.gaussian_filter1d(x, 3.1))
    with pytest.raises(ValueError):
        filters.gaussian_filter1d(x, 1.0, mode="wrap")


@pytest.mark.parametrize("mode", ["reflect", "nearest"])
def test_minimum_and_maximum_filters_equal_scipys_exactly(mode):
    rng = np.random.default_rng(2)
    for shape in SHAPES:
        for axis in range(-1, len(shape)):
            for size in (1, 2, 3, 4, 5, 8, 41):
                x = np.round(rng.normal(size=shape), 1)  # ties
                assert np.array_equal(filters.maximum_filter1d(x, size, axis=axis, mode=mode),
                                      nd.maximum_filter1d(x, size, axis=axis, mode=mode)), (shape, axis, size)
                assert np.array_equal(filters.minimum_filter1d(x, size, axis=axis, mode=mode),
                                      nd.minimum_filter1d(x, size, axis=axis, mode=mode)), (shape, axis, size)
    for shape in ((1, 1), (2, 5), (30, 17), (6, 5, 4)):
        for size in (2, 3, 5):
            d = np.round(rng.normal(size=shape), 1)
            assert np.array_equal(filters.minimum_filter(d, size, mode=mode), nd.minimum_filter(d, size=size, mode=mode))
    assert np.array_equal(filters.maximum_filter1d(np.array([3, 1, 2]), 3), nd.maximum_filter1d(np.array([3, 1, 2]), 3))


def _knots(rng, n: int) -> np.ndarray:
    return np.cumsum(rng.uniform(0.3, 1.7, n)) * 10.0 ** rng.integers(-2, 2) + rng.normal()


@pytest.mark.parametrize("bc_type", ["not-a-knot", "natural"])
def test_cubic_spline_equals_scipys(bc_type):
    rng = np.random.default_rng(3)
    for n in list(range(2, 12)) + [40, 97, 300]:
        x = _knots(rng, n)
        inside = np.sort(rng.uniform(x[0], x[-1], 50))
        points = np.concatenate([inside, x, [x[0] - 0.3 * np.ptp(x), x[-1] + 0.2 * np.ptp(x)]])
        for shape in ((n,), (n, 3), (n, 2, 4)):
            y = rng.normal(size=shape) * 10.0 ** rng.integers(-3, 3)
            ours = splines.CubicSpline(x, y, axis=0, bc_type=bc_type)(points)
            assert _close(ours, si.CubicSpline(x, y, axis=0, bc_type=bc_type)(points)), (n, shape)
        y = rng.normal(size=(3, n))
        grid = np.linspace(x[0], x[-1], 7).reshape(7, 1)
        assert _close(splines.CubicSpline(x, y, axis=1, bc_type=bc_type)(grid),
                      si.CubicSpline(x, y, axis=1, bc_type=bc_type)(grid)), n
    t = np.arange(46) / 30.0  # a clip's frames (retarget.effort_signature), evaluated at 120 Hz
    p = np.cumsum(rng.normal(size=(46, 3)), axis=0)
    tt = np.arange(0.0, t[-1] + 1e-9, 1 / 120)
    assert _close(splines.CubicSpline(t, p, bc_type=bc_type)(tt), si.CubicSpline(t, p, bc_type=bc_type)(tt))


def test_cubic_spline_checks_its_input_like_scipy():
    for x, y in (([0.0], [1.0]), ([0.0, 1.0, 1.0], [1.0, 2.0, 3.0]), ([0.0, 1.0], [1.0, np.nan]), ([0.0, 1.0], [1.0])):
        with pytest.raises(ValueError):
            splines.CubicSpline(x, y)
    with pytest.raises(ValueError):
        splines.CubicSpline([0.0, 1.0, 2.0], [0.0, 1.0, 0.0], bc_type="clamped")


def test_pchip_equals_scipys():
    rng = np.random.default_rng(4)
    for n in list(range(2, 10)) + [46, 200]:
        x = _knots(rng, n)
        points = np.concatenate([np.sort(rng.uniform(x[0], x[-1], 60)), x, [x[0] - 1.0, x[-1] + 1.0]])
        for y in (np.round(rng.normal(size=n), 1),  # flat stretches and sign changes: zero slopes
                  np.cumsum(rng.uniform(0.0, 1.0, n)),  # monotone (retarget.stylize's time warp)
                  rng.normal(size=(n, 3)), np.zeros(n)):
            assert _close(splines.PchipInterpolator(x, y)(points), si.PchipInterpolator(x, y)(points)), (n, y.shape)
    x = _knots(rng, 6)
    y = rng.normal(size=(2, 6))
    assert _close(splines.PchipInterpolator(x, y, axis=1)(x[2]), si.PchipInterpolator(x, y, axis=1)(x[2]))


def test_cubic_hermite_spline_equals_scipys():
    rng = np.random.default_rng(5)
    x = _knots(rng, 12)
    y, dydx = rng.normal(size=(12, 3)), rng.normal(size=(12, 3))
    points = np.linspace(x[0] - 1, x[-1] + 1, 99)
    assert _close(splines.CubicHermiteSpline(x, y, dydx)(points), si.CubicHermiteSpline(x, y, dydx)(points))


def test_the_catmull_rom_resampling_equals_the_sparse_product():
    from scipy.sparse import csr_matrix

    from retarget.stylize import _catmull_rom

    rng = np.random.default_rng(6)
    for frames_n in (1, 2, 5, 40):
        frames = rng.normal(size=(frames_n, 4, 7))
        f = np.concatenate([rng.uniform(-1.0, frames_n + 1.0, 50), np.arange(frames_n, dtype=float)])
        last = frames_n - 1
        fc = np.clip(f, 0.0, last)
        k = np.minimum(np.floor(fc).astype(int), max(last - 1, 0))
        u = fc - k
        weights = np.stack([0.5 * (-u + 2 * u**2 - u**3), 0.5 * (2 - 5 * u**2 + 3 * u**3),
                            0.5 * (u + 4 * u**2 - 3 * u**3), 0.5 * (u**3 - u**2)], axis=1)
        cols = np.clip(k[:, None] + np.arange(-1, 3)[None], 0, last)
        w = csr_matrix((weights.ravel(), (np.repeat(np.arange(len(f)), 4), cols.ravel())), shape=(len(f), frames_n))
        theirs = (w @ frames.reshape(frames_n, -1)).reshape((len(f),) + frames.shape[1:])
        assert _close(_catmull_rom(frames, f), theirs)
