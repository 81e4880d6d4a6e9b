"""Tests of the Laban-effort-labelled trajectory generator (laban.synth).

The effort signatures are measured here, independently of ``laban.features``: each take is
resampled uniformly at 90 Hz, differentiated with a Savitzky–Golay filter (cubic, 9 samples;
15 for the size of the jerk peak, where tracking noise is loudest) and compared with its
counterpart that differs in one Element only (same person, pattern and other two Elements).
"""

from __future__ import annotations

import dataclasses
import time

import numpy as np
import pytest
from scipy.signal import savgol_filter

from doodle.core import quat
from laban import synth
from laban.efforts import DRIVES, ELEMENTS, FACTORS

RATE = 90.0


def _who(seed: int = 0, **changes) -> synth.Person:
    return dataclasses.replace(synth.person(np.random.default_rng(seed)), **changes)


def _kinematics(t: np.ndarray, p: np.ndarray, window: int = 9):
    tu = np.arange(t[0], t[-1], 1.0 / RATE)
    pu = np.stack([np.interp(tu, t, p[:, a]) for a in range(3)], axis=1)
    v, a, j = (savgol_filter(pu, window, 3, deriv=k, delta=1.0 / RATE, axis=0) for k in (1, 2, 3))
    return tu, pu, v, a, j


def _measures(t: np.ndarray, p: np.ndarray) -> dict[str, float]:
    tu, pu, v, a, j = _kinematics(t, p)
    speed = np.linalg.norm(v, axis=1)
    s = np.cumsum(speed) / speed.sum()  # fraction of the path length
    size = float(np.linalg.norm(np.ptp(pu, axis=0)))  # bounding-box diagonal
    # The movement: from leaving the start to reaching the end (3 % of the size; tremor
    # and noise are well under a millimetre).
    i0 = np.argmax(np.linalg.norm(pu - pu[0], axis=1) > 0.03 * size)
    i1 = len(pu) - 1 - np.argmax(np.linalg.norm(pu - pu[-1], axis=1)[::-1] > 0.03 * size)
    jerk = np.linalg.norm(j, axis=1)[i0:i1 + 1]
    jerk15 = np.linalg.norm(_kinematics(t, p, window=15)[4], axis=1)[i0:i1 + 1]  # less noise
    cross = np.linalg.norm(np.cross(v, a), axis=1)
    inner = (s > 0.1) & (s < 0.9)  # the envelope's ends left out
    va = np.cbrt(cross[inner])  # equi-affine speed in the osculating plane
    fast = speed > 0.2 * speed.max()
    curvature = cross[fast] / speed[fast] ** 2
    return {
        "duration": float(tu[i1] - tu[i0]),
        "jerk": float(jerk15.max() / size),
        "jerk_at": float(np.argmax(jerk) / (i1 - i0)),
        "size": size,
        "va_cv": float(va.std() / va.mean()),
        "curvature": float((curvature * speed[fast]).sum() / speed[fast].sum() * size),
    }


@pytest.fixture(scope="module")
def takes() -> list[synth.Example]:
    return synth.dataset(people=3, repeats=1, seed=7)


@pytest.fixture(scope="module")
def measured(takes):
    return {(e.person, e.pattern, e.drive): _measures(e.t, e.p) for e in takes}


def _drive(signs) -> str:
    return next(d for d, s in DRIVES.items() if s == tuple(signs))


def _pairs(measured, factor: str, key: str) -> tuple[np.ndarray, np.ndarray]:
    """``key`` for the +1 Element and for its −1 counterpart, matched on everything else."""
    i = FACTORS.index(factor)
    plus, minus = [], []
    for (who, pattern, drive), m in measured.items():
        signs = list(DRIVES[drive])
        if signs[i] > 0:
            signs[i] = -1
            plus.append(m[key])
            minus.append(measured[who, pattern, _drive(signs)][key])
    return np.array(plus), np.array(minus)


# ----------------------------------------------------------------------------- API


def test_drive_signs_are_those_of_laban_efforts():
    named = {
        "Punch": ("Direct", "Sudden", "Strong"), "Dab": ("Direct", "Sudden", "Light"),
        "Press": ("Direct", "Sustained", "Strong"), "Glide": ("Direct", "Sustained", "Light"),
        "Slash": ("Indirect", "Sudden", "Strong"), "Flick": ("Indirect", "Sudden", "Light"),
        "Wring": ("Indirect", "Sustained", "Strong"), "Float": ("Indirect", "Sustained", "Light"),
    }
    assert set(named) == set(DRIVES)
    for drive, elements in named.items():
        signs = tuple(1 if ELEMENTS[f].index(el) == 1 else -1 for f, el in zip(FACTORS, elements))
        assert DRIVES[drive] == signs, drive
    assert synth.DRIVES is DRIVES


