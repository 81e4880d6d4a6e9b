"""Start-up of ``doodle compile`` (bench/startup.py measures it): the numpy stand-ins for
scipy.signal give scipy's results; the command line and a compile import none of the heavy
libraries they no longer need."""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.signal import find_peaks as scipy_find_peaks
from scipy.signal import savgol_coeffs as scipy_savgol_coeffs

from doodle.core.peaks import find_peaks
from doodle.input.smoothing import savgol_coeffs, savgol_kernel

ROOT = Path(__file__).resolve().parents[1]
DEMO = ROOT / "examples" / "demo.doodle"
BUILTIN_CLIPS = ROOT / "library" / "builtin" / "clips"


# --- numpy stand-ins for scipy.signal ----------------------------------------------------------

@pytest.mark.parametrize("window", range(2, 64))
def test_savgol_coeffs_equal_scipys(window):
    for order in range(0, min(window, 7)):
        ours, theirs = savgol_coeffs(window, order), scipy_savgol_coeffs(window, order)
        assert ours.shape == theirs.shape
        assert np.max(np.abs(ours - theirs)) <= 1e-12


def test_savgol_kernels_of_the_segmenter_equal_scipys_bit_for_bit():
    for rate in (30.0, 60.0, 72.0, 90.0, 120.0, 144.0, 240.0):
        for window in (0.05, 0.1, 0.2):
            kernel = savgol_kernel(window, rate)
            assert np.array_equal(kernel, scipy_savgol_coeffs(len(kernel), 3))


def test_savgol_coeffs_refuse_an_order_as_long_as_the_window():
    with pytest.raises(ValueError):
        savgol_coeffs(3, 3)


def _same_peaks(x, **options):
    ours, props = find_peaks(x, **options)
    theirs, their_props = scipy_find_peaks(x, **options)
    assert np.array_equal(ours, theirs) and ours.dtype == theirs.dtype, options
    assert props.keys() == their_props.keys(), options
    for key in props:
        assert np.array_equal(props[key], their_props[key]) and props[key].dtype == their_props[key].dtype, (key, options)
    return ours


def _options(x, rng):
    """The option sets the program uses (retarget.analysis, laban.features) and a few more."""
    span = float(np.ptp(x)) if len(x) else 1.0
    low = float(np.min(x)) if len(x) else 0.0
    return [{}, {"plateau_size": 1}, {"prominence": 0.0, "plateau_size": 1},
            {"height": -(low + 0.3 * span), "prominence": 0.2 * span, "plateau_size": 1},
            {"height": low + 0.5 * span, "prominence": span / 3, "distance": int(rng.integers(1, 12))},
            {"height": 0.05 * span, "prominence": 0.3 * 0.05 * span}, {"distance": 2.5},
            {"prominence": (0.1 * span, 0.8 * span)}, {"height": (None, low + 0.7 * span)},
            {"plateau_size": (2, 4)}, {"height": rng.normal(size=len(x))}]


def test_find_peaks_equals_scipys_on_random_signals_with_plateaus():
    rng = np.random.default_rng(1)
    for _ in range(1500):
        n = int(rng.integers(0, 80))
        x = np.round(rng.normal(size=n), int(rng.integers(0, 3)))  # coarse rounding: flat runs and ties
        for options in _options(x, rng):
            _same_peaks(x, **options)


def test_find_peaks_equals_scipys_on_real_speeds():
    from doodle.input.loader import load
    from laban.features import _norm, effort_signal
    from retarget.analysis import body_speed
    from retarget.bvh import read_bvh
    from retarget.skeleton import forward_kinematics

    rng = np.random.default_rng(2)
    signals = []
    for path in sorted(BUILTIN_CLIPS.glob("*.bvh")):  # body speed: stages and repetitions of clips
        motion = read_bvh(path)
        speed, _ = body_speed(motion, forward_kinematics(motion)[0])
        signals += [speed, -speed]
    track = load(DEMO).tracks[0]  # the hand's speed over stretches of the demo: strokes (laban.features)
    for start in range(0, len(track.t) - 60, 45):
        _, v, _, _, _ = effort_signal(track.t[start:start + 90], track.p[start:start + 90])
        speed = _norm(v)
        signals.append(np.concatenate([[0.0], speed, [0.0]]))
    found = 0
    for x in signals:
        for options in _options(x, rng):
            found += len(_same_peaks(x, **options))
    assert found > 1000


def test_find_peaks_checks_its_input_like_scipy():
    with pytest.raises(ValueError):
        find_peaks(np.zeros((3, 3)))
    with pytest.raises(ValueError):
        find_peaks(np.arange(5.0), distance=0.5)
    with pytest.raises(ValueError):
        find_peaks(np.arange(5.0), height=np.zeros(4))


# --- what is imported ---------------------------------------------------------------------------

HEAVY = ("pandas", "sklearn", "scipy.signal", "scipy.stats", "matplotlib", "trimesh", "hmmlearn.hmm")


def _imported(code: str, tmp_path) -> set:
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")]),
               DOODLE_CACHE=str(tmp_path / "cache"))
    out = subprocess.run([sys.executable, "-c", code + "\nimport sys; print(' '.join(sorted(sys.modules)))"],
                         cwd=ROOT, env=env, capture_output=True, text=True, check=True).stdout
    return set(out.splitlines()[-1].split())


def test_the_command_line_parser_imports_no_numerical_library(tmp_path):
    mods = _imported("from doodle.app.cli.main import build_parser; build_parser()", tmp_path)
    assert not {m for m in mods if m.split(".")[0] in ("numpy", "scipy", "pandas", "sklearn", "lark")}


def test_a_compile_imports_no_library_it_does_not_use(tmp_path):
    code = (f"from doodle.app.cli.main import main; main(['compile', {str(DEMO)!r}, '-o', {str(tmp_path / 'out')!r}])\n"
            f"main(['compile', {str(DEMO)!r}, '-o', {str(tmp_path / 'out')!r}])")
    mods = _imported(code, tmp_path)
    assert not {m for m in mods if m in HEAVY or m.split(".")[0] in ("pandas", "sklearn", "matplotlib")}
