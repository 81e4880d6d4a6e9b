"""Synthetic Laban-effort-labelled hand trajectories: seeded 6-DoF doodles in each Drive.

No recorded effort-labelled data exists, so classifiers are trained and evaluated on
performances generated here from kinematic models. The thesis (§4.4.2, Fig. 4.22) recorded
11 predefined patterns in each of the 8 Drives plus free-style curves; :func:`dataset` does
the same for sampled performers (:class:`Person`). A take is ``t`` (n,), ``p`` (n, 3) and
``q`` (n, 4): SPEC conventions — metres, seconds, right-handed world with +y up, +z the
performer's forward and +x their left; unit scalar-last ``(x, y, z, w)`` world-from-figurine
quaternions, the figurine's +x left, +y up, +z front. Drive signs come from
:data:`laban.efforts.DRIVES` (+1 Direct / Sudden / Strong).

Models, and where they come from
--------------------------------
* **Shapes.** Each pattern is a 3D path of extent ≈ 1 in pattern units, resampled to uniform
  arc length; polygonal corners are rounded by Gaussian smoothing along the arc (a hand never
  turns a true corner at speed), and every turnaround is a small U-turn rather than a cusp.
  In the performer's view (x left, y up, z forward): *circle* (frontal plane, from the top);
  *line* a diagonal stroke out and back; *lemniscate* a horizontal figure eight;
  *loop* a sideways stroke with one loop in its middle; *c_shape* a 260° arc opening to the
  performer's right; *screw* a helix of 2.5 turns along the forward axis; *zigzag* five
  strokes alternating up and down; *hip* — our reading of Fig. 4.22(h): a hip sway, the hand
  swinging across along a U-shaped arc that bulges forward at the bottom and back along a
  nearly flat one (a bowl with its lid); *triangle* (apex up, closed); *come_forth* a beckoning
  pull from arm's length up, back toward the body and curling down (sagittal plane);
  *thrust* a forward push and return slightly lower. Free-style curves are sums of three
  random low-frequency 3D sinusoids (flatter in depth). The path is scaled to the performer's
  size (0.25–0.45 m), tilted and yawed by their habitual drawing plane, mirrored for
  left-handers and placed in front of them.
* **Time** (sets the duration and the onset of the speed envelope g(τ), τ ∈ [0, 1]).
  *Sustained*: nominally 2.6–4.0 s; g rises and falls with minimum-jerk steps,
  ``g = s(τ/r)·s((1−τ)/r)`` with ``s`` the Flash & Hogan (1985) profile
  (``doodle.core.profiles.min_jerk``) and r ≈ 0.2–0.4: smooth, symmetric, no impulse anywhere.
  *Sudden*: nominally 0.35–0.75 s, with an impulsive onset — the minimum-jerk rise takes
  only 5–20 % of the movement (15–150 ms) — so peak jerk is high and comes early (the
  thesis's "great impulse (jerk peak) at the beginning", §4.3). Durations also scale with
  the pattern's length (× 0.8–1.25), the performer's tempo and how strongly they express
  Time (nominal 0.75 s and 2.6 s at the weakest, 0.35 s and 4.0 s at the strongest).
* **Weight** (sets the amplitude and how uniform the speed is inside the envelope).
  Along the path both Elements follow the 1/3 power law of drawing, speed ∝ κ^(−1/3), i.e.
  the path is traversed in its equi-affine arc length ``dσ = κ^(1/3) ds`` (Lacquaniti,
  Terzuolo & Viviani 1983, "The law relating the kinematic and figural aspects of drawing
  movements", Acta Psychologica 54:115–130; Pollick & Sapiro 1997, "Constant affine velocity
  predicts the 1/3 power law of planar motion perception and generation", Vision Research
  37(3):347–353); so that straight segments (κ = 0) keep a finite speed we use Viviani &
  Schneider's (1991) modified law ``dσ = (κ + κ₀)^(1/3) ds``, κ₀ = 1 per pattern unit
  (J. Exp. Psychol. HPP 17(1):198–218). Hands slow down in tight bends, whatever the Weight.
  *Light*: amplitude × 0.70–0.85 and a flat envelope — after the rise, constant equi-affine
  speed until a soft minimum-jerk stop (over 20–40 % of the movement, 30–50 % after a
  Sudden onset). *Strong*: amplitude × 1.15–1.30 and non-uniform equi-affine speed that
  curvature does not explain: Sustained Strong multiplies the envelope with 2–4 Gaussian
  speed bursts (up to ×8 the base speed, each at least 45 ms wide); Sudden Strong puts all
  its speed into the impulse and then brakes, ``g = s(τ/r)·(1−τ)^k`` (k ≈ 2–3), so its
  speed peaks in the first fifth and decays.
  *Which equi-affine speed.* The thesis uses the 3D speed ``|[ẋ, ẍ, x⃛]|^(1/6)`` and its
  1/6 law (Pollick, Maoz, Handzel, Giblin, Sapiro & Flash 2009, "Three-dimensional arm
  movements at constant equi-affine speed", Cortex 45(3):325–339). Most patterns of
  Fig. 4.22 are planar, where the torsion is zero and that quantity collapses to noise, so
  the timing uses the speed in the osculating plane, ``|ẋ × ẍ|^(1/3)`` (the 2D equi-affine
  speed of a planar curve); for the screw (constant κ and τ) both laws give the same timing.
  Measure Weight with ``|ẋ × ẍ|^(1/3)``; the 3D quantity only sees Indirect wander.
* **Space.** *Direct*: the pattern drawn cleanly — straight segments straight, planar.
  *Indirect*: the same pattern with meandering detours: three smooth sinusoidal wanders
  (0.8–1.6 cycles per pattern unit of arc length, but at most ~4 per second so they stay
  within voluntary bandwidth; random 3D directions with the tangential part removed, so
  lateral and out-of-plane) of 7–12 % of the pattern size each, tapered to zero at both ends
  so the detour still starts and ends where the pattern does; and a twisting hand (roll and
  yaw of 0.15–0.35 rad, pitch half that, following the same arc length) — higher, varying
  curvature and torsion (thesis §4.3, Fig. 4.16). Expression scales both.
* **Orientation.** The prop is held upright facing forward (identity) with the performer's
  grip offset (≤ 0.08 rad per axis) and a small smooth wobble (sum of sin(jπτ), zero at both
  ends, ≤ 0.02–0.05 rad). Indirect adds the twist above; Strong adds a wrist turn and back
  (Gaussian, 0.15–0.6 rad, about a random wrist axis) with each speed burst, or with the
  Sudden impulse, so angular speed peaks with linear speed. Quaternions are unit and
  sign-continuous (w ≥ 0 at the start).
* **People and takes.** A :class:`Person` holds one performer's habits: size, tempo, how
  strongly they express each Factor (0.5–1.0 — weaker expression brings the two Elements
  closer), ramp and onset fractions, drawing-plane tilt and yaw, handedness, grip and noise
  levels. Each take varies size, duration, aspect, plane and placement by ± ``vary``
  (5–12 %), and is framed by still pauses of 0.2–0.5 s before and after.
* **Tremor, noise, clock** — as :mod:`doodle.synth.strokes`: physiological tremor as 2–3 sinusoids at
  8–12 Hz of 0.3–0.8 mm (and that over a 0.1 m lever in radians; Elble & Koller 1990),
  white tracking noise of 0.2–0.5 mm (Niehorster, Li & Lappe 2017), and a 90 Hz clock with
  ±10 % jitter per sample, t[0] = 0.

Everything is seeded and vectorised: a take's randomness comes from the generator passed
in; :func:`dataset` derives each take's generator from ``SeedSequence([seed, person,
pattern, drive, repeat])``, so a take does not depend on which other takes are asked for.
5 people × 11 patterns × 8 Drives × 2 repeats are generated in about two seconds.

Public API: :data:`PATTERNS`, :class:`Person`, :func:`person`, :class:`Example`,
:func:`trajectory`, :func:`free_style`, :func:`dataset`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.ndimage import gaussian_filter1d

from doodle.core import quat
from doodle.core.profiles import ORIENTATION_LEVER, min_jerk
from laban.efforts import DRIVES

__all__ = ["PATTERNS", "Person", "person", "Example", "trajectory", "free_style", "dataset"]

PATTERNS: tuple[str, ...] = ("circle", "line", "lemniscate", "loop", "c_shape", "screw", "zigzag",
                             "hip", "triangle", "come_forth", "thrust")
FREE = "free"  # pattern name of free-style examples

_N = 1024  # dense samples of a path
_KAPPA0 = 1.0  # modified power law regulariser, 1 / pattern unit
# Pattern length factor on duration (long, winding patterns take longer).
_LENGTH = {"circle": 1.0, "line": 0.85, "lemniscate": 1.2, "loop": 1.1, "c_shape": 0.9, "screw": 1.25,
           "zigzag": 1.15, "hip": 1.0, "triangle": 1.1, "come_forth": 0.9, "thrust": 0.8, FREE: 1.0}


@dataclass(frozen=True)
class Person:
    """One performer's habits (see the module docstring); sample one with :func:`person`."""

    size: float  # pattern size, m
    tempo: float  # duration multiplier
    expression: tuple[float, float, float]  # how strongly Space, Time, Weight are shown, 0.5–1
    ramp: float  # minimum-jerk rise/fall as a fraction of the movement
    onset: float  # Sudden rise fraction of the movement
    decay: float  # Sudden decay exponent
    tilt: float  # drawing plane tilted back about the x axis, rad
    yaw: float  # drawing plane turned about the up axis, rad
    hand: int  # +1 right-handed, -1 left-handed
    centre: tuple[float, float, float]  # where patterns are drawn, world m
    grip: tuple[float, float, float]  # how the prop sits in the hand, rotation vector, rad
    wobble: float  # orientation wobble, rad
    tremor: float  # physiological tremor amplitude, m
    noise: float  # tracking noise std, m
    vary: float  # take-to-take variation, fraction
    jitter: float = 0.1  # clock jitter, sample periods