def test_patterns():
    assert synth.PATTERNS == ("circle", "line", "lemniscate", "loop", "c_shape", "screw", "zigzag",
                              "hip", "triangle", "come_forth", "thrust")


def test_every_pattern_and_drive_well_formed(takes):
    assert {(e.pattern, e.drive) for e in takes} == {(p, d) for p in synth.PATTERNS for d in DRIVES}
    assert len(takes) == 3 * len(synth.PATTERNS) * len(DRIVES)
    for e in takes:
        n = len(e.t)
        assert e.t.shape == (n,) and e.p.shape == (n, 3) and e.q.shape == (n, 4), (e.pattern, e.drive)
        assert np.all(np.isfinite(e.t)) and np.all(np.isfinite(e.p)) and np.all(np.isfinite(e.q))
        assert e.t[0] == 0.0 and np.all(np.diff(e.t) > 0)
        assert abs(np.median(np.diff(e.t)) - 1 / 90) < 1e-3
        np.testing.assert_allclose(np.linalg.norm(e.q, axis=1), 1.0, atol=1e-9)
        assert np.all(np.einsum("ij,ij->i", e.q[1:], e.q[:-1]) > 0.9), (e.pattern, e.drive)
        # In front of the performer, at hand height, about 0.1–0.8 m across.
        assert np.all(e.p[:, 2] > 0.05) and np.all((e.p[:, 1] > 0.6) & (e.p[:, 1] < 1.8))
        assert 0.05 < np.linalg.norm(np.ptp(e.p, axis=0)) < 0.9
        # Upright and facing forward, give or take a wrist turn.
        up = quat.rotate(e.q, np.array([0.0, 1.0, 0.0]))[:, 1]
        assert np.all(up > 0.3) and np.median(up) > 0.8, (e.pattern, e.drive)


def test_still_pauses_before_and_after(takes):
    for e in takes:
        for part in (e.p[e.t < 0.19], e.p[e.t > e.t[-1] - 0.19]):
            assert len(part) >= 15
            assert np.linalg.norm(np.ptp(part, axis=0)) < 0.005, (e.pattern, e.drive)


def test_free_style():
    who = _who(3)
    shapes = []
    for k, drive in enumerate(DRIVES):
        t, p, q = synth.free_style(drive, who, np.random.default_rng(k))
        assert t[0] == 0 and np.all(np.diff(t) > 0) and p.shape == (len(t), 3) and q.shape == (len(t), 4)
        assert np.all(np.isfinite(p)) and np.allclose(np.linalg.norm(q, axis=1), 1.0)
        shapes.append(np.ptp(p, axis=0))
    assert not np.allclose(shapes[0], shapes[1])
    free = [e for e in synth.dataset(people=1, repeats=0, free=2) if e.pattern == "free"]
    assert len(free) == 2 * len(DRIVES)


def test_deterministic_for_a_seed():
    a = synth.dataset(people=2, repeats=1, seed=3, patterns=("circle", "thrust"), free=1)
    b = synth.dataset(people=2, repeats=1, seed=3, patterns=("circle", "thrust"), free=1)
    c = synth.dataset(people=2, repeats=1, seed=4, patterns=("circle", "thrust"), free=1)
    assert [(e.pattern, e.drive, e.person) for e in a] == [(e.pattern, e.drive, e.person) for e in b]
    for x, y, z in zip(a, b, c):
        assert np.array_equal(x.t, y.t) and np.array_equal(x.p, y.p) and np.array_equal(x.q, y.q)
        assert len(x.t) != len(z.t) or not np.allclose(x.p, z.p)
    t1, p1, _ = synth.trajectory("loop", "Wring", _who(1), np.random.default_rng(5))
    t2, p2, _ = synth.trajectory("loop", "Wring", _who(1), np.random.default_rng(5))
    t3, p3, _ = synth.trajectory("loop", "Wring", _who(1), np.random.default_rng(6))
    assert np.array_equal(p1, p2) and (len(p1) != len(p3) or not np.allclose(p1, p3))


def test_take_does_not_depend_on_the_rest_of_the_dataset():
    small = synth.dataset(people=1, repeats=1, seed=2, patterns=("zigzag",))
    large = synth.dataset(people=2, repeats=2, seed=2, patterns=("circle", "zigzag"))
    same = {}
    for e in large:  # the first repeat of each Drive
        if e.person == 0 and e.pattern == "zigzag":
            same.setdefault(e.drive, e)
    for e in small:
        assert np.array_equal(e.p, same[e.drive].p)


def test_people_differ():
    a, b = synth.person(np.random.default_rng(0)), synth.person(np.random.default_rng(1))
    assert a != b
    for who in (a, b):
        assert all(0.5 <= x <= 1.0 for x in who.expression)
        assert who.hand in (-1, 1) and 0.2 <= who.size <= 0.5


