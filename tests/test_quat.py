"""doodle.core.quat against scipy's Rotation and Slerp: the same rotations, angles and
interpolations to 1e-12, on many random rotations at once and on the edge cases (the
identity, half turns, gimbal lock in every Euler order, q and -q)."""

import itertools
import warnings

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation, Slerp

from doodle.core import quat

ORDERS = ["".join(p) for p in itertools.permutations("XYZ")]
TOL = 1e-12


def _random(n, seed=0):
    """n random quaternions (not unit: every function normalises, as scipy does)."""
    return np.random.default_rng(seed).normal(size=(n, 4)) * np.exp(np.random.default_rng(seed + 1).normal(size=(n, 1)))


def _locked(order):
    """Quaternions at gimbal lock in ``order``: the middle angle ±90° and within scipy's
    1e-7 rad window of it, first and last angles over the circle."""
    a, c = np.meshgrid([-180.0, -135.0, -30.0, 0.0, 45.0, 179.0, 180.0], [-180.0, -60.0, 0.0, 90.0, 180.0])
    middles = [90.0, -90.0, 90.0 - 1e-6, -90.0 + 1e-6]  # 1e-6° is 1.7e-8 rad: inside the window
    angles = np.concatenate([np.column_stack([a.ravel(), np.full(a.size, b), c.ravel()]) for b in middles])
    return Rotation.from_euler(order, angles, degrees=True).as_quat()


EDGES = np.concatenate([
    np.eye(4),  # half turns about x, y, z and the identity
    -np.eye(4),
    [[0.0, 0.0, 0.0, 1e-150], [np.sqrt(0.5), 0.0, 0.0, np.sqrt(0.5)], [0.0, -np.sqrt(0.5), np.sqrt(0.5), 0.0],
     [0.5, 0.5, 0.5, 0.5], [0.5, -0.5, 0.5, -0.5], [1e-17, 0.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1e-17]],
])


def _angle_between(p, q):
    """Angles (rad) between rotations p and q (..., 4)."""
    return Rotation.from_quat(p.reshape(-1, 4)).inv().__mul__(Rotation.from_quat(q.reshape(-1, 4))).magnitude()


def _same_rotation(p, q, tol=TOL):
    assert _angle_between(np.asarray(p), np.asarray(q)).max() <= tol


def _close(ours, theirs, tol=TOL):
    assert ours.shape == np.shape(theirs)
    assert np.max(np.abs(ours - theirs), initial=0.0) <= tol


def test_unit_normalises_as_scipy_does_and_refuses_a_zero_quaternion():
    q = np.concatenate([_random(1000), EDGES])
    assert np.array_equal(quat.unit(q), Rotation.from_quat(q).as_quat())
    assert quat.unit([0.0, 0.0, 0.0, 2.0]).tolist() == [0.0, 0.0, 0.0, 1.0]
    with pytest.raises(ValueError):
        quat.unit(np.zeros((3, 4)))


def test_compose_equals_scipys_products():
    p, q, r = _random(2000, 1), _random(2000, 2), _random(2000, 3)
    theirs = Rotation.from_quat(p) * Rotation.from_quat(q) * Rotation.from_quat(r)
    _close(quat.compose(p, q, r), theirs.as_quat())
    _close(quat.compose(p[0], q), (Rotation.from_quat(p[0]) * Rotation.from_quat(q)).as_quat())  # broadcast
    _close(quat.compose(EDGES, EDGES[::-1]), (Rotation.from_quat(EDGES) * Rotation.from_quat(EDGES[::-1])).as_quat())
    assert quat.compose(p[0], q[0]).shape == (4,)


def test_magnitude_and_rotation_vectors_equal_scipys():
    q = np.concatenate([_random(5000), EDGES, -EDGES])
    r = Rotation.from_quat(q)
    _close(quat.magnitude(q), r.magnitude())
    _close(quat.as_rotvec(q), r.as_rotvec())
    _close(quat.as_rotvec(-q), r.as_rotvec())  # q and -q: one rotation
    half_turns = np.array([[0.0, 0.0, -1.0, 0.0], [0.0, -1.0, 1.0, 0.0], [-1.0, 1.0, 0.0, 0.0]])  # w = 0: scipy's sign
    _close(quat.as_rotvec(half_turns), Rotation.from_quat(half_turns).as_rotvec())
    rng = np.random.default_rng(4)
    axes = rng.normal(size=(5000, 3))
    rv = axes / np.linalg.norm(axes, axis=1, keepdims=True) * np.logspace(-12, np.log10(3.1), 5000)[:, None]
    _close(quat.as_rotvec(quat.exp(rv)), rv)  # angles below π: back where they were
    rv = np.concatenate([rv, rv * 2.0, np.zeros((1, 3)), [[np.pi, 0.0, 0.0]]])
    _close(quat.exp(rv), Rotation.from_rotvec(rv).as_quat())