def person(rng: np.random.Generator) -> Person:
    """A random performer."""
    hand = 1 if rng.random() < 0.85 else -1
    return Person(
        size=float(rng.uniform(0.25, 0.45)),
        tempo=float(rng.uniform(0.85, 1.15)),
        expression=tuple(float(e) for e in rng.uniform(0.5, 1.0, 3)),
        ramp=float(rng.uniform(0.2, 0.4)),
        onset=float(rng.uniform(0.05, 0.15)),
        decay=float(rng.uniform(2.0, 3.0)),
        tilt=float(rng.uniform(-0.3, 0.3)),
        yaw=float(rng.uniform(-0.3, 0.3)),
        hand=hand,
        centre=(float(-hand * rng.uniform(0.05, 0.2)), float(rng.uniform(1.0, 1.3)),
                float(rng.uniform(0.3, 0.45))),
        grip=tuple(float(g) for g in rng.uniform(-0.08, 0.08, 3)),
        wobble=float(rng.uniform(0.02, 0.05)),
        tremor=float(rng.uniform(0.0003, 0.0008)),
        noise=float(rng.uniform(0.0002, 0.0005)),
        vary=float(rng.uniform(0.05, 0.12)),
    )


@dataclass(frozen=True, eq=False)
class Example:
    """One labelled take: ``pattern`` (a name of :data:`PATTERNS` or ``"free"``), ``drive``
    (a key of :data:`laban.efforts.DRIVES`), ``person`` (performer index) and the track."""

    pattern: str
    drive: str
    person: int
    t: np.ndarray
    p: np.ndarray
    q: np.ndarray


