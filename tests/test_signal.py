"""The signal layer: smoothing, quaternion helpers, local velocities in the moving frame."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from doodle.core import quat
from doodle.input.frame import local_velocities, local_velocity
from doodle.input.smoothing import StreamingSmoother, laplacian_kernel, savgol_kernel, smooth


def umbrella(x, k, lam=0.5):
    """k explicit Laplacian iterations (interior only) — the thesis's smoothing."""
    y = x.copy()
    for _ in range(k):
        y[1:-1] = y[1:-1] + lam * (0.5 * (y[:-2] + y[2:]) - y[1:-1])
    return y


def test_laplacian_kernel_is_iterated_umbrella_in_the_interior():
    rng = np.random.default_rng(0)
    x = rng.normal(size=(200, 3))
    kernel = laplacian_kernel(0.03, 90.0)
    k = len(kernel) // 2
    assert k == round((0.03 * 90) ** 2 / 0.5)
    assert kernel.sum() == pytest.approx(1.0)
    np.testing.assert_allclose(smooth(x, kernel)[k:-k], umbrella(x, k)[k:-k], atol=1e-12)


def test_kernel_length_follows_the_rate():
    assert len(laplacian_kernel(0.03, 144.0)) > len(laplacian_kernel(0.03, 90.0))
    # same temporal spread in seconds: variance in samples² scales with rate²
    for rate in (60.0, 90.0, 144.0):
        kern = laplacian_kernel(0.03, rate)
        j = np.arange(len(kern)) - len(kern) // 2
        assert np.sqrt((kern * j**2).sum()) / rate == pytest.approx(0.03, rel=0.1)


@pytest.mark.parametrize("kernel", [laplacian_kernel(0.03, 90.0), savgol_kernel(0.1, 90.0)])
def test_linear_motion_survives_the_ends(kernel):
    """Odd reflection keeps a straight, constant-speed motion untouched up to the ends."""
    t = np.linspace(0, 1, 91)
    x = np.column_stack([2 * t, -t, 0.5 + 0 * t])
    np.testing.assert_allclose(smooth(x, kernel), x, atol=1e-12)


def test_smoothing_removes_tremor():
    t = np.arange(270) / 90.0
    tremor = 0.001 * np.sin(2 * np.pi * 10 * t)
    out = smooth(tremor[:, None], laplacian_kernel(0.03, 90.0))[:, 0]
    assert np.abs(out[20:-20]).max() < 0.25 * 0.001


@settings(max_examples=40, deadline=None)
@given(n=st.integers(1, 80), seed=st.integers(0, 10_000), savgol=st.booleans())
def test_streaming_smoother_is_bit_identical(n, seed, savgol):
    kernel = savgol_kernel(0.1, 90.0) if savgol else laplacian_kernel(0.03, 90.0)
    x = np.random.default_rng(seed).normal(size=(n, 8)) * 10
    s = StreamingSmoother(kernel, 8)
    rows = [y for r in x for y in s.push(tuple(r))] + s.close()
    assert np.array_equal(np.array(rows).reshape(n, 8), smooth(x, kernel))


def test_streaming_smoother_across_buffer_wraps():
    kernel = laplacian_kernel(0.03, 90.0)
    x = np.random.default_rng(1).normal(size=(9000, 8))
    s = StreamingSmoother(kernel, 8)
    rows = [y for r in x for y in s.push(tuple(r))] + s.close()
    assert np.array_equal(np.array(rows), smooth(x, kernel))


def test_hemisphere_signs_make_quaternions_continuous():
    q = Rotation.from_rotvec(np.outer(np.linspace(0, 6, 50), [0, 1, 0])).as_quat()
    flipped = q * np.where(np.arange(50) % 3 == 0, -1.0, 1.0)[:, None]
    cont = quat.make_continuous(flipped)
    assert (np.sum(cont[1:] * cont[:-1], axis=1) > 0).all()
    assert np.allclose(np.abs(np.sum(cont * q, axis=1)), 1.0)


def test_rotate_matches_scipy():
    rng = np.random.default_rng(2)
    q = Rotation.random(50, random_state=3).as_quat()
    u = rng.normal(size=(50, 3))
    np.testing.assert_allclose(quat.rotate(q, u), Rotation.from_quat(q).apply(u), atol=1e-12)
    np.testing.assert_allclose(quat.rotate_inverse(q, u), Rotation.from_quat(q).inv().apply(u), atol=1e-12)
    a, b = Rotation.random(2, random_state=4)
    ab = quat.multiply(a.as_quat()[None], b.as_quat()[None])[0]
    np.testing.assert_allclose(Rotation.from_quat(ab).as_matrix(), (a * b).as_matrix(), atol=1e-12)


def test_local_velocity_is_in_the_figurine_frame():
    """A figurine facing world +x (turned left by 90°) and moving along world +x moves
    forward (+z) in its own frame, at the world speed."""
    n = 20
    t = np.arange(n) / 90.0
    facing = Rotation.from_rotvec([0, np.pi / 2, 0])  # +z -> world +x
    q = np.tile(facing.as_quat(), (n, 1))
    p = np.column_stack([0.5 * t, 0 * t, 0 * t])
    v, w = local_velocities(t, p, q, 90.0)
    np.testing.assert_allclose(v, np.tile([0, 0, 0.5], (n - 1, 1)), atol=1e-12)
    np.testing.assert_allclose(w, 0, atol=1e-12)


def test_angular_velocity_from_quaternions_not_euler():
    """Turning left about the figurine's own up axis at 2 rad/s while pitched up: ω = +2 ŷ,
    even across the ±π wrap where Euler-angle differences jump."""
    n = 400
    t = np.arange(n) / 90.0
    pitch = Rotation.from_rotvec([-0.4, 0, 0])
    yaw = Rotation.from_rotvec(np.outer(2.0 * t, [0, 1, 0]))
    q = quat.make_continuous((pitch * yaw).as_quat())  # body-frame yaw after a pitch
    v, w = local_velocities(t, np.zeros((n, 3)), q, 90.0)
    np.testing.assert_allclose(w, np.tile([0, 2.0, 0], (n - 1, 1)), atol=1e-9)


def test_scalar_and_vector_velocity_are_bit_identical():
    rng = np.random.default_rng(5)
    n = 300
    t = np.cumsum(rng.uniform(0.005, 0.02, n))
    p = rng.normal(size=(n, 3))
    q = quat.make_continuous(Rotation.random(n, random_state=6).as_quat())
    v, w = local_velocities(t, p, q, 90.0)
    rows = np.column_stack([t, p, q]).tolist()
    scalar = np.array([local_velocity(rows[i - 1], rows[i], 90.0) for i in range(1, n)])
    assert np.array_equal(scalar, np.hstack([v, w]))
