"""Tests of the synthetic doodle generator (doodle.synth.strokes)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from doodle.core.model import Doodle, Track
from doodle.synth.strokes import (
    Stroke,
    lost_tracking,
    min_jerk,
    resample,
    stroke,
    synth_doodle,
    synth_track,
    synth_tracks,
)

CLEAN = dict(tremor=0.0, noise=0.0, jitter=0.0, drift=0.0, wobble=0.0, vary=0.0)


def still_mean(track: Track, rng: tuple[int, int]) -> np.ndarray:
    a, b = rng
    return track.p[a:b].mean(axis=0)


def still_rot(track: Track, rng: tuple[int, int]) -> Rotation:
    a, b = rng
    return Rotation.from_quat(track.q[a:b]).mean()


# ----------------------------------------------------------------------------- tokens


def test_stroke_tokens():
    s = stroke("T_Z", 0.5)
    assert s.kind == "T" and s.direction == (0.0, 0.0, 1.0) and s.amplitude == pytest.approx(0.10)
    s = stroke("T_N_X_Y", 0.5)
    assert np.allclose(s.direction, np.array([-1, 1, 0]) / math.sqrt(2))
    s = stroke("T_X_N_Y_Z", 0.5, 0.2)
    assert np.allclose(s.direction, np.array([1, -1, 1]) / math.sqrt(3)) and s.amplitude == 0.2
    s = stroke("R_N_Z", 1.0)
    assert s.kind == "R" and s.direction == (0.0, 0.0, -1.0) and s.amplitude == pytest.approx(1.2)
    s = stroke("T_STILL", 1.0)
    assert s.kind == "S" and s.amplitude == 0.0
    for tok in ("T_Z", "T_N_X_Y", "T_X_N_Y_Z", "R_Y", "R_N_Z", "T_STILL"):
        assert stroke(tok, 1.0).token == tok


@pytest.mark.parametrize("bad", ["T_W", "Q_Z", "T_", "T_Y_X", "T_X_X", "T_N_N_X", "R_STILL", "t_z", "T_Z_", ""])
def test_bad_tokens_name_themselves(bad):
    with pytest.raises(ValueError) as err:
        stroke(bad, 1.0)
    assert repr(bad) in str(err.value)


def test_bad_strokes_rejected():
    with pytest.raises(ValueError):
        stroke("T_Z", 0.0)
    with pytest.raises(ValueError):
        synth_track([Stroke("T", (0, 0, 0), 1.0, 0.1)])
    with pytest.raises(ValueError):
        synth_track([Stroke("Q", (0, 0, 1), 1.0, 0.1)])
    with pytest.raises(ValueError):
        synth_track([])
    with pytest.raises(ValueError):
        synth_track([stroke("T_Z", 1.0)], jitter=0.5)


def test_min_jerk_profile():
    s = min_jerk(np.array([-1.0, 0.0, 0.5, 1.0, 2.0]))
    assert np.allclose(s, [0.0, 0.0, 0.5, 1.0, 1.0])


# ----------------------------------------------------------------------------- basics


def test_shapes_quaternions_times():
    strokes = [stroke("T_STILL", 0.4), stroke("T_Z", 0.6), stroke("R_Y", 0.8), stroke("T_N_X_Y", 0.5)]
    tr, ranges = synth_track(strokes, rate=90.0, seed=3)
    n = len(tr)
    assert tr.t.shape == (n,) and tr.p.shape == (n, 3) and tr.q.shape == (n, 4) and tr.valid.shape == (n,)
    assert tr.valid.all() and tr.name == "c0"
    assert np.allclose(np.linalg.norm(tr.q, axis=1), 1.0, atol=1e-12)
    assert np.all(np.einsum("ij,ij->i", tr.q[1:], tr.q[:-1]) > 0)  # sign-continuous
    assert tr.t[0] == 0.0 and np.all(np.diff(tr.t) > 0)
    dt = np.diff(tr.t)
    assert dt.min() >= 0.8 / 90 - 1e-12 and dt.max() <= 1.2 / 90 + 1e-12
    assert not np.allclose(dt, 1 / 90)  # jittered
    assert n == pytest.approx(90 * 2.3, rel=0.12)
    assert len(ranges) == len(strokes)


def test_ranges_partition_samples():
    strokes = [stroke(tok, d) for tok, d in [("T_STILL", 0.3), ("T_Z", 0.5), ("R_Y", 0.7), ("T_STILL", 0.2), ("T_X", 0.4)]]
    tr, ranges = synth_track(strokes, seed=5)
    assert ranges[0][0] == 0 and ranges[-1][1] == len(tr)
    for (a0, b0), (a1, b1) in zip(ranges, ranges[1:]):
        assert b0 == a1 and a0 <= b0
    assert all(b > a for a, b in ranges)


def test_deterministic_for_a_seed():
    strokes = [stroke("T_Z", 0.5), stroke("R_Y", 0.5), stroke("T_STILL", 0.5)]
    a, ra = synth_track(strokes, seed=7)
    b, rb = synth_track(strokes, seed=7)
    c, _ = synth_track(strokes, seed=8)
    assert ra == rb
    assert np.array_equal(a.t, b.t) and np.array_equal(a.p, b.p) and np.array_equal(a.q, b.q)
    assert len(a) != len(c) or not np.array_equal(a.p, c.p)


def test_clean_performance_is_exact():
    tr, ranges = synth_track([stroke("T_Z", 1.0, 0.1)], **CLEAN)
    assert len(tr) == 91 and np.allclose(tr.t, np.arange(91) / 90)
    s = min_jerk(tr.t / 1.0)
    assert np.allclose(tr.p[:, 2], 0.1 * s) and np.allclose(tr.p[:, :2], 0.0)
    assert np.allclose(np.abs(tr.q[:, 3]), 1.0)


# ----------------------------------------------------------------------------- motion


def test_t_z_moves_forward():
    tr, rg = synth_track([stroke("T_STILL", 0.5), stroke("T_Z", 0.6, 0.1), stroke("T_STILL", 0.5)], seed=1)
    d = still_mean(tr, rg[2]) - still_mean(tr, rg[0])
    assert np.linalg.norm(d) == pytest.approx(0.1, abs=0.015)
    assert np.dot(d / np.linalg.norm(d), [0, 0, 1]) > math.cos(math.radians(5))


def test_t_n_x_y_moves_right_and_up():
    tr, rg = synth_track([stroke("T_STILL", 0.5), stroke("T_N_X_Y", 0.6, 0.1), stroke("T_STILL", 0.5)], seed=2)
    d = still_mean(tr, rg[2]) - still_mean(tr, rg[0])
    want = np.array([-1.0, 1.0, 0.0]) / math.sqrt(2)
    assert np.dot(d / np.linalg.norm(d), want) > math.cos(math.radians(5))
    assert np.linalg.norm(d) == pytest.approx(0.1, abs=0.015)


def test_translation_in_local_frame_of_start_orientation():
    q0 = Rotation.from_rotvec([0.0, math.pi / 2, 0.0])  # facing world +x
    tr, rg = synth_track([stroke("T_STILL", 0.4), stroke("T_Z", 0.6), stroke("T_STILL", 0.4)],
                         start_q=q0.as_quat(), start_p=(1.0, 1.0, 2.0), **CLEAN)
    assert np.allclose(tr.p[0], (1.0, 1.0, 2.0))
    d = tr.p[-1] - tr.p[0]
    assert np.allclose(d, [0.1, 0.0, 0.0], atol=1e-9)


def test_rotation_then_forward_translation():
    strokes = [stroke("T_STILL", 0.5), stroke("R_Y", 1.0, 1.2), stroke("T_STILL", 0.5),
               stroke("T_Z", 0.6, 0.1), stroke("T_STILL", 0.5)]
    tr, rg = synth_track(strokes, seed=4)
    r0, r1 = still_rot(tr, rg[0]), still_rot(tr, rg[2])
    rel = (r0.inv() * r1).as_rotvec()  # body-frame turn
    assert np.linalg.norm(rel) == pytest.approx(1.2, rel=0.12)
    assert np.dot(rel / np.linalg.norm(rel), [0, 1, 0]) > math.cos(math.radians(3))
    # The forward stroke follows the turned figurine's forward axis.
    d = still_mean(tr, rg[4]) - still_mean(tr, rg[2])
    fwd = r1.apply([0.0, 0.0, 1.0])
    assert np.dot(d / np.linalg.norm(d), fwd) > math.cos(math.radians(5))
    # Without variability the turn is exactly 1.2 rad: forward = (sin 1.2, 0, cos 1.2).
    tr, rg = synth_track(strokes, **CLEAN)
    d = tr.p[rg[4][0]] - tr.p[rg[3][0]]
    assert np.allclose(d / np.linalg.norm(d), [math.sin(1.2), 0.0, math.cos(1.2)], atol=1e-9)
    rel = (Rotation.from_quat(tr.q[0]).inv() * Rotation.from_quat(tr.q[-1])).as_rotvec()
    assert np.allclose(rel, [0.0, 1.2, 0.0], atol=1e-9)


def test_still_strokes_barely_move():
    tr, rg = synth_track([stroke("T_STILL", 2.0), stroke("T_Z", 0.5), stroke("T_STILL", 2.0)], seed=9)
    for a, b in (rg[0], rg[2]):
        seg = tr.p[a:b]
        assert np.linalg.norm(seg - seg.mean(axis=0), axis=1).max() < 0.004
        ang = (Rotation.from_quat(tr.q[a:b]) * Rotation.from_quat(tr.q[a]).inv()).magnitude()
        assert ang.max() < 0.05


def test_translation_adds_no_net_rotation():
    tr, rg = synth_track([stroke("T_STILL", 0.5), stroke("T_X_Y_Z", 0.8), stroke("T_STILL", 0.5)], seed=11)
    rel = (still_rot(tr, rg[0]).inv() * still_rot(tr, rg[2])).magnitude()
    assert rel < 0.02
    wob = (Rotation.from_quat(tr.q[slice(*rg[1])]) * still_rot(tr, rg[0]).inv()).magnitude()
    assert wob.max() < 0.05 + 0.03


def test_scale_scales_displacements():
    strokes = [stroke("T_STILL", 0.5), stroke("T_Z", 0.6, 0.1), stroke("T_STILL", 0.5)]
    a, ra = synth_track(strokes, seed=6)
    b, rb = synth_track(strokes, seed=6, scale=3.0)
    da = still_mean(a, ra[2]) - still_mean(a, ra[0])
    db = still_mean(b, rb[2]) - still_mean(b, rb[0])
    assert np.linalg.norm(db) / np.linalg.norm(da) == pytest.approx(3.0, rel=0.03)
    # Everything positional scales: the whole path is 3× the unscaled one.
    assert np.allclose(b.p, 3.0 * a.p, atol=1e-12)


# ----------------------------------------------------------------------------- doodles


def test_synth_doodle_shared_clock_and_padding():
    d = synth_doodle({"a": [stroke("T_Z", 1.0), stroke("T_STILL", 1.0)], "b": [stroke("R_Y", 0.5)]},
                     rate=90.0, seed=2, start_p={"b": (1.0, 0.0, 0.0)})
    assert isinstance(d, Doodle)
    assert d.names == ["a", "b"] and d.rate == 90.0 and d.device == "synthetic" and d.source == "<synthetic>"
    ta, tb = d.tracks
    assert np.array_equal(ta.t, tb.t)
    assert np.allclose(tb.p[0], (1.0, 0.0, 0.0), atol=0.002)
    tracks, ranges = synth_tracks({"a": [stroke("T_Z", 1.0), stroke("T_STILL", 1.0)], "b": [stroke("R_Y", 0.5)]},
                                  seed=2)
    assert len(ranges["a"]) in (2, 3) and len(ranges["b"]) == 2  # b padded with a still stroke
    assert ranges["b"][-1][1] == len(tracks[1])


def test_synth_doodle_from_list_matches_synth_track():
    strokes = [stroke("T_Z", 0.5), stroke("R_N_Z", 0.5)]
    d = synth_doodle(strokes, seed=4)
    tr, _ = synth_track(strokes, seed=4)
    assert d.names == ["c0"] and np.array_equal(d.tracks[0].p, tr.p) and np.array_equal(d.tracks[0].t, tr.t)


def test_long_doodle_is_fast():
    import time

    strokes = [stroke(tok, 0.5) for tok in ("T_Z", "R_Y", "T_STILL", "T_N_X_Y")] * 450  # 15 min
    t0 = time.perf_counter()
    tr, _ = synth_track(strokes)
    assert time.perf_counter() - t0 < 5.0
    assert len(tr) == pytest.approx(90 * 900, rel=0.12)


# ----------------------------------------------------------------------------- helpers


def test_resample_sample_count():
    tr, _ = synth_track([stroke("T_Z", 1.0), stroke("R_Y", 1.0)], seed=1)
    r = resample(tr, 144.0)
    assert len(r) == math.floor(tr.duration * 144.0 + 1e-9) + 1
    assert np.allclose(np.diff(r.t), 1 / 144)
    assert np.allclose(np.linalg.norm(r.q, axis=1), 1.0)
    assert np.all(np.einsum("ij,ij->i", r.q[1:], r.q[:-1]) > 0)
    # Interpolation follows the path.
    for a in range(3):
        assert np.allclose(r.p[:, a], np.interp(r.t, tr.t, tr.p[:, a]))
    j = resample(tr, 144.0, seed=3)
    assert len(j) == len(r) and np.all(np.diff(j.t) > 0) and not np.allclose(np.diff(j.t), 1 / 144)
    d = resample(synth_doodle({"a": [stroke("T_Z", 1.0)], "b": [stroke("T_X", 1.0)]}), 144.0)
    assert d.rate == 144.0 and np.array_equal(d.tracks[0].t, d.tracks[1].t)


def test_lost_tracking_marks_window():
    tr, _ = synth_track([stroke("T_Z", 1.0), stroke("T_STILL", 1.0)], seed=1)
    lost = lost_tracking(tr, 0.5, 0.8)
    win = (tr.t >= 0.5) & (tr.t <= 0.8)
    assert win.sum() > 20
    assert np.array_equal(~lost.valid, win)
    assert np.isnan(lost.p[win]).all() and np.isnan(lost.q[win]).all()
    assert np.array_equal(lost.p[~win], tr.p[~win]) and tr.valid.all()  # original untouched
    r = resample(lost, 144.0)
    assert not r.valid.all() and r.valid.any()
    assert np.isnan(r.p[~r.valid]).all() and np.isfinite(r.p[r.valid]).all()