# --------------------------------------------------------------------------- shapes


def _arclength(x: np.ndarray) -> np.ndarray:
    return np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(x, axis=0), axis=1))])


def _uniform(x: np.ndarray, n: int = _N) -> np.ndarray:
    """``x`` resampled to ``n`` points equally spaced in arc length."""
    s = _arclength(x)
    si = np.linspace(0.0, s[-1], n)
    return np.stack([np.interp(si, s, x[:, a]) for a in range(3)], axis=1)


def _rounded(points, fillet: float, closed: bool = False) -> np.ndarray:
    """A polyline through ``points`` with corners rounded over ``fillet`` pattern units."""
    pts = np.asarray(points, dtype=float)
    if closed:
        pts = np.vstack([pts, pts[:1]])
    x = _uniform(pts, _N + 1 if closed else _N)
    sigma = fillet / (_arclength(x)[-1] / len(x))
    if closed:
        x = gaussian_filter1d(x[:-1], sigma, axis=0, mode="wrap")
        return np.vstack([x, x[:1]])
    return gaussian_filter1d(x, sigma, axis=0, mode="nearest")


def _frontal(r, up, z=0.0) -> np.ndarray:
    """Points given as (rightward, up, forward) in the performer's view → (x, y, z)."""
    r, up = np.asarray(r, dtype=float), np.asarray(up, dtype=float)
    return np.stack([-r, up, np.broadcast_to(z, r.shape)], axis=-1)