def test_matrices_equal_scipys_both_ways():
    q = np.concatenate([_random(5000), EDGES, -EDGES])
    m = Rotation.from_quat(q).as_matrix()
    assert np.array_equal(quat.as_matrix(q), m)  # the same arithmetic: to the bit
    _close(quat.from_matrix(m), Rotation.from_matrix(m).as_quat())
    bent = m + np.random.default_rng(5).normal(size=m.shape) * 1e-5  # not orthogonal: the nearest rotation
    _close(quat.from_matrix(bent), Rotation.from_matrix(bent).as_quat())
    _close(quat.from_matrix(m[7]), Rotation.from_matrix(m[7]).as_quat())
    assert quat.from_matrix(m.reshape(-1, 2, 3, 3)[:5]).shape == (5, 2, 4)
    with pytest.raises(ValueError):
        quat.from_matrix(np.diag([1.0, 1.0, -1.0]))


@pytest.mark.parametrize("order", ORDERS + ["X", "ZX", "YX", "ZXZ"])
def test_from_euler_gives_scipys_rotations(order):
    rng = np.random.default_rng(6)
    angles = np.concatenate([rng.uniform(-400.0, 400.0, (2000, len(order))),
                             np.array(list(itertools.product([0.0, 90.0, -90.0, 180.0], repeat=len(order))))])
    theirs = Rotation.from_euler(order, angles, degrees=True).as_quat()
    _same_rotation(quat.from_euler(order, angles, degrees=True), theirs)
    _same_rotation(quat.from_euler(order, np.radians(angles)), theirs)
    assert quat.from_euler(order, angles[0], degrees=True).shape == (4,)


@pytest.mark.parametrize("order", ORDERS)
def test_euler_angles_equal_scipys(order):
    q = np.concatenate([_random(20000), EDGES, -EDGES])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # scipy warns of the gimbal locks among the edges
        theirs = Rotation.from_quat(q).as_euler(order)
    ours = quat.as_euler(q, order)
    free = np.abs(theirs[:, 1]) < np.radians(89.0)  # away from gimbal lock: the angles themselves
    free[20000:] &= False
    assert free.sum() > 19000
    _close(ours[free], theirs[free])
    _close(quat.as_euler(-q, order)[free], theirs[free])  # q and -q
    _close(quat.as_euler(q, order, degrees=True)[free], np.degrees(theirs[free]), 1e-10)
    edges = np.abs(theirs[20000:, 1]) < np.radians(89.0)
    wrapped = ((ours - theirs + np.pi) % (2 * np.pi) - np.pi)[20000:][edges]  # ±180°: one angle, either sign
    _close(wrapped, np.zeros_like(wrapped))
    _same_rotation(quat.from_euler(order, ours), q)  # everywhere: the same rotations
    assert (np.abs(ours[:, [0, 2]]) <= np.pi).all() and (np.abs(ours[:, 1]) <= np.pi / 2).all()


@pytest.mark.parametrize("order", ORDERS)
def test_euler_angles_at_gimbal_lock_follow_scipys_branch(order):
    q = _locked(order)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        theirs = Rotation.from_quat(q).as_euler(order)
    ours = quat.as_euler(q, order)
    assert np.array_equal(ours[:, 2], theirs[:, 2]) and (ours[:, 2] == 0).all()  # the last angle set to zero
    _close(ours[:, 1], theirs[:, 1])
    _same_rotation(quat.from_euler(order, ours), Rotation.from_euler(order, theirs).as_quat())
    _same_rotation(quat.from_euler(order, ours)[np.abs(np.abs(ours[:, 1]) - np.pi / 2) < 1e-15],
                   q[np.abs(np.abs(ours[:, 1]) - np.pi / 2) < 1e-15])  # exactly ±90°: exact
    _same_rotation(quat.from_euler(order, quat.as_euler(-q, order)), quat.from_euler(order, ours))


