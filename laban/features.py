"""Kinematic features of a hand trajectory segment (thesis §4.3; summaries §4.4.1, sets Table 4.3).

Pipeline (:func:`kinematics`):

1. **Resample** uniformly in time at ``rate`` (default: the segment's median rate), at least
   :data:`MIN_SAMPLES` points: positions linearly, orientations by normalised linear
   interpolation of sign-continuous quaternions (nlerp; steps are one sample, so it equals
   slerp to well below tracking noise). This absorbs jittered timestamps.
2. **Differentiate** with Savitzky–Golay cubic fits over a window of :data:`WINDOW_S`
   seconds (so the filter is rate independent); at the ends the fit of the first / last
   window is evaluated (scipy's ``mode="interp"``). A segment shorter than the window uses
   one fit over all its samples.
3. **Global (world) features** ``Ve = (v_e, ω)`` and its derivatives ``Ae``, ``Je``:
   ``v_e, a, j = ṗ, p̈, p⃛``; ``ω`` from the quaternion log of relative rotations,
   ``ω_{i+½} = log(q_{i+1} q_i⁻¹)/Δt`` (world axes, never Euler differences), averaged onto
   the samples and then smoothed and differentiated like ``p``.
4. **Moving frame** (figurine axes left, up, front): ``v = R_iᵀ v_e`` and its time
   derivatives ``v̇, v̈`` (derivatives of the components, as the thesis feeds them).
5. **Geometry**, regularised so that slow or straight motion never divides by zero:

   * curvature ``κ = |v_e × a| / (|v_e|² + ε²)^{3/2}``, ε = :data:`EPS_SPEED` = 0.05 m/s —
     exact ``|v_e × a|/|v_e|³`` above ~0.5 m/s (< 1.5 % low), 0 for a still hand;
   * torsion ``τ = [v_e, a, j] / (|v_e × a|² + ε'²)``, ε' = ε·:data:`EPS_ACCEL` =
     0.05 m²/s³ (a 0.05 m/s motion turning at 1 m/s²); signed (right-handed helix > 0);
   * equi-affine speed ``V_a = |[v_e, a, j]|^{1/6}`` (m^½/s; 0 for any planar curve —
     the 3-D definition) and ``A_a = dV_a/dt`` by the same smoothing differentiator
     (not the analytic formula, whose ``1/6`` power is singular at 0).

:func:`summary` gives the ~50 per-segment features of §4.4.1 (:data:`SUMMARY_NAMES`), and
:func:`sequence` the per-sample columns of Table 4.3 resampled to a fixed length (HMM input).
Both compress the heavy-tailed κ and τ as ``log1p(κ)`` and ``sign(τ)·log1p(|τ|)`` (κ, τ in
1/m); :class:`Kinematics` holds them raw.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from numpy.lib.stride_tricks import as_strided

from doodle.core import quat
from doodle.core.filters import gaussian_filter1d
from doodle.core.splines import CubicSpline

WINDOW_S = 0.12  # s, Savitzky–Golay window (11 samples at 90 Hz)
ORDER = 3  # cubic fits: up to the third derivative (jerk)
MIN_SAMPLES = 5  # resampled length floor, so a cubic can be fitted to 2- or 3-sample segments
DEFAULT_RATE = 90.0  # Hz, for a single-sample segment
EPS_SPEED = 0.05  # m/s, speed floor in κ and in the speed variation
EPS_ACCEL = 1.0  # m/s², with EPS_SPEED the floor of |v × a| in τ
EPS_CROSS = EPS_SPEED * EPS_ACCEL  # m²/s³
EPS_JERK = 1.0  # m/s³, floor of the mean jerk in "Jerk Peak Ratio"
EPS_AFFINE = 0.1  # m^½/s, floor of the mean V_a in the equi-affine ratios
TINY = 1e-9  # below this (m/s, m/s³, m) a peak or a path is numerical noise


@dataclass(frozen=True, eq=False)
class Kinematics:
    """Per-sample features on the uniform grid ``t`` (n,). Norms are world-frame; ``local_*``
    are (n, 3) in figurine axes (left, up, front); ``curvature`` and ``torsion`` in 1/m."""

    t: np.ndarray
    speed: np.ndarray  # |v_e|, m/s
    accel: np.ndarray  # |a|, m/s²
    jerk: np.ndarray  # |j|, m/s³
    ang_speed: np.ndarray  # |ω|, rad/s
    ang_accel: np.ndarray  # |ω̇|, rad/s²
    ang_jerk: np.ndarray  # |ω̈|, rad/s³
    local_v: np.ndarray  # v = Rᵀ v_e
    local_a: np.ndarray  # v̇
    local_j: np.ndarray  # v̈
    curvature: np.ndarray
    torsion: np.ndarray
    affine_speed: np.ndarray  # V_a
    affine_accel: np.ndarray  # A_a


_FACTORIALS = np.array([math.factorial(d) for d in range(ORDER + 1)], float)


@lru_cache(maxsize=64)
def _operators(w: int) -> tuple[np.ndarray, np.ndarray]:
    """Least-squares cubic fit over ``w`` samples centred on 0: ``proj`` (4, w) maps a window
    to polynomial coefficients; ``ev[d]`` (w, 4) evaluates the d-th derivative at each offset."""
    offs = np.arange(w, dtype=float) - w // 2
    proj = np.linalg.pinv(np.vander(offs, ORDER + 1, increasing=True))
    k = np.arange(ORDER + 1)
    ev = np.stack(
        [np.array([math.perm(kk, d) for kk in k], float) * offs[:, None] ** np.maximum(k - d, 0) for d in k]
    )
    return proj, ev


def _derivatives(x: np.ndarray, dt: float, count: int) -> np.ndarray:
    """Savitzky–Golay estimates (count, m, c) of derivatives 0..count-1 of the columns of
    ``x`` (m, c), m ≥ 5, sampled every ``dt`` s; equals ``savgol_filter(x, w, 3, deriv=d,
    delta=dt, mode="interp", axis=0)`` for the odd window ``w`` nearest :data:`WINDOW_S` (≤ m)."""
    m, c = x.shape
    w = min(max(MIN_SAMPLES, 2 * int(round(WINDOW_S / dt / 2)) + 1), m - 1 + m % 2)
    h, n = w // 2, m - w + 1
    proj, ev = _operators(w)
    xt = np.ascontiguousarray(x.T)
    windows = as_strided(xt, (c, n, w), (xt.strides[0], xt.strides[1], xt.strides[1]), writeable=False)
    coef = (windows.reshape(-1, w) @ proj.T).reshape(c, n, ORDER + 1)  # cubic per window
    out = np.empty((count, m, c))
    out[:, h : m - h] = (coef[:, :, :count] * _FACTORIALS[:count]).transpose(2, 1, 0)
    out[:, :h] = ev[:count, :h] @ coef[:, 0].T  # first window's cubic at the first h samples
    out[:, m - h :] = ev[:count, h + 1 :] @ coef[:, -1].T
    return out / (dt ** np.arange(count))[:, None, None]


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return np.stack(
        [
            a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1],
            a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
            a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0],
        ],
        axis=-1,
    )


def _norm(x: np.ndarray) -> np.ndarray:
    return np.sqrt(np.einsum("ij,ij->i", x, x))


def _gradient(x: np.ndarray, dt: float) -> np.ndarray:
    """``np.gradient(x, dt, axis=0)`` (central differences, one-sided at the ends) to the bit,
    without its checks; ``x`` has at least two rows."""
    out = np.empty_like(x, dtype=float)
    out[1:-1] = (x[2:] - x[:-2]) / (2.0 * dt)
    out[0] = (x[1] - x[0]) / dt
    out[-1] = (x[-1] - x[-2]) / dt
    return out


def _median(x: np.ndarray) -> float:
    """``np.median`` of a non-empty 1-D array, to the bit (:func:`_quantiles`)."""
    return _quantiles(x, ())[1]


def _quantiles(x: np.ndarray, qs: tuple[float, ...]) -> tuple[tuple[float, ...], float]:
    """``(np.quantile(x, q) for q in qs)`` (linear interpolation) and ``np.median(x)`` of a
    non-empty 1-D array, to the bit, from one partition (numpy's functions spend more on their
    checks than on a segment's few hundred samples)."""
    n = len(x)
    virtual = [(n - 1) * q for q in qs]
    below = [min(math.floor(v), n - 1) for v in virtual]
    kth = {n // 2, n - 1, *below, *(min(b + 1, n - 1) for b in below)} | ({n // 2 - 1} if n % 2 == 0 else set())
    part = np.partition(x, sorted(kth))
    if math.isnan(part[-1]):  # numpy's answer with a NaN
        return tuple(math.nan for _ in qs), math.nan
    median = float(part[n // 2]) if n % 2 else float((part[n // 2 - 1] + part[n // 2]) / 2.0)
    out = []
    for v, b in zip(virtual, below):
        if v >= n - 1:
            out.append(float(part[-1]))
            continue
        lo, hi, gamma = part[b], part[b + 1], v - b
        diff = hi - lo
        out.append(float(hi - diff * (1 - gamma)) if gamma >= 0.5 else float(lo + diff * gamma))
    return tuple(out), median


def _resample(t: np.ndarray, grid: np.ndarray, x: np.ndarray) -> np.ndarray:
    """Linear interpolation of the rows of ``x`` (n, c), sampled at ``t``, at ``grid`` ⊂ [t0, t_end]."""
    i = np.clip(np.searchsorted(t, grid, side="right") - 1, 0, len(t) - 2)
    a = ((grid - t[i]) / (t[i + 1] - t[i]))[:, None]
    return x[i] + a * (x[i + 1] - x[i])


def kinematics(t: np.ndarray, p: np.ndarray, q: np.ndarray, rate: float | None = None) -> Kinematics:
    """Per-sample kinematic features of a segment (§4.3), see the module docstring.

    ``t`` (n,) strictly increasing seconds, ``p`` (n, 3) metres, ``q`` (n, 4) world-from-
    figurine quaternions (x, y, z, w; any norm or sign). ``rate`` (Hz) is the resampling
    rate, by default ``1 / median(Δt)``. A single sample is treated as a still segment.
    """
    t = np.asarray(t, float).ravel()
    p = np.asarray(p, float).reshape(-1, 3)
    q = quat.make_continuous(quat.normalise(np.asarray(q, float).reshape(-1, 4)))
    if len(t) == 0 or len(p) != len(t) or len(q) != len(t):
        raise ValueError("kinematics needs t, p, q with the same, non-zero number of samples")
    if len(t) == 1:
        t = np.array([t[0], t[0] + 1.0 / (rate or DEFAULT_RATE)])
        p, q = np.repeat(p, 2, axis=0), np.repeat(q, 2, axis=0)
    steps = np.diff(t)
    if not np.all(steps > 0):
        raise ValueError("timestamps must be strictly increasing")
    duration = t[-1] - t[0]
    rate = float(rate) if rate else 1.0 / _median(steps)
    m = max(MIN_SAMPLES, int(round(duration * rate)) + 1)
    grid = np.linspace(t[0], t[-1], m)
    dt = duration / (m - 1)
    pq = _resample(t, grid, np.hstack([p, q]))
    pg, qg = pq[:, :3], quat.normalise(pq[:, 3:])

    r = quat.multiply(qg[1:], quat.conjugate(qg[:-1]))  # q_{i+1} = r q_i: world-frame step
    r = np.where(r[:, 3:4] < 0, -r, r)
    om = quat.log(r) / dt
    om = np.concatenate([om[:1], 0.5 * (om[1:] + om[:-1]), om[-1:]])

    x0, x1, x2, x3 = _derivatives(np.hstack([pg, om]), dt, ORDER + 1)
    ve, ae, je = x1[:, :3], x2[:, :3], x3[:, :3]
    speed = _norm(ve)
    c = _cross(ve, ae)
    c2 = np.einsum("ij,ij->i", c, c)
    triple = np.einsum("ij,ij->i", c, je)
    va = np.abs(triple) ** (1.0 / 6.0)
    local_v = quat.rotate_inverse(qg, ve)
    y0, y1, y2 = _derivatives(np.hstack([local_v, va[:, None]]), dt, 3)
    return Kinematics(
        t=grid,
        speed=speed,
        accel=_norm(ae),
        jerk=_norm(je),
        ang_speed=_norm(x0[:, 3:]),
        ang_accel=_norm(x1[:, 3:]),
        ang_jerk=_norm(x2[:, 3:]),
        local_v=local_v,
        local_a=y1[:, :3],
        local_j=y2[:, :3],
        curvature=np.sqrt(c2) / (speed * speed + EPS_SPEED**2) ** 1.5,
        torsion=triple / (c2 + EPS_CROSS**2),
        affine_speed=va,
        affine_accel=y1[:, 3],
    )


def _log_curvature(k: Kinematics) -> np.ndarray:
    return np.log1p(k.curvature)


def _log_torsion(k: Kinematics) -> np.ndarray:
    return np.sign(k.torsion) * np.log1p(np.abs(k.torsion))


_AXES = ("Left", "Up", "Front")
_LOCAL = tuple(f"Local {q} {a}" for q in ("Speed", "Accel", "Jerk") for a in _AXES)
_NORMS = ("Speed", "Acceleration", "Jerk", "Angular Speed", "Angular Accel", "Angular Jerk")
_AFFINE = ("Equi-Affine Speed", "Equi-Affine Accel", "Curvature", "Torsion")

FEATURE_SETS: dict[str, tuple[str, ...]] = {
    "euclidean": _NORMS,  # ‖Ve‖ ‖Ae‖ ‖Je‖, linear and angular (Ve = (v_e, ω))
    "affine": _AFFINE,  # V_a A_a κ τ — κ as log1p(κ), τ as sign(τ)·log1p(|τ|)
    "moving": _LOCAL,  # v v̇ v̈, 3 components each
}
"""Per-sample column names of Table 4.3's feature sets, in :func:`sequence`'s column order."""

_STATS = _LOCAL + _NORMS + _AFFINE
SUMMARY_NAMES: tuple[str, ...] = tuple(f"{f} {s}" for f in _STATS for s in ("Mean", "Stdev")) + (
    "Duration",  # s
    "Path Length",  # m, ∫|v_e| dt
    "Amplitude",  # m, twice the largest distance from the centroid (rotation invariant)
    "Straightness",  # chord / path length, in [0, 1] (0 for a still hand)
    "Peak Speed",  # m/s
    "Peak Speed Time",  # time of the peak speed / duration, in [0, 1]
    "Peak Jerk",  # m/s³
    "Peak Jerk Time",  # time of the peak jerk / duration (onset impulse of Sudden motion)
    "Speed Variation",  # std |v_e| / max(mean |v_e|, EPS_SPEED)
    "Jerk Peak Ratio",  # max |j| / max(mean |j|, EPS_JERK) (impulsiveness)
    "Equi-Affine Speed Variation",  # std V_a / max(mean V_a, EPS_AFFINE) (Weight: uniformity)
    "Equi-Affine Accel Ratio",  # mean |A_a| / max(mean V_a, EPS_AFFINE), 1/s
)
"""Names of :func:`summary`'s features (§4.4.1, Table 4.2 naming): the mean and standard
deviation of each per-sample feature over the segment's uniform time grid, then twelve
Time / Weight descriptors. Curvature and Torsion statistics are **speed-weighted**
(``Σ|v_e|x / Σ|v_e|``, i.e. per unit arc length, so a still hand does not dominate) and
taken on the log1p scale (``log1p(κ)``, ``sign(τ)·log1p(|τ|)``)."""


def _peak(x: np.ndarray, floor: float) -> tuple[float, float]:
    """``(max, relative index of the max)``; a max below ``floor`` is noise: ``(max, 0)``."""
    i = int(np.argmax(x))
    return float(x[i]), (i / (len(x) - 1) if x[i] >= floor else 0.0)


def summary(t: np.ndarray, p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """The (len(SUMMARY_NAMES),) summary features of a segment, all finite (§4.4.1)."""
    k = kinematics(t, p, q)
    cols = np.column_stack(
        [k.local_v, k.local_a, k.local_j, k.speed, k.accel, k.jerk, k.ang_speed, k.ang_accel, k.ang_jerk,
         k.affine_speed, k.affine_accel]
    )
    mean, std = cols.mean(axis=0), cols.std(axis=0)
    total = k.speed.sum()
    w = k.speed / total if total > TINY else np.full(len(k.speed), 1.0 / len(k.speed))
    geo = np.column_stack([_log_curvature(k), _log_torsion(k)])
    gmean = w @ geo
    gstd = np.sqrt(np.maximum(w @ (geo - gmean) ** 2, 0.0))
    stats = np.column_stack([np.append(mean, gmean), np.append(std, gstd)]).ravel()

    p = np.asarray(p, float).reshape(-1, 3)
    duration = float(k.t[-1] - k.t[0]) if len(np.asarray(t).ravel()) > 1 else 0.0
    dt = np.diff(k.t)
    path = float(np.sum(0.5 * (k.speed[1:] + k.speed[:-1]) * dt))
    chord = float(np.linalg.norm(p[-1] - p[0]))
    amplitude = 2.0 * float(np.max(_norm(p - p.mean(axis=0))))
    peak_v, peak_v_time = _peak(k.speed, TINY)
    peak_j, peak_j_time = _peak(k.jerk, TINY)
    i_v, i_j, i_va = _STATS.index("Speed"), _STATS.index("Jerk"), _STATS.index("Equi-Affine Speed")
    va_mean = max(mean[i_va], EPS_AFFINE)
    extra = [
        duration,
        path,
        amplitude,
        chord / max(path, chord, TINY),
        peak_v,
        peak_v_time,
        peak_j,
        peak_j_time,
        std[i_v] / max(mean[i_v], EPS_SPEED),
        peak_j / max(mean[i_j], EPS_JERK),
        std[i_va] / va_mean,
        float(np.abs(k.affine_accel).mean()) / va_mean,
    ]
    return np.concatenate([stats, extra])


def sequence(
    t: np.ndarray,
    p: np.ndarray,
    q: np.ndarray,
    sets: tuple[str, ...] = ("euclidean", "affine", "moving"),
    points: int = 512,
) -> np.ndarray:
    """(points, d) HMM input (§4.4.2): the columns of :data:`FEATURE_SETS` for ``sets``, in
    that order, linearly resampled to ``points`` rows uniformly spaced in time, on a signed
    log scale ``sign(x)·log1p(|x|)`` (SI units): jerks, curvatures and torsions are heavy
    tailed, and a Gaussian state fits their logarithm far better (measured: Drive HMM
    accuracy on held-out generated curves 0.71 → 0.80)."""
    k = kinematics(t, p, q)
    blocks = {
        "euclidean": lambda: [k.speed, k.accel, k.jerk, k.ang_speed, k.ang_accel, k.ang_jerk],
        "affine": lambda: [k.affine_speed, k.affine_accel, k.curvature, k.torsion],
        "moving": lambda: [k.local_v, k.local_a, k.local_j],
    }
    unknown = set(sets) - set(blocks)
    if unknown or not sets:
        raise ValueError(f"feature sets must be among {sorted(blocks)}, got {list(sets)}")
    x = np.column_stack([c for s in sets for c in blocks[s]()])
    grid = np.linspace(k.t[0], k.t[-1], points)
    x = _resample(k.t, grid, x)
    return np.sign(x) * np.log1p(np.abs(x))


# --- Effort features: what Time and Weight are, whatever the size and the sampling --------------
#
# The Drive HMM above reads the thesis's raw kinematics (m/s, m/s², m/s³), which change with
# the size of the movement (a figurine's 20 cm against an arm's 1.5 m) and, through the
# derivative filter, with the sampling rate. The Time and Weight decisions read these instead.
#
# Rate: every segment is first brought to one signal — a cubic spline through its samples
# (natural end conditions; a 30 Hz take keeps a 5 Hz component within ~1 %) evaluated on
# a fixed EFFORT_RATE grid, then low-passed by a Gaussian of EFFORT_SIGMA seconds and
# differentiated (central differences) into velocity, acceleration and jerk. The filter's
# response is −3 dB near 4 Hz and nil at 15 Hz, the Nyquist frequency of the slowest rate accepted (30 Hz): the same
# movement sampled at 30, 60, 90 or 144 Hz becomes the same smoothed signal. Voluntary hand
# movement lies below ~5 Hz (physiological tremor, 8–12 Hz, is removed too).
#
# Size: a length only ever appears divided by the segment's own extent (twice the largest
# distance from its centroid) or a stroke's own length, and a speed by its own mean or peak,
# so uniform scaling of the path leaves every feature unchanged. Time remains in seconds:
# Sudden and Sustained ARE durations and rates of change (Laban; EMOTE, Chi et al. 2000, sets
# Time by the duration and the timing of a stroke).
#
# Strokes: the movement is cut at its speed minima into strokes (speed peaks of at least 30 %
# of its fast speed — the 90th percentile, not the single fastest moment, so that one accent
# does not make a phrase's other strokes into wobbles — standing out by 15 % of it) and each stroke is measured on its own, the
# measures averaged weighted by the strokes' kinetic energy: a walk's steps or a wave's
# swings are strokes however far the body travels, where the segment's extent would grow
# with the distance walked. The "Stroke" Weight features are free of tempo as well as size
# (a stroke's duration T, length L and peak speed make them dimensionless): Weight is how
# force is spent, whatever the Time — the same stroke made Sudden or Sustained is equally
# Strong. Noise: with the tracker's absolute noise (0.3 mm) a figurine's jerk is noisier
# than an arm's; the classifiers are trained on every size ×0.1–×10 with that noise.
#
# Where each feature comes from is in EFFORT_SOURCES.

EFFORT_RATE = 120.0  # Hz, the grid every segment is brought to
EFFORT_SIGMA = 0.04  # s, Gaussian low-pass (and derivative) width
ACTIVE = 0.1  # the movement is where the speed is above this share of its peak
STROKE_TOP = 0.9  # the segment's fast speed: this quantile of its speed ...
STROKE_FLOOR = 0.3  # ... a stroke is a speed peak above this share of it ...
STROKE_DIP = 0.5  # ... with a prominence of this share of that floor

EFFORT_SOURCES: dict[str, str] = {
    "Active Duration": "log s the speed is above 10 % of its peak. Time: Sudden is brief, Sustained "
                       "lingers (Laban 1947; EMOTE sets a stroke's duration by Time, Chi et al. 2000).",
    "Relative Peak Speed": "log(peak |v| / extent), 1/s. Time: urgency, the extent covered per second "
                           "(Samadani et al. 2013 rate Time by velocity and acceleration).",
    "Relative Mean Speed": "log(mean |v| / extent) while moving, 1/s. Time (as above).",
    "Speed Change Rate": "log(RMS |a| / RMS |v|), 1/s: how fast speed changes. Time: Sudden has large "
                         "accelerations (Samadani et al. 2013: Time = acceleration magnitude; Fdili "
                         "Alaoui et al. 2017: Sudden = acceleration peaks).",
    "Jerk Rate": "log(RMS |j| / RMS |a|), 1/s. Time: Sudden movement is impulsive, its jerk high "
                 "(thesis §4.3; Fdili Alaoui et al. 2017 compute Time from jerk).",
    "Onset Time": "log s from the start of the movement to half its peak speed. Time: the impulse at "
                  "the start of a Sudden movement (thesis §4.3; EMOTE's inflection time t_i).",
    "Peak Stroke Width": "log s around the fastest moment that the speed stays above half its peak. "
                         "Time: a Sudden stroke is brief whatever else the take holds (EMOTE times each "
                         "stroke; thesis §5.4.3 Time shortens the execution stroke).",
    "Peak Rise Time": "log s from the last rest (speed under 20 % of the peak) before the fastest moment "
                      "to it. Time: the impulse of a Sudden stroke (thesis §4.3; EMOTE's t_i).",
    "Peak Fall Time": "log s from the fastest moment to the next rest. Time (brief), and Weight: a "
                      "Strong stroke stops short (impact), a Light one lands softly.",
    "Peak Energy Ratio": "log(max |v|² / mean |v|²) while moving. Weight: Strong concentrates kinetic "
                         "energy in a peak (Samadani et al. 2013 and Fdili Alaoui et al. 2017 take "
                         "Weight as the peak kinetic energy; relative to the mean it is size-free).",
    "Peak Accel Ratio": "log(max |a| / mean |a|). Weight: Strong exerts force in bursts; Light keeps "
                        "acceleration low and even (Bernstein et al. 2015: Strong = high peak "
                        "acceleration; force = mass × acceleration).",
    "Peak Jerk Ratio": "log(max |j| / mean |j|). Weight: the impulsive change of force of a Strong "
                       "stroke (Bernstein et al. 2015; Larboulette & Gibet 2015, jerk as impact).",
    "Impact": "log(largest deceleration / mean |d|v|/dt|). Weight: a Strong stroke ends in an impact, "
              "a sharp stop (Laban 1947; EMOTE's overshoot v1 for Strong; Larboulette & Gibet 2015).",
    "Stop Sharpness": "log(largest deceleration / largest acceleration) of the speed. Weight: Strong "
                      "brakes harder than it starts; Light lands softly (buoyant; Laban & Lawrence "
                      "1947).",
    "Speed Variation": "std |v| / mean |v| while moving. Weight: Light is delicate and even; Strong "
                       "varies speed with force (thesis §5.4.3 Weight amplifies speed variations).",
    "Energy Spread": "share of ∫|v|² dt spent in the busiest fifth of the time. Weight: Strong "
                     "concentrates energy, Light spreads it (Samadani et al. 2013; Fdili Alaoui 2017).",
    "Accel Quantile Ratio": "log(95th percentile |a| / median |a|). Weight: acceleration peaks against "
                            "the movement's own typical acceleration (robust to a lone outlier).",
    "Light Glide": "log(RMS |a| · active duration / RMS |v|): acceleration relative to speed, the "
                   "movement's own time-scale removed. Weight: Light is buoyant, low acceleration "
                   "for its speed (Laban & Lawrence 1947; Chi et al. 2000).",
    "Stroke Rate": "log(1 + strokes per second): speed peaks above 30 % of its fast speed, apart from "
                   "each other. Time (Sudden repeats quick strokes) and Weight (Strong phrases "
                   "accents; Fdili Alaoui et al. 2017).",
    # per stroke (a speed peak between the speed minima around it, see _stroke_table), averaged
    # over the strokes weighted by their kinetic energy ∫|v|² dt, so the movement's main strokes
    # count and a wobble does not
    "Stroke Duration": "log s a stroke (speed minimum to speed minimum) takes to cover the middle 80 % "
                       "of its length. Time: EMOTE sets Time by each stroke's duration (Chi et al. "
                       "2000); Sudden is brief, Sustained lingers (Laban 1947) — a walk's steps, a "
                       "wave's swings alike, however far the body travels.",
    "Stroke Rise": "log s a stroke takes from 10 % to 50 % of its length. Time: the impulsive onset of "
                   "a Sudden stroke (EMOTE's inflection time t_i, Chi et al. 2000; thesis §4.3).",
    "Stroke Peakedness": "log(peak |v| · T / L) of a stroke of duration T and length L: 1 for an even "
                         "speed, 1.875 for a minimum-jerk stroke, more when the energy is packed in a "
                         "peak. Weight: Strong concentrates kinetic energy (Samadani et al. 2013, Fdili "
                         "Alaoui et al. 2017: Weight as peak kinetic energy), Light spreads it. Free of "
                         "size and of tempo (T and L of the stroke itself).",
    "Stroke Peak Accel": "log(max |a| · T / peak |v|) in a stroke: peak acceleration relative to what "
                         "the stroke's speed and duration need. Weight: Strong exerts force in bursts "
                         "(Bernstein et al. 2015: Strong = high peak acceleration; force = mass × "
                         "acceleration); Light is buoyant, low acceleration for its speed (Laban & "
                         "Lawrence 1947; Chi et al. 2000). Free of size and tempo.",
    "Stroke Impact": "log(largest deceleration after the peak · T / peak |v|): how sharply a stroke "
                     "stops. Weight: a Strong stroke ends in an impact, a sharp deceleration at the "
                     "stroke's end (Laban 1947; Larboulette & Gibet 2015; EMOTE's overshoot for "
                     "Strong, Chi et al. 2000); a Light one lands softly.",
    "Stroke Jerk": "log(∫|j|² dt · T⁵ / L²) of a stroke: the dimensionless jerk (Hogan & Sternad 2009) "
                   "— 720 for a minimum-jerk stroke, less once low-passed. Weight: the impulsive changes of force of a "
                   "Strong stroke (Bernstein et al. 2015; Larboulette & Gibet 2015, jerk as impact); "
                   "Light is smooth. Free of size and tempo.",
    "Stroke Brake Ratio": "log(largest deceleration / largest acceleration of the speed) in a stroke. "
                          "Weight: Strong brakes harder than it starts (impact), Light settles "
                          "(Laban & Lawrence 1947).",
}
"""Each Effort feature and its justification. The sources:
Laban & Lawrence (1947) Effort; Chi, Costa, Zhao & Badler (2000) "The EMOTE model for effort
and shape", SIGGRAPH; Samadani, Burton, Gorbet & Kulić (2013) "Laban effort and shape
analysis of affective hand and arm movements", ACII; Bernstein, Shafir, Tsachor, Studd &
Schuster (2015) "Multitask learning for Laban movement analysis", MOCO; Larboulette & Gibet
(2015) "A review of computable expressive descriptors of human motion", MOCO; Fdili Alaoui,
Françoise, Schiphorst, Studd & Bevilacqua (2017) "Seeing, sensing and recognizing Laban
movement qualities", CHI; Hogan & Sternad (2009) "Sensitivity of smoothness measures to
movement duration, amplitude, and arrests", Journal of Motor Behavior 41(6).

What was measured when these were checked against the two real-motion procedures (the
EMOTE-style timing and the stylisation operators, both this project's): the measures of
energy concentration ("Stroke Peakedness", "Peak Energy Ratio", "Energy Spread", "Speed
Variation") separate Strong from Light in both, while the force and impact measures ("Stroke
Peak Accel", "Stroke Impact", "Stroke Jerk", "Impact", …) barely do (areas under the ROC
curve 0.5–0.7) — both procedures make Strong by packing a stroke's energy into its peak (EMOTE
by the time exponent, the operators by speed ∝ V^(α·L_w)), which energy concentration
mirrors. The force measures are also the ones a tracker's absolute noise disturbs at a
figurine's size. That Weight reads as energy concentration here is therefore partly the
procedures' definition; motion capture of people performing Strong and Light may differ."""

EFFORT_NAMES: tuple[str, ...] = tuple(EFFORT_SOURCES)


def effort_signal(t: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """The segment on the fixed grid: ``(grid, v, a, j, dt)`` — velocity, acceleration and jerk
    (n, 3) of the cubic spline through ``p`` low-passed by the EFFORT_SIGMA Gaussian."""
    return _effort_signal(t, p)[:5]


def _effort_signal(t: np.ndarray, p: np.ndarray) -> tuple:
    """:func:`effort_signal` and the spline's points on the grid before the low-pass."""
    t = np.asarray(t, float).ravel()
    p = np.asarray(p, float).reshape(-1, 3)
    duration = float(t[-1] - t[0])
    n = max(MIN_SAMPLES, int(round(duration * EFFORT_RATE)) + 1)
    grid = np.linspace(t[0], t[-1], n)
    dt = duration / (n - 1)
    points = CubicSpline(t, p, axis=0, bc_type="natural")(grid) if len(t) >= 4 else _resample(t, grid, p)
    x = gaussian_filter1d(points - points[0], EFFORT_SIGMA / dt, axis=0, mode="nearest")
    # central differences of the smoothed signal (scipy's derivative-of-Gaussian kernels are
    # truncated and leak a constant offset into the acceleration); at 120 Hz they are within
    # 1 % of the exact derivatives of anything the low-pass lets through
    v = _gradient(x, dt)
    a = _gradient(v, dt)
    j = _gradient(a, dt)
    return grid, v, a, j, dt, points


def _stroke_peaks(speed: np.ndarray) -> np.ndarray:
    """Indices of the speed peaks of at least STROKE_FLOOR of the segment's fast speed (its
    STROKE_TOP quantile) that stand out by a prominence of STROKE_DIP of that floor (a dip
    between strokes, not a wobble); at least the largest. The fast speed, not the peak: with
    the largest peak as the scale, a Sudden wave's one quick raise (3.7 m/s) put its swings
    (1.0-1.6 m/s) under the floor, and the strokes between the floor's peaks ran over several
    swings each (1.1-1.6 s "strokes" in a movement of 0.2 s swings)."""
    from doodle.core.peaks import find_peaks  # scipy.signal's, without its import

    top = _quantiles(speed, (STROKE_TOP,))[0][0]
    padded = np.concatenate([[0.0], speed, [0.0]])  # a movement starting or ending fast still peaks
    peaks, _ = find_peaks(padded, height=STROKE_FLOOR * top, prominence=STROKE_DIP * STROKE_FLOOR * top)
    peaks = np.clip(peaks - 1, 0, len(speed) - 1)
    return peaks if len(peaks) else np.array([int(np.argmax(speed))])


def _strokes(speed: np.ndarray) -> int:
    """How many strokes (:func:`_stroke_peaks`)."""
    return len(_stroke_peaks(speed))


STROKE_REST = 0.1  # a first or last stroke starts / ends where the speed is under this share of its peak
STROKE_SMOOTH = 0.05  # s: the speed is smoothed this much more to find the strokes (not to measure them)
STROKE_CORE = (0.1, 0.5, 0.9)  # shares of a stroke's length: its timing is read where these are reached


def _stroke_table(speed: np.ndarray, acc: np.ndarray, jerk: np.ndarray, dt: float) -> np.ndarray:
    """Per stroke (rows), ``(energy, log T, log rise, log peakedness, log peak accel, log
    impact, log jerk, log brake)`` — see the "Stroke …" entries of :data:`EFFORT_SOURCES`.

    A stroke runs from the speed minimum before a peak of :func:`_stroke_peaks` (or, for the
    first, where the speed last rose past STROKE_REST of the peak) to the one after; the
    peaks and minima are found on the speed smoothed STROKE_SMOOTH more, so that a 30 Hz
    tracker's ripple does not split a stroke. Its timing is read by the distance covered,
    not by speed thresholds, which move with how finely an onset was sampled: its duration
    is the time from 10 % to 90 % of the stroke's length ``L``, its rise from 10 % to 50 %.
    The dimensionless Weight measures use the whole stroke, minimum to minimum (``T``, ``L``):
    a Strong or a Light stroke differs most at its ends."""
    n = len(speed)
    smooth = gaussian_filter1d(speed, STROKE_SMOOTH / dt, mode="nearest") if n > 1 else speed
    peaks = _stroke_peaks(smooth)
    tangential = _gradient(speed, dt) if n > 1 else np.zeros(n)
    rows = []
    eps = 1e-12
    for i, k in enumerate(peaks):
        if i == 0:
            low = np.flatnonzero(smooth[: k + 1] <= STROKE_REST * smooth[k])
            a = int(low[-1]) if len(low) else 0
        else:
            a = int(peaks[i - 1] + np.argmin(smooth[peaks[i - 1]: k + 1]))
        if i == len(peaks) - 1:
            low = np.flatnonzero(smooth[k:] <= STROKE_REST * smooth[k])
            b = int(k + low[0]) if len(low) else n - 1
        else:
            b = int(k + np.argmin(smooth[k: peaks[i + 1] + 1]))
        if b - a < 2:
            continue
        s = slice(a, b + 1)
        v = speed[s]
        arc = np.concatenate([[0.0], np.cumsum(0.5 * (v[1:] + v[:-1]))]) * dt
        length = float(arc[-1])
        if length <= TINY:
            continue
        t0, tm, t1 = np.interp(np.array(STROKE_CORE) * length, arc, np.arange(len(v)) * dt)
        T = (b - a) * dt
        vp = float(v.max())
        kk = int(np.argmax(v))
        brake = max(float(-tangential[a + kk: b + 1].min()), eps)
        push = max(float(tangential[a: a + kk + 1].max()), eps)
        rows.append([float(np.sum(v**2)) * dt, math.log(max(t1 - t0, dt)), math.log(max(tm - t0, dt)),
                     math.log(vp * T / length), math.log(float(acc[s].max()) * T / vp + eps), math.log(brake * T / vp),
                     math.log(float(np.sum(jerk[s] ** 2)) * dt * T**5 / length**2 + eps), math.log(brake / push)])
    return np.array(rows).reshape(-1, 8)


def effort_features(t: np.ndarray, p: np.ndarray) -> np.ndarray:
    """The (len(EFFORT_NAMES),) Effort features of a segment, all finite; unchanged by a
    uniform scaling of ``p``, a translation or rotation, and the sampling rate (30–144 Hz)."""
    t = np.asarray(t, float).ravel()
    p = np.asarray(p, float).reshape(-1, 3)
    if len(t) < 2 or not t[-1] > t[0]:
        return np.zeros(len(EFFORT_NAMES))
    grid, v, a, j, dt, points = _effort_signal(t, p)
    speed, acc, jerk = _norm(v), _norm(a), _norm(j)
    top = float(speed.max())
    if top <= TINY:
        return np.zeros(len(EFFORT_NAMES))
    moving = np.flatnonzero(speed >= ACTIVE * top)
    lo, hi = int(moving[0]), int(moving[-1]) + 1
    if hi - lo < 3:
        lo, hi = max(0, lo - 1), min(len(speed), hi + 1)
    sp, ac, je = speed[lo:hi], acc[lo:hi], jerk[lo:hi]
    pts = points[lo:hi]  # the spline (or the line) through p on the active part of the grid: made once
    extent = max(2.0 * float(np.max(_norm(pts - pts.mean(axis=0)))), TINY)
    active = (hi - lo) * dt
    tangential = _gradient(sp, dt) if len(sp) > 1 else np.zeros(1)
    mean_tan = max(float(np.abs(tangential).mean()), TINY)
    rms_v, rms_a = float(np.sqrt(np.mean(sp**2))), float(np.sqrt(np.mean(ac**2)))
    rms_j = float(np.sqrt(np.mean(je**2)))
    onset = int(np.argmax(sp >= 0.5 * top))
    k = int(np.argmax(sp))
    above = sp >= 0.5 * top
    left = k - (int(np.argmin(above[k::-1])) if not above[k::-1].all() else k + 1) + 1
    right = k + (int(np.argmin(above[k:])) if not above[k:].all() else len(sp) - k)
    rest = sp <= 0.2 * top
    rise = k - (k - int(np.argmax(rest[k::-1])) if rest[: k + 1].any() else 0)
    fall = (int(np.argmax(rest[k:])) if rest[k:].any() else len(sp) - 1 - k)
    (p95,), median_acc = _quantiles(ac, (0.95,))
    energy = np.sort(sp**2)[::-1]
    busiest = max(1, int(round(0.2 * len(energy))))
    eps = 1e-12
    feats = [
        math.log(active),
        math.log(top / extent),
        math.log(float(sp.mean()) / extent + eps),
        math.log(rms_a / rms_v + eps),
        math.log(rms_j / max(rms_a, eps) + eps),
        math.log(max(onset * dt, dt)),
        math.log(max(right - left, 1) * dt),
        math.log(max(rise, 1) * dt),
        math.log(max(fall, 1) * dt),
        math.log(top**2 / float(np.mean(sp**2))),
        math.log(float(ac.max()) / max(float(ac.mean()), eps) + eps),
        math.log(float(je.max()) / max(float(je.mean()), eps) + eps),
        math.log(max(float(-tangential.min()), eps) / mean_tan + eps),
        math.log((max(float(-tangential.min()), eps) + eps) / (max(float(tangential.max()), eps) + eps)),
        float(sp.std() / sp.mean()),
        float(energy[:busiest].sum() / energy.sum()),
        math.log((p95 + eps) / (median_acc + eps)),
        math.log(rms_a * active / rms_v + eps),
        math.log1p(_strokes(sp) / active),
    ]
    table = _stroke_table(sp, ac, je, dt)
    if len(table):
        w = table[:, 0] / max(float(table[:, 0].sum()), 1e-300)
        feats += list(w @ table[:, 1:])
    else:
        feats += [math.log(active), math.log(active), 0.0, 0.0, 0.0, 0.0, 0.0]
    return np.nan_to_num(np.array(feats, float), nan=0.0, posinf=50.0, neginf=-50.0)