@lru_cache(maxsize=None)
def _shape(pattern: str) -> np.ndarray:
    """Dense unit-size path of a pattern, (n, 3), not yet resampled (read-only, cached)."""
    x = _build(pattern)
    x.flags.writeable = False
    return x


def _build(pattern: str) -> np.ndarray:
    u = np.linspace(0.0, 1.0, _N)
    if pattern == "circle":
        th = np.pi / 2 + 2 * np.pi * u
        return _frontal(-0.45 * np.cos(th), 0.45 * np.sin(th))
    if pattern == "line":  # diagonal, lower left to upper right, and back just below
        d = np.array([np.cos(0.5), np.sin(0.5)])
        n = np.array([d[1], -d[0]]) * 0.08
        a, b = -0.45 * d, 0.45 * d
        return _rounded(_frontal(*np.array([a, b, b + n, a + n]).T), 0.04)
    if pattern == "lemniscate":
        return _frontal(0.5 * np.sin(2 * np.pi * u), 0.22 * np.sin(4 * np.pi * u))
    if pattern == "loop":  # a sideways stroke, one loop up and around, leaving a little behind
        th = np.linspace(-np.pi / 2, 1.5 * np.pi, 256)
        a = (th - th[0]) / (2 * np.pi)
        loop = _frontal(0.16 * np.cos(th) - 0.05 * a, 0.16 + 0.16 * np.sin(th) - 0.04 * a)
        return _rounded(np.vstack([_frontal(-0.5, 0.0), loop, _frontal(0.45, -0.04)]), 0.02)
    if pattern == "c_shape":
        th = np.radians(50 + 260 * u)
        return _frontal(0.45 * np.cos(th), 0.45 * np.sin(th))
    if pattern == "screw":
        th = 2 * np.pi * 2.5 * u
        return _frontal(0.2 * np.sin(th), 0.2 * np.cos(th), 0.7 * (u - 0.5))
    if pattern == "zigzag":
        r = np.linspace(-0.5, 0.5, 6)
        return _rounded(_frontal(r, 0.18 * (-1.0) ** np.arange(6)), 0.035)
    if pattern == "hip":  # swing down-forward across, back along a shallower arc
        th = 2 * np.pi * u
        return _frontal(-0.5 * np.cos(th), -0.15 * np.sin(th) - 0.12 * np.sin(th) ** 2,
                        0.15 * np.sin(th) ** 2)
    if pattern == "triangle":
        a = np.pi / 2 + np.radians([0.0, 120.0, 240.0])
        return _rounded(_frontal(-0.5 * np.cos(a), 0.5 * np.sin(a) - 0.1), 0.04, closed=True)
    if pattern == "come_forth":  # sagittal plane: (forward, up)
        zy = np.array([[0.5, 0.0], [0.3, 0.22], [0.0, 0.3], [-0.22, 0.18], [-0.3, 0.0]])
        return _rounded(np.stack([np.zeros(5), zy[:, 1], zy[:, 0]], axis=1), 0.12)
    if pattern == "thrust":  # forward push, return slightly lower
        zy = np.array([[-0.3, 0.0], [0.4, 0.02], [0.4, -0.06], [-0.3, -0.08]])
        return _rounded(np.stack([np.zeros(4), zy[:, 1], zy[:, 0]], axis=1), 0.04)
    raise AssertionError(pattern)


