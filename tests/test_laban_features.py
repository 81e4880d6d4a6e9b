"""Laban kinematic features (thesis §4.3) and relevance-factor selection (eq. 4.13–4.17)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.signal import savgol_filter

from doodle.core import quat
from laban import features as F
from laban.features import FEATURE_SETS, SUMMARY_NAMES, kinematics, sequence, summary
from laban.selection import normalise, ranking, relevance

RATE = 90.0
INNER = slice(15, -15)  # away from the ends, where the end fits are less accurate
IDENTITY = np.array([0.0, 0.0, 0.0, 1.0])


def still_q(n):
    return np.tile(IDENTITY, (n, 1))


def helix(a=0.2, b=0.1, w=5.0, T=3.0, scale=1.0):
    t = np.arange(0.0, T, 1.0 / RATE)
    s = w * t
    p = scale * np.column_stack([a * np.cos(s), a * np.sin(s), b * s])
    return t, p, still_q(len(t))


def smooth_motion(seed, T=2.0, jitter=0.0):
    """A generic smooth hand motion: sums of sinusoids in position and rotation vector,
    sampled at 90 Hz with timestamps jittered by up to ``jitter`` seconds."""
    rng = np.random.default_rng(seed)
    f = rng.uniform(0.3, 1.5, (3, 3))
    ph = rng.uniform(0, 2 * np.pi, (3, 3))
    amp = rng.uniform(0.05, 0.3, (3, 3))
    ang = rng.uniform(0.2, 1.0, (3, 3))
    t = np.arange(0.0, T, 1.0 / RATE)
    t = t + np.random.default_rng(seed + 1).uniform(-jitter, jitter, len(t))
    arg = 2 * np.pi * f[None] * t[:, None, None] + ph[None]
    p = (amp[None] * np.sin(arg)).sum(axis=1)
    rv = (ang[None] * np.sin(0.7 * arg)).sum(axis=1)
    return t, p, quat.exp(rv)


def as_dict(k):
    return {name: getattr(k, name) for name in k.__dataclass_fields__}


# --- the smoothing differentiator ------------------------------------------------------------


@pytest.mark.parametrize("m", [5, 6, 9, 11, 40])
def test_derivatives_equal_scipy_savgol_interp(m):
    x = np.random.default_rng(m).normal(size=(m, 4))
    w = min(11, m - 1 + m % 2)
    out = F._derivatives(x, 1.0 / RATE, 4)
    for d in range(4):
        ref = savgol_filter(x, w, 3, deriv=d, delta=1.0 / RATE, mode="interp", axis=0)
        np.testing.assert_allclose(out[d], ref, rtol=1e-9, atol=1e-9 * np.abs(ref).max())


# --- geometry on known curves ----------------------------------------------------------------


def test_circle_curvature_torsion_and_moving_frame():
    r, v = 0.15, 1.0
    t = np.arange(0.0, 2.0, 1.0 / RATE)
    th = v / r * t
    p = np.column_stack([r * np.cos(th), np.full_like(th, 1.2), r * np.sin(th)])
    q = np.column_stack([np.zeros_like(th), np.sin(-th / 2), np.zeros_like(th), np.cos(-th / 2)])  # front = tangent
    k = kinematics(t, p, q)
    np.testing.assert_allclose(k.curvature[INNER], 1 / r, rtol=2e-2)
    assert np.abs(k.torsion[INNER]).max() < 1e-6
    # 3-D equi-affine speed of a planar curve is 0, up to the 1/6 power of rounding noise
    assert np.abs(k.affine_speed).max() < 0.05
    np.testing.assert_allclose(k.speed[INNER], v, rtol=1e-3)
    np.testing.assert_allclose(k.jerk[INNER], r * (v / r) ** 3, rtol=2e-2)
    np.testing.assert_allclose(k.ang_speed[INNER], v / r, rtol=1e-3)
    # the figurine faces its way: all velocity is "front", and constant in the moving frame
    np.testing.assert_allclose(k.local_v[INNER], np.tile([0.0, 0.0, v], (len(t) - 30, 1)), atol=2e-3)
    assert np.abs(k.local_a[INNER]).max() < 0.05


def test_helix_curvature_torsion_and_affine_speed():
    a, b, w = 0.2, 0.1, 5.0
    k = kinematics(*helix(a, b, w))
    np.testing.assert_allclose(k.curvature[INNER], a / (a * a + b * b), rtol=2e-2)
    np.testing.assert_allclose(k.torsion[INNER], b / (a * a + b * b), rtol=2e-2)
    np.testing.assert_allclose(k.affine_speed[INNER], (a * a * b) ** (1 / 6) * w, rtol=1e-2)
    assert np.abs(k.affine_accel[INNER]).max() < 0.05  # constant V_a
    # a left-handed helix has negative torsion
    t, p, q = helix(a, b, w)
    assert np.all(kinematics(t, p * [1, 1, -1], q).torsion[INNER] < 0)


@pytest.mark.parametrize("accelerating", [False, True])
def test_straight_line_has_no_curvature(accelerating):
    t = np.arange(0.0, 1.5, 1.0 / RATE)
    s = 0.5 * t + (2.0 * t * t if accelerating else 0.0)
    p = np.array([0.1, 1.0, -0.2]) + s[:, None] * np.array([0.6, 0.0, 0.8])
    k = kinematics(t, p, still_q(len(t)))
    assert np.abs(k.curvature).max() < 1e-6 and np.abs(k.torsion).max() < 1e-6
    assert np.abs(k.affine_speed).max() < 1e-2


def test_line_extras_path_straightness_amplitude_peak_time():
    T, L = 1.0, 0.4
    t = np.arange(0.0, T + 1e-9, 1.0 / RATE)
    u = t / T
    s = L * (10 * u**3 - 15 * u**4 + 6 * u**5)  # minimum-jerk profile, peak speed at T/2
    p = s[:, None] * np.array([0.0, 0.6, 0.8])
    f = dict(zip(SUMMARY_NAMES, summary(t, p, still_q(len(t)))))
    assert f["Duration"] == pytest.approx(T)
    assert f["Path Length"] == pytest.approx(L, rel=1e-2)
    assert f["Straightness"] == pytest.approx(1.0, rel=1e-2)
    assert f["Amplitude"] == pytest.approx(L, rel=1e-2)
    assert f["Peak Speed"] == pytest.approx(1.875 * L / T, rel=1e-2)
    assert f["Peak Speed Time"] == pytest.approx(0.5, abs=0.02)
    assert f["Curvature Mean"] < 1e-6


def test_half_circle_straightness():
    th = np.linspace(0, np.pi, 100)
    p = 0.2 * np.column_stack([np.cos(th), np.sin(th), np.zeros_like(th)])
    f = dict(zip(SUMMARY_NAMES, summary(np.linspace(0, 1, 100), p, still_q(100))))
    assert f["Straightness"] == pytest.approx(2 / np.pi, rel=1e-2)
    assert f["Path Length"] == pytest.approx(0.2 * np.pi, rel=1e-2)


def test_curvature_summary_is_speed_weighted():
    """A noisy still tail must not dominate the curvature of a straight stroke."""
    rng = np.random.default_rng(3)
    t = np.arange(0.0, 2.0, 1.0 / RATE)
    s = np.minimum(t, 1.0) * 0.5
    p = s[:, None] * np.array([1.0, 0.0, 0.0]) + rng.normal(0, 1e-4, (len(t), 3)) * (t > 1.0)[:, None]
    q = still_q(len(t))
    k = kinematics(t, p, q)
    unweighted = np.log1p(k.curvature).mean()
    f = dict(zip(SUMMARY_NAMES, summary(t, p, q)))
    assert unweighted > 0.3
    assert f["Curvature Mean"] < 0.2 * unweighted


def test_angular_derivatives_are_world_frame():
    """Spin ω0 about the figurine's x while the figurine turns Ω about world y: the world
    angular velocity Ω ŷ + R ω0 x̂ has |ω̇| = Ω ω0 and |ω̈| = Ω² ω0 (in figurine axes |ω̈| would
    be Ω ω0²)."""
    big, small = 4.0, 1.0  # ω0, Ω
    t = np.arange(0.0, 2.0, 1.0 / RATE)
    n = len(t)
    turn = quat.exp(np.column_stack([np.zeros(n), small * t, np.zeros(n)]))
    spin = quat.exp(np.column_stack([big * t, np.zeros(n), np.zeros(n)]))
    k = kinematics(t, np.zeros((n, 3)), quat.multiply(turn, spin))
    np.testing.assert_allclose(k.ang_speed[INNER], np.hypot(big, small), rtol=1e-3)
    np.testing.assert_allclose(k.ang_accel[INNER], small * big, rtol=1e-2)
    np.testing.assert_allclose(k.ang_jerk[INNER], small**2 * big, rtol=5e-2)


def test_rate_independence():
    """The same motion sampled at 90 Hz and 144 Hz, or resampled at another rate, gives the
    same features (the differentiator's window is set in seconds)."""
    a, b, w = 0.2, 0.1, 5.0
    k90 = kinematics(*helix(a, b, w))
    t = np.arange(0.0, 3.0, 1.0 / 144.0)
    p = np.column_stack([a * np.cos(w * t), a * np.sin(w * t), b * w * t])
    k144 = kinematics(t, p, still_q(len(t)))
    k180 = kinematics(*helix(a, b, w), rate=180.0)
    assert len(k180.t) == round(k90.t[-1] * 180.0) + 1
    for k in (k144, k180):
        for name in ("speed", "accel", "jerk", "curvature", "torsion", "affine_speed"):
            np.testing.assert_allclose(
                np.median(getattr(k, name)), np.median(getattr(k90, name)), rtol=2e-2, err_msg=name
            )


# --- invariances -----------------------------------------------------------------------------

seeds = st.integers(0, 10_000)
unit_quats = (
    st.tuples(*[st.floats(-1, 1) for _ in range(4)])
    .map(np.array)
    .filter(lambda v: np.linalg.norm(v) > 0.1)
    .map(lambda v: v / np.linalg.norm(v))
)


@settings(max_examples=25, deadline=None)
@given(seeds, st.tuples(*[st.floats(-5, 5) for _ in range(3)]))
def test_translation_leaves_every_summary_feature_unchanged(seed, c):
    t, p, q = smooth_motion(seed)
    np.testing.assert_allclose(summary(t, p + np.array(c), q), summary(t, p, q), rtol=1e-6, atol=1e-6)


@settings(max_examples=25, deadline=None)
@given(seeds, unit_quats)
def test_world_rotation_leaves_invariant_features_unchanged(seed, g):
    t, p, q = smooth_motion(seed)
    G = np.tile(g, (len(t), 1))
    k0 = as_dict(kinematics(t, p, q))
    k1 = as_dict(kinematics(t, quat.rotate(G, p), quat.multiply(G, q)))
    for name, x in k0.items():  # every per-sample feature: norms, κ, τ, V_a, A_a, moving frame
        np.testing.assert_allclose(k1[name], x, rtol=1e-6, atol=1e-7 * (1 + np.abs(x).max()), err_msg=name)
    s0, s1 = summary(t, p, q), summary(t, quat.rotate(G, p), quat.multiply(G, q))
    np.testing.assert_allclose(s1, s0, rtol=1e-6, atol=1e-6)


@settings(max_examples=20, deadline=None)
@given(st.floats(0.5, 3.0))
def test_spatial_scale(s):
    k0, k1 = kinematics(*helix()), kinematics(*helix(scale=s))
    np.testing.assert_allclose(k1.speed, s * k0.speed, rtol=1e-9)
    np.testing.assert_allclose(k1.jerk, s * k0.jerk, rtol=1e-9)
    np.testing.assert_allclose(k1.local_v, s * k0.local_v, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(k1.affine_speed, np.sqrt(s) * k0.affine_speed, rtol=1e-9)
    np.testing.assert_allclose(s * k1.curvature[INNER], k0.curvature[INNER], rtol=2e-2)
    np.testing.assert_allclose(s * k1.torsion[INNER], k0.torsion[INNER], rtol=1e-2)


@settings(max_examples=20, deadline=None)
@given(st.floats(0.5, 2.0))
def test_time_scaling_divides_speeds(kf):
    # a cubic path (exact under cubic Savitzky–Golay fits of any window) and a steady spin
    t = np.arange(0.0, 1.5, 1.0 / RATE)
    p = np.column_stack([0.3 * t, 0.2 * t**2 - 0.1 * t, 0.1 * t**3 + 0.05 * t**2])
    ang = 2.0 * t
    q = np.column_stack([np.zeros_like(t), np.sin(ang / 2), np.zeros_like(t), np.cos(ang / 2)])
    k0, k1 = kinematics(t, p, q), kinematics(kf * t, p, q)
    np.testing.assert_allclose(k1.t, kf * k0.t, rtol=1e-12)
    np.testing.assert_allclose(k1.speed, k0.speed / kf, rtol=1e-6)
    np.testing.assert_allclose(k1.accel, k0.accel / kf**2, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(k1.jerk, k0.jerk / kf**3, rtol=1e-6)
    np.testing.assert_allclose(k1.ang_speed, k0.ang_speed / kf, rtol=1e-6)
    np.testing.assert_allclose(k1.local_v, k0.local_v / kf, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(k1.affine_speed, k0.affine_speed / kf, rtol=1e-4)
    assert summary(kf * t, p, q)[SUMMARY_NAMES.index("Duration")] == pytest.approx(kf * t[-1])


# --- robustness and shapes -------------------------------------------------------------------


def test_names_match_summary():
    assert len(SUMMARY_NAMES) == len(set(SUMMARY_NAMES)) == len(summary(*helix())) == 50
    table_4_2 = (
        "Torsion Mean", "Acceleration Mean", "Speed Mean", "Equi-Affine Speed Stdev", "Local Accel Up Mean",
        "Local Jerk Up Mean", "Acceleration Stdev", "Local Speed Up Mean", "Local Accel Up Stdev",
        "Local Speed Up Stdev", "Local Jerk Up Stdev", "Equi-Affine Speed Mean", "Equi-Affine Accel Mean",
    )
    assert set(table_4_2) <= set(SUMMARY_NAMES)


def segments():
    rng = np.random.default_rng(7)
    q = quat.normalise(rng.normal(size=(1, 4)))
    yield "still", np.arange(270) / RATE, np.tile([0.1, 1.2, 0.3], (270, 1)), np.tile(q, (270, 1))
    yield "noisy still", np.arange(270) / RATE, 1e-4 * rng.normal(size=(270, 3)), np.tile(q, (270, 1))
    for n in (1, 2, 3, 4):
        q = quat.normalise(rng.normal(size=(n, 4)))
        yield f"{n} samples", np.arange(n) / RATE, rng.normal(size=(n, 3)) * 0.05, q
    yield "jittered", *smooth_motion(5, jitter=4e-3)


@pytest.mark.parametrize("name,t,p,q", list(segments()), ids=lambda x: x if isinstance(x, str) else "")
def test_degenerate_segments_give_finite_features(name, t, p, q):
    s = summary(t, p, q)
    assert s.shape == (len(SUMMARY_NAMES),) and np.all(np.isfinite(s)), name
    x = sequence(t, p, q, points=64)
    assert x.shape == (64, 19) and np.all(np.isfinite(x)), name
    k = kinematics(t, p, q)
    assert all(np.all(np.isfinite(v)) for v in as_dict(k).values()), name


def test_still_segment_is_zero():
    k = kinematics(np.arange(100) / RATE, np.tile([0.1, 1.2, 0.3], (100, 1)), still_q(100))
    for name in ("speed", "jerk", "ang_speed", "curvature", "torsion", "affine_speed"):
        assert np.abs(getattr(k, name)).max() < 1e-9, name


def test_jittered_timestamps_give_the_same_features():
    k0 = kinematics(*smooth_motion(11))
    k1 = kinematics(*smooth_motion(11, jitter=4e-3))  # the same motion at jittered times
    mid = slice(30, -30)
    for name in ("speed", "accel", "ang_speed", "local_v"):
        x1 = getattr(k1, name).reshape(len(k1.t), -1)
        a = getattr(k0, name).reshape(len(k0.t), -1)[mid]
        b = np.column_stack([np.interp(k0.t, k1.t, c) for c in x1.T])[mid]
        np.testing.assert_allclose(b, a, rtol=0.05, atol=0.05 * np.abs(a).max(), err_msg=name)


def test_sequence_sets_and_order():
    t, p, q = helix()
    full = sequence(t, p, q)
    assert full.shape == (512, sum(len(v) for v in FEATURE_SETS.values()))
    parts = [sequence(t, p, q, sets=(s,)) for s in ("euclidean", "affine", "moving")]
    assert [x.shape[1] for x in parts] == [6, 4, 9]
    np.testing.assert_allclose(np.hstack(parts), full)
    k = kinematics(t, p, q)
    np.testing.assert_allclose(full[0, 0], np.log1p(k.speed[0]))  # signed log scale
    np.testing.assert_allclose(full[-1, 6], np.log1p(k.affine_speed[-1]))
    with pytest.raises(ValueError):
        sequence(t, p, q, sets=("spatial",))


# --- relevance-factor selection --------------------------------------------------------------


def test_relevance_hand_computed():
    # f01 = [0, .25, .5, 1]; f̄ = .4375; f̄_i = .125, .75;
    # σ²_inter = (2·.3125² + 2·.3125²)/4 = .09765625; σ²_intra = (.125²·2 + .25²·2)/4 = .0390625
    X = np.array([[0.0], [1.0], [2.0], [4.0]])
    assert relevance(X, np.array([0, 0, 1, 1]))[0] == pytest.approx(2.5)
    # unequal class sizes: f01 = [0, .5, 1], y = a a b: σ²_inter = (2·.25² + 1·.5²)/3 = .125,
    # σ²_intra = (.25² + .25²)/3 = 1/24 → Rel = 3
    assert relevance(np.array([[3.0], [5.0], [7.0]]), np.array(["a", "a", "b"]))[0] == pytest.approx(3.0)


def test_relevance_ranks_separating_feature_first():
    rng = np.random.default_rng(0)
    y = np.repeat([0, 1], 50)
    X = np.column_stack(
        [
            rng.normal(size=100),  # noise
            np.full(100, 3.0),  # constant
            y + 0.1 * rng.normal(size=100),  # separates, with spread
            rng.normal(size=100),  # noise
            10.0 * y - 4.0,  # separates perfectly, no within-class spread
        ]
    )
    rel = relevance(X, y)
    assert rel[1] == 0.0 and np.isinf(rel[4])
    assert rel[2] > 10 * max(rel[0], rel[3])
    assert list(ranking(X, y)[:2]) == [4, 2]
    assert ranking(X, y)[-1] == 1
    assert list(ranking(np.zeros((4, 3)), np.array([0, 0, 1, 1]))) == [0, 1, 2]  # stable ties


def test_normalise_uses_training_bounds():
    train = np.array([[0.0, 5.0, 1.0], [10.0, 7.0, 1.0]])
    X01, lo, hi = normalise(train)
    np.testing.assert_allclose(X01, [[0, 0, 0], [1, 1, 0]])
    test = np.array([[5.0, 6.0, 3.0], [20.0, 4.0, 1.0], [-5.0, 7.0, 0.0]])
    T01, lo2, hi2 = normalise(test, lo, hi)
    np.testing.assert_allclose(T01, [[0.5, 0.5, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    np.testing.assert_array_equal(lo2, lo)
    np.testing.assert_array_equal(hi2, hi)


def test_quantiles_median_and_gradient_equal_numpys_to_the_bit():
    from laban.features import _gradient, _median, _quantiles

    rng = np.random.default_rng(4)
    for n in [1, 2, 3, 4, 5, 20, 21, 97, 400]:
        for x in (rng.random(n) * 10 ** rng.uniform(-3, 3), np.round(rng.random(n), 1)):  # the second with ties
            (p95, p0, p50, p100), median = _quantiles(x, (0.95, 0.0, 0.5, 1.0))
            assert (p95, p0, p50, p100) == tuple(float(np.quantile(x, q)) for q in (0.95, 0.0, 0.5, 1.0))
            assert median == _median(x) == float(np.median(x))
            assert p95 == float(np.percentile(x, 95))
        if n >= 2:
            y = rng.normal(size=(n, 3))
            assert np.array_equal(_gradient(y, 0.0123), np.gradient(y, 0.0123, axis=0))
            assert np.array_equal(_gradient(y[:, 0], 0.0123), np.gradient(y[:, 0], 0.0123))
    assert all(np.isnan(v) for v in _quantiles(np.array([1.0, np.nan, 2.0]), (0.95,))[0])


def test_one_accent_does_not_merge_a_phrases_strokes():
    """A quick raise (peak 4.5 m/s) then twelve swings of 0.2 s (1.3 m/s, under 30 % of the
    raise): each swing is a stroke. With the single fastest moment as the strokes' scale the
    swings fell under its floor and the 'strokes' between the floor's peaks ran 2.6 s."""
    from laban.features import EFFORT_NAMES, effort_features

    t = np.arange(0.0, 3.0, 1 / 90)
    u = np.clip(t / 0.25, 0.0, 1.0)
    x = 0.6 * (10 * u**3 - 15 * u**4 + 6 * u**5) + 0.08 * np.sin(2 * np.pi * np.clip(t - 0.3, 0.0, None) / 0.4) * (t > 0.3)
    f = effort_features(t, np.column_stack([x, 0 * t, 0 * t]))
    assert np.exp(f[EFFORT_NAMES.index("Stroke Duration")]) < 0.3
