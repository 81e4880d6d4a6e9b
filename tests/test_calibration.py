"""Calibration: the figurine's forward (device mount) and the thresholds θ and ε."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from doodle.input.calibration import calibrate
from doodle.input.devices import apply_mount, calibrate_mount
from doodle.core.errors import DoodleError
from doodle.input.segmenter import SegmenterParams, tokenize
from doodle.input.settings import read_calibration, write_calibration
from doodle.synth.strokes import stroke, synth_track


def test_mount_found_from_still_then_push():
    """A controller strapped to the figurine on its side (rolled 90°, yawed 30°): after
    calibration a forward push reads T_Z and a lift T_Y, as for a prop held upright."""
    mount_true = Rotation.from_euler("zy", [90, 30], degrees=True)  # device-to-figurine
    device_of = tuple(mount_true.inv().as_quat())  # q_dev = q_fig ⊗ mount⁻¹
    calib = synth_track([stroke("T_STILL", 0.6), stroke("T_Z", 0.5, 0.1), stroke("T_STILL", 0.3)], seed=1)[0]
    mount = calibrate_mount(apply_mount(calib, device_of))
    np.testing.assert_allclose(abs(np.dot(mount, mount_true.as_quat())), 1.0, atol=1e-3)
    take = synth_track([stroke("T_STILL", 0.4), stroke("T_Z", 0.5), stroke("T_STILL", 0.3), stroke("T_Y", 0.5),
                        stroke("T_STILL", 0.3)], seed=2)[0]
    raw = apply_mount(take, device_of)
    expected = ["T_STILL", "T_Z", "T_STILL", "T_Y", "T_STILL"]
    assert [k.name for k in tokenize(raw, 90.0)] != expected
    assert [k.name for k in tokenize(apply_mount(raw, mount), 90.0)] == expected


def test_mount_needs_a_push():
    still = synth_track([stroke("T_STILL", 1.0)], seed=3)[0]
    with pytest.raises(DoodleError, match="push the prop forward"):
        calibrate_mount(still)


def test_thresholds_from_minimal_gestures():
    """θ from a minimal translation and a minimal rotation, ε under the slowest motion: the
    slow gesture is then motion, not stillness, and stillness stays still."""
    translation = synth_track([stroke("T_STILL", 0.3), stroke("T_Z", 1.0, 0.05), stroke("T_STILL", 0.3)], seed=4)[0]
    rotation = synth_track([stroke("T_STILL", 0.3), stroke("R_Y", 1.0, 0.6), stroke("T_STILL", 0.3)], seed=5)[0]
    slow = synth_track([stroke("T_STILL", 0.3), stroke("T_X", 2.0, 0.04), stroke("T_STILL", 0.3)], seed=6)[0]
    params = calibrate(translation, rotation, slow, 90.0)
    # the moving parts of min-jerk strokes: v ~ 0.05 m/s, ω ~ 0.6 rad/s → θ ~ 0.08 m/rad
    assert 0.04 < params.theta < 0.15
    assert 0.002 < params.eps < 0.02
    assert [k.name for k in tokenize(slow, 90.0, params)] == ["T_STILL", "T_X", "T_STILL"]
    # with the defaults (ε = 0.05 m/s) this slow motion is lost in stillness
    assert "T_X" not in [k.name for k in tokenize(slow, 90.0)]


def test_calibration_file_round_trip_and_errors(tmp_path):
    path = tmp_path / "cal.toml"
    write_calibration(path, SegmenterParams(eps=0.02, theta=0.1), {"c0": (0.0, 0.0, 0.7071068, 0.7071068)})
    params, mounts = read_calibration(path)
    assert params.eps == pytest.approx(0.02) and params.theta == pytest.approx(0.1)
    assert mounts["c0"] == pytest.approx((0, 0, 0.7071068, 0.7071068))
    path.write_text("[segmenter]\nepsilon = 3\n")
    with pytest.raises(DoodleError, match=r"cal.toml: segmenter.epsilon"):
        read_calibration(path)
    path.write_text("[mount]\nc0 = [0, 0, 0]\n")
    with pytest.raises(DoodleError, match=r"cal.toml: mount.c0"):
        read_calibration(path)
    path.write_text("[segmenter\n")
    with pytest.raises(DoodleError, match="not valid TOML"):
        read_calibration(path)