def _free_shape(rng: np.random.Generator) -> np.ndarray:
    u = np.linspace(0.0, 1.0, _N)[:, None]
    f = rng.uniform(0.3, 1.2, 3)
    phase = rng.uniform(0.0, 2 * np.pi, 3)
    vec = rng.normal(size=(3, 3)) * np.array([1.0, 1.0, 0.4])
    x = np.sin(2 * np.pi * f * u + phase) @ vec
    x = x - x[0]
    return x / max(np.linalg.norm(np.ptp(x, axis=0)), 1e-9)


# --------------------------------------------------------------------------- internals


def _check(pattern: str | None, drive: str | None, rate: float) -> None:
    if pattern is not None and pattern not in PATTERNS:
        raise ValueError(f"unknown pattern {pattern!r}; valid patterns: {', '.join(PATTERNS)}")
    if drive is not None and drive not in DRIVES:
        raise ValueError(f"unknown drive {drive!r}; valid drives: {', '.join(DRIVES)}")
    if not (rate > 0 and math.isfinite(rate)):
        raise ValueError(f"rate must be positive and finite, got {rate!r}")


def _sines(t: np.ndarray, rng: np.random.Generator, total: float, fmin: float, fmax: float,
           count: int) -> np.ndarray:
    """(n, 3) sum of ``count`` sinusoids in random directions; peak norm ≤ ``total``."""
    f = rng.uniform(fmin, fmax, count)
    phase = rng.uniform(0.0, 2 * np.pi, count)
    w = rng.uniform(0.5, 1.0, count)
    u = rng.normal(size=(count, 3))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    return (np.sin(2 * np.pi * f * t[:, None] + phase) * (w / w.sum() * total)) @ u


