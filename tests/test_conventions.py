import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.spatial.transform import Rotation

from doodle.input.conventions import CONVENTIONS, convention_matrix, from_ours, to_ours
from doodle.core.errors import DoodleError

NAMES = sorted(CONVENTIONS)


def _world_dir(q, local):
    """World direction of a body-frame vector for a world-from-body quaternion."""
    return Rotation.from_quat(q).apply(local)


@pytest.mark.parametrize("name", NAMES)
def test_quaternion_rule_matches_matrix_form(name):
    C = convention_matrix(name)
    rot = Rotation.random(50, random_state=1)
    p = np.random.default_rng(2).normal(size=(50, 3))
    p2, q2 = to_ours(p, rot.as_quat(), name)
    np.testing.assert_allclose(p2, p @ C.T, atol=1e-12)
    expected = C @ rot.as_matrix() @ C.T
    np.testing.assert_allclose(Rotation.from_quat(q2).as_matrix(), expected, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(q2, axis=1), 1.0, atol=1e-12)


def test_unity_quaternion_formula():
    q = np.array([0.1, 0.2, 0.3, 0.9])
    q = q / np.linalg.norm(q)
    _, q2 = to_ours(np.zeros(3), q, "unity")
    np.testing.assert_allclose(q2, [q[0], -q[1], -q[2], q[3]])


def test_determinants():
    assert np.linalg.det(CONVENTIONS["doodle"]) == pytest.approx(1)
    assert np.linalg.det(CONVENTIONS["unity"]) == pytest.approx(-1)
    assert np.linalg.det(CONVENTIONS["openvr"]) == pytest.approx(1)


def test_unity_motion_and_controller_axes():
    identity = np.array([0.0, 0.0, 0.0, 1.0])
    # moving +z (forward), -x (left), +y (up) in Unity
    p_unity = np.array([[0, 0, 0], [0, 0, 1], [-1, 0, 0], [0, 1, 0]], dtype=float)
    p, q = to_ours(p_unity, np.tile(identity, (4, 1)), "unity")
    d = p[1:] - p[0]
    np.testing.assert_allclose(d[0], [0, 0, 1])  # forward -> +z
    np.testing.assert_allclose(d[1], [1, 0, 0])  # left -> +x (ours is +x left)
    np.testing.assert_allclose(d[2], [0, 1, 0])  # up -> +y
    C = CONVENTIONS["unity"]
    # the controller's own axes, expressed in our body frame, then to our world
    np.testing.assert_allclose(_world_dir(q[0], C @ [0, 0, 1]), [0, 0, 1], atol=1e-12)  # local forward
    np.testing.assert_allclose(_world_dir(q[0], C @ [1, 0, 0]), [-1, 0, 0], atol=1e-12)  # local right
    # a controller yawed so that it points to the performer's right in Unity (+x there)
    yaw = np.array([0.0, np.sin(np.pi / 4), 0.0, np.cos(np.pi / 4)])
    np.testing.assert_allclose(_world_dir(yaw, [0, 0, 1]), [1, 0, 0], atol=1e-12)  # Unity: +z -> +x
    _, qy = to_ours(np.zeros(3), yaw, "unity")
    np.testing.assert_allclose(_world_dir(qy, C @ [0, 0, 1]), [-1, 0, 0], atol=1e-12)  # ours: right is -x


def test_openvr_motion_and_controller_axes():
    identity = np.array([0.0, 0.0, 0.0, 1.0])
    # moving -z (forward in OpenVR), -x (left), +y (up)
    p_vr = np.array([[0, 0, 0], [0, 0, -1], [-1, 0, 0], [0, 1, 0]], dtype=float)
    p, q = to_ours(p_vr, np.tile(identity, (4, 1)), "openvr")
    d = p[1:] - p[0]
    np.testing.assert_allclose(d[0], [0, 0, 1])
    np.testing.assert_allclose(d[1], [1, 0, 0])
    np.testing.assert_allclose(d[2], [0, 1, 0])
    C = CONVENTIONS["openvr"]
    # an OpenVR controller points along its local -z; its right is local +x
    np.testing.assert_allclose(_world_dir(q[0], C @ [0, 0, -1]), [0, 0, 1], atol=1e-12)
    np.testing.assert_allclose(_world_dir(q[0], C @ [1, 0, 0]), [-1, 0, 0], atol=1e-12)
    # pitched up by 90 degrees in OpenVR (rotation about +x turns -z toward +y)
    pitch = Rotation.from_euler("x", 90, degrees=True).as_quat()
    np.testing.assert_allclose(_world_dir(pitch, [0, 0, -1]), [0, 1, 0], atol=1e-12)
    _, qp = to_ours(np.zeros(3), pitch, "openvr")
    np.testing.assert_allclose(_world_dir(qp, C @ [0, 0, -1]), [0, 1, 0], atol=1e-12)


def test_nan_rows_pass_through():
    p = np.array([[np.nan, np.nan, np.nan], [1.0, 2.0, 3.0], [np.nan, 1.0, 2.0]])
    q = np.array([[np.nan] * 4, [0, 0, 0, 1.0], [np.nan] * 4])
    for name in NAMES:
        p2, q2 = to_ours(p, q, name)
        assert np.isnan(p2[0]).all() and np.isnan(q2[0]).all() and np.isnan(q2[2]).all()
        assert np.isfinite(p2[1]).all() and np.isfinite(q2[1]).all()
        # a NaN in one component does not spread into the others
        assert np.isnan(p2[2, 0]) and np.isfinite(p2[2, 1:]).all()


def test_unknown_convention_lists_known():
    with pytest.raises(DoodleError) as err:
        to_ours(np.zeros(3), [0, 0, 0, 1], "maya")
    for name in NAMES:
        assert name in str(err.value)
    with pytest.raises(DoodleError):
        from_ours(np.zeros(3), [0, 0, 0, 1], "maya")


def test_bad_shapes():
    with pytest.raises(DoodleError):
        to_ours(np.zeros(2), [0, 0, 0, 1], "unity")
    with pytest.raises(DoodleError):
        to_ours(np.zeros(3), [0, 0, 1], "unity")


finite = st.floats(-1e3, 1e3, allow_nan=False, allow_infinity=False)
quat_raw = st.tuples(finite, finite, finite, finite).filter(lambda v: np.linalg.norm(v) > 1e-3)


@settings(max_examples=200, deadline=None)
@given(st.sampled_from(NAMES), st.tuples(finite, finite, finite), quat_raw)
def test_round_trip_is_identity(name, p, q):
    q = np.asarray(q) / np.linalg.norm(q)
    p = np.asarray(p)
    p2, q2 = to_ours(*from_ours(p, q, name), name)
    np.testing.assert_allclose(p2, p, atol=1e-12)
    np.testing.assert_allclose(q2, q, atol=1e-12)
    p3, q3 = from_ours(*to_ours(p, q, name), name)
    np.testing.assert_allclose(p3, p, atol=1e-12)
    np.testing.assert_allclose(q3, q, atol=1e-12)
    assert np.linalg.norm(q3) == pytest.approx(1.0)