def test_unknown_names_rejected():
    who = _who()
    rng = np.random.default_rng(0)
    with pytest.raises(ValueError, match=r"'square'.*circle.*thrust"):
        synth.trajectory("square", "Punch", who, rng)
    with pytest.raises(ValueError, match=r"'Punchy'.*Punch.*Float"):
        synth.trajectory("circle", "Punchy", who, rng)
    with pytest.raises(ValueError, match="'Sway'"):
        synth.free_style("Sway", who, rng)
    with pytest.raises(ValueError, match="'square'"):
        synth.dataset(people=1, patterns=("circle", "square"))


def test_full_dataset_is_fast():
    start = time.perf_counter()
    data = synth.dataset(people=5, repeats=2, seed=0)
    elapsed = time.perf_counter() - start
    assert len(data) == 5 * 11 * 8 * 2
    assert elapsed < 8.0, elapsed


# ----------------------------------------------------------------------------- signatures


def test_sudden_is_short_and_sustained_long(measured):
    sudden, sustained = _pairs(measured, "time", "duration")
    assert np.all(sudden < sustained)
    assert np.all(sudden < 1.2) and 0.2 < np.median(sudden) < 0.8
    assert np.all(sustained > 1.0) and 1.6 < np.median(sustained) < 4.5


def test_sudden_has_an_early_impulse(measured):
    sudden, sustained = _pairs(measured, "time", "jerk")
    assert np.all(sudden > sustained)
    assert np.exp(np.mean(np.log(sudden / sustained))) > 5.0
    at_sudden, at_sustained = _pairs(measured, "time", "jerk_at")
    assert np.mean(at_sudden) < 0.3
    assert np.mean(at_sudden) < np.mean(at_sustained) - 0.15


def test_strong_is_larger_than_light(measured):
    strong, light = _pairs(measured, "weight", "size")
    assert np.mean(strong > light) > 0.95
    assert np.exp(np.mean(np.log(strong / light))) > 1.25


def test_light_has_uniform_equi_affine_speed(measured):
    strong, light = _pairs(measured, "weight", "va_cv")
    assert np.mean(light < strong) > 0.85
    assert np.exp(np.mean(np.log(strong / light))) > 1.5


def test_indirect_meanders(measured):
    direct, indirect = _pairs(measured, "space", "curvature")
    assert np.mean(indirect > direct) > 0.8
    assert np.exp(np.mean(np.log(indirect / direct))) > 1.3


def test_light_follows_the_power_law():
    """Noise-free Glide on the hip sway (curvature varies, no inflections): constant
    equi-affine speed while the Euclidean speed falls where the path bends (the 1/3 power
    law, speed ∝ κ^(-1/3)); Press on the same path: equi-affine speed varies."""
    found = {}
    for seed in range(3):
        who = _who(seed, tremor=0.0, noise=0.0)
        for drive in ("Glide", "Press"):
            t, p, _ = synth.trajectory("hip", drive, who, np.random.default_rng(seed))
            _, pu, v, a, _ = _kinematics(t, p)
            speed = np.linalg.norm(v, axis=1)
            cross = np.linalg.norm(np.cross(v, a), axis=1)
            s = np.cumsum(speed) / speed.sum()
            plateau = (s > 0.25) & (s < 0.75)
            va = np.cbrt(cross[plateau])
            kappa = cross[plateau] / speed[plateau] ** 2
            slope = np.polyfit(np.log(kappa), np.log(speed[plateau]), 1)[0]
            found[seed, drive] = va.std() / va.mean(), speed[plateau].std() / speed[plateau].mean(), slope
        glide, press = found[seed, "Glide"], found[seed, "Press"]
        assert glide[0] < 0.12 < glide[1], glide
        assert -0.6 < glide[2] < -0.2, glide
        assert press[0] > 3 * glide[0], (glide, press)


def test_orientation_twists_when_indirect_and_snaps_when_strong():
    who = _who(4, tremor=0.0, noise=0.0)

    def turning(drive):
        out = []
        for k, pattern in enumerate(("circle", "zigzag", "triangle")):
            t, _, q = synth.trajectory(pattern, drive, who, np.random.default_rng(k))
            rv = quat.log(quat.multiply(quat.conjugate(q[:1]), q))
            w = np.linalg.norm(np.diff(rv, axis=0), axis=1) / np.diff(t)
            out.append((w.sum() * np.mean(np.diff(t)), w.max()))
        return np.array(out)

    glide, float_, press = turning("Glide"), turning("Float"), turning("Press")
    assert np.all(float_[:, 0] > 2 * glide[:, 0])  # total turning
    assert np.all(press[:, 1] > 2 * glide[:, 1])  # peak angular speed