def _rot(axis: int, angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    m = np.eye(3)
    m[i, i] = m[j, j] = c
    m[i, j], m[j, i] = -s, s
    return m


def _derivatives(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    d1 = np.gradient(x, axis=0)
    return d1, np.gradient(d1, axis=0)


def _perform(unit: np.ndarray, length: float, drive: str, who: Person, rng: np.random.Generator,
             rate: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Render a unit-size path in a Drive: the models of the module docstring."""
    space, time, weight = DRIVES[drive]
    e_space, e_time, e_weight = who.expression
    v = who.vary

    def var(k: int | None = None):  # take-to-take variation factor(s)
        return 1.0 + rng.uniform(-v, v, k)

    # Time: duration.
    lo, hi = ((0.75, 0.35) if time > 0 else (2.6, 4.0))
    duration = who.tempo * length * (lo + (hi - lo) * (e_time - 0.5) / 0.5) * var()

    # Path geometry in pattern units: take-to-take aspect, then Space.
    x = _uniform(unit * var(3))
    s = _arclength(x)
    L = s[-1]
    twist = np.zeros((len(x), 3))
    if space < 0:
        window = (min_jerk(s / 0.15) * min_jerk((L - s) / 0.15))[:, None]
        tangent = np.gradient(x, axis=0)
        tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
        # Detours per pattern unit, at most ~4 per second on average (voluntary bandwidth).
        f = np.minimum(rng.uniform(0.8, 1.6, 3), 4.0 * duration / L)
        vec = rng.normal(size=(3, 3))
        vec *= (rng.uniform(0.07, 0.12, 3) * e_space / np.linalg.norm(vec, axis=1))[:, None]
        wander = np.sin(2 * np.pi * f * s[:, None] + rng.uniform(0.0, 2 * np.pi, 3)) @ vec
        wander -= np.einsum("ij,ij->i", wander, tangent)[:, None] * tangent
        x = x + wander * window
        axes = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
        amp = rng.uniform(0.15, 0.35, 3) * e_space * np.array([1.0, 1.0, 0.5])
        f = np.minimum(rng.uniform(0.3, 0.8, 3), 2.0 * duration / L)
        twist = (np.sin(2 * np.pi * f * s[:, None] + rng.uniform(0, 2 * np.pi, 3)) * amp) @ axes * window

    # Progress measure along the path: modified equi-affine arc length; amplitude.
    d1, d2 = _derivatives(x)
    ds = np.linalg.norm(d1, axis=1)
    kappa = np.linalg.norm(np.cross(d1, d2), axis=1) / np.maximum(ds, 1e-12) ** 3
    dsig = np.cbrt(kappa + _KAPPA0) * ds
    sig = np.concatenate([[0.0], np.cumsum(0.5 * (dsig[1:] + dsig[:-1]))])
    sig /= sig[-1]
    amplitude = who.size * var() * (1.0 + 0.3 * e_weight * weight)

    # Speed envelope: Time sets the rise, Weight how uniform the rest is.
    tau = np.linspace(0.0, 1.0, 1001)
    ramp = who.ramp * var()
    onset = who.onset * (1.3 - 0.6 * (e_time - 0.5)) if time > 0 else ramp
    g = min_jerk(tau / onset)
    if time > 0 and weight > 0:  # one impulse, then braking; the wrist snaps with it
        g = g * (1.0 - tau) ** who.decay
        bursts = np.array([[tau[np.argmax(g)], max(0.7 * onset, 0.045 / duration)]])
    else:  # flat, then a soft minimum-jerk stop (softer still after a Sudden onset)
        g = g * min_jerk((1.0 - tau) / (ramp + (0.1 if time > 0 else 0.0)))
        bursts = np.zeros((0, 2))
    if time < 0 and weight > 0:  # speed bursts along the path
        k = int(rng.integers(2, 5))
        centres = 0.12 + 0.76 * (np.arange(k) + 0.5 + rng.uniform(-0.3, 0.3, k)) / k
        widths = np.maximum(rng.uniform(0.035, 0.06, k), 0.045 / duration)
        bursts = np.stack([centres, widths], axis=1)
        g = g * ((1.0 - 0.6 * e_weight) + 3.0 * e_weight * np.exp(
            -0.5 * ((tau[:, None] - centres) / widths) ** 2).sum(axis=1))
    prog = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]))])
    prog /= prog[-1]

    # Clock with still pauses around the movement.
    pre, post = rng.uniform(0.2, 0.5, 2)
    n = int(math.floor((pre + duration + post) * rate)) + 1
    t = np.arange(n, dtype=float)
    t[1:] += rng.uniform(-who.jitter, who.jitter, n - 1)
    t /= rate
    tau_t = np.clip((t - pre) / duration, 0.0, 1.0)
    idx = np.interp(np.interp(tau_t, tau, prog), sig, np.arange(len(x)))

    # Place the path in the world.
    xs = x * amplitude
    xs -= 0.5 * (xs.min(axis=0) + xs.max(axis=0))
    xs[:, 0] *= who.hand
    R = (_rot(1, who.yaw + rng.uniform(-0.05, 0.05)) @ _rot(0, -who.tilt + rng.uniform(-0.05, 0.05)))
    xs = xs @ R.T + np.asarray(who.centre) + rng.uniform(-0.02, 0.02, 3)
    grid = np.arange(len(x))
    p = np.stack([np.interp(idx, grid, xs[:, a]) for a in range(3)], axis=1)

    # Orientation: grip, wobble, Indirect twist, Strong wrist bursts.
    rv = np.asarray(who.grip) + rng.uniform(-0.03, 0.03, 3)
    rv = np.broadcast_to(rv, (n, 3)).copy()
    j = np.arange(1, 4)
    wob = rng.normal(size=(3, 3))
    wob *= (who.wobble * rng.uniform(0.3, 1.0, 3) / 3 / np.linalg.norm(wob, axis=1))[:, None]
    rv += np.sin(np.pi * j * tau_t[:, None]) @ wob
    rv += np.stack([np.interp(idx, grid, twist[:, a]) for a in range(3)], axis=1)
    if len(bursts):
        k = len(bursts)  # a wrist turn and back with each burst
        ax = rng.normal(size=(k, 3)) * np.array([1.0, 0.5, 1.0])
        ax /= np.linalg.norm(ax, axis=1, keepdims=True)
        ang = rng.uniform(0.3, 0.6, k) * e_weight * (-1.0) ** np.arange(k)
        rv += np.exp(-0.5 * ((tau_t[:, None] - bursts[:, 0]) / bursts[:, 1]) ** 2) * ang @ ax

    # Tremor and tracking noise.
    count = int(rng.integers(2, 4))
    p += _sines(t, rng, who.tremor, 8.0, 12.0, count)
    rv += _sines(t, rng, who.tremor / ORIENTATION_LEVER, 8.0, 12.0, count)
    p += rng.normal(0.0, who.noise, (n, 3))
    rv += rng.normal(0.0, who.noise / ORIENTATION_LEVER, (n, 3))
    q = quat.make_continuous(quat.normalise(quat.exp(rv)))
    if q[0, 3] < 0:
        q = -q
    return t, p, q


# --------------------------------------------------------------------------- public API


def trajectory(pattern: str, drive: str, who: Person, rng: np.random.Generator,
               rate: float = 90.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """One take of ``pattern`` in ``drive`` by ``who``: times (n,), positions (n, 3), quaternions (n, 4)."""
    _check(pattern, drive, rate)
    return _perform(_shape(pattern), _LENGTH[pattern], drive, who, rng, rate)


def free_style(drive: str, who: Person, rng: np.random.Generator,
               rate: float = 90.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A random smooth free-form curve performed in ``drive``, as :func:`trajectory`."""
    _check(None, drive, rate)
    return _perform(_free_shape(rng), _LENGTH[FREE], drive, who, rng, rate)


def dataset(people: int = 5, repeats: int = 2, seed: int = 0, patterns=PATTERNS, free: int = 0,
            rate: float = 90.0) -> list[Example]:
    """Every pattern × every Drive × ``repeats`` takes (plus ``free`` free-style curves per
    Drive) for each of ``people`` sampled performers; deterministic for a ``seed``."""
    patterns = tuple(patterns)
    for pat in patterns + (None,):
        _check(pat, None, rate)
    if min(people, repeats, free, seed) < 0:
        raise ValueError(f"people, repeats, free and seed must be ≥ 0, got {people}, {repeats}, {free}, {seed}")
    drives = list(DRIVES)
    out: list[Example] = []
    for i in range(people):
        who = person(np.random.default_rng([seed, i + 1]))
        for pat in patterns:
            k = PATTERNS.index(pat)
            for d, drive in enumerate(drives):
                for r in range(repeats):
                    rng = np.random.default_rng([seed, i + 1, k + 1, d + 1, r + 1])
                    out.append(Example(pat, drive, i, *trajectory(pat, drive, who, rng, rate)))
        for d, drive in enumerate(drives):
            for r in range(free):
                rng = np.random.default_rng([seed, i + 1, len(PATTERNS) + 1, d + 1, r + 1])
                out.append(Example(FREE, drive, i, *free_style(drive, who, rng, rate)))
    return out