def test_euler_orders_are_checked():
    for bad in ("ZXX", "zxy", "ZX", "ZXYZ", "ZXW"):
        with pytest.raises(ValueError):
            quat.as_euler(np.array([0.0, 0.0, 0.0, 1.0]), bad)
    with pytest.raises(ValueError):
        quat.from_euler("ZQ", [1.0, 2.0])
    with pytest.raises(ValueError):
        quat.as_euler(np.array([[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, 0.0, 0.0]]), "ZXY")  # a zero quaternion, as in scipy


def test_slerp_between_two_rotations_equals_scipys():
    a, b = _random(3000, 7), _random(3000, 8)
    w = np.random.default_rng(9).uniform(0.0, 1.0, 3000)
    w[:3] = [0.0, 1.0, 0.5]
    theirs = np.array([Slerp([0.0, 1.0], Rotation.from_quat([a[k], b[k]]))(w[k]).as_quat() for k in range(200)])
    _close(quat.slerp(a[:200], b[:200], w[:200]), theirs)
    # the shorter arc, whichever sign the keys have
    _close(quat.slerp(a[:200], -b[:200], w[:200]), theirs)
    one = Slerp([0.0, 1.0], Rotation.from_quat([a[0], b[0]]))(w).as_quat()
    _close(quat.slerp(a[0], b[0], w), one)
    half = Slerp([0.0, 1.0], Rotation.from_quat([[0.0, 0.0, 0.0, 1.0], [-1.0, 0.0, 0.0, 0.0]]))(w).as_quat()
    _close(quat.slerp([0.0, 0.0, 0.0, 1.0], [-1.0, 0.0, 0.0, 0.0], w), half)  # a half turn: scipy's way round


def test_slerp_between_keys_equals_scipys_for_many_sequences():
    rng = np.random.default_rng(10)
    times = np.cumsum(rng.uniform(0.01, 0.2, 60))
    keys = rng.normal(size=(60, 5, 4))
    keys[10, 2] = -keys[9, 2]  # a key and its negative: no turn
    new = np.concatenate([rng.uniform(times[0], times[-1], 400), times, [times[0], times[-1]]])
    ours = quat.slerp_keys(times, keys, new)
    assert ours.shape == (len(new), 5, 4)
    for j in range(5):
        _close(ours[:, j], Slerp(times, Rotation.from_quat(keys[:, j]))(new).as_quat())
    _close(quat.slerp_keys(times, keys[:, 0], new), ours[:, 0])
    for bad_times in ([times[0] - 1e-9], [times[-1] + 1.0]):
        with pytest.raises(ValueError):
            quat.slerp_keys(times, keys, bad_times)
    with pytest.raises(ValueError):
        quat.slerp_keys(times[::-1], keys, new)


def test_the_front_is_the_matrix_third_column():
    q = np.concatenate([_random(3000), EDGES])
    assert np.array_equal(quat.front(q), quat.as_matrix(q)[..., 2])


angles = st.floats(-720.0, 720.0, allow_nan=False)


@settings(max_examples=100, deadline=None)
@given(st.sampled_from(ORDERS), angles, angles, angles)
def test_euler_round_trip(order, a, b, c):
    """Angles → rotation → angles → the same rotation: to 1e-12 away from gimbal lock, to
    the 1e-7 rad of scipy's lock window near it."""
    q = quat.from_euler(order, [a, b, c], degrees=True)
    back = quat.from_euler(order, quat.as_euler(q, order, degrees=True), degrees=True)
    _same_rotation(back, q, TOL if abs(abs((b + 90.0) % 180.0 - 90.0) - 90.0) > 1.0 else 1e-7)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.floats(-1.0, 1.0, allow_nan=False), min_size=4, max_size=4).filter(
    lambda v: np.linalg.norm(v) > 1e-3))
def test_matrix_round_trip(v):
    q = quat.unit(np.array(v))
    back = quat.from_matrix(quat.as_matrix(q))
    assert min(np.abs(back - q).max(), np.abs(back + q).max()) <= TOL
