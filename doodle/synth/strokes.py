"""Synthetic spatial motion doodles: a seeded, human-like performer for tests and examples.

A performer holds a figurine (a tracked controller) and plays a sequence of *strokes*: a
translation along a direction of the figurine's own frame (``"T"``), a rotation about an axis
of its own frame (``"R"``) or a pause (``"S"``). Directions are given in the figurine's local
frame at the start of the stroke (+x LEFT, +y UP, +z FRONT), like the Segmenter's tokens
(``T_Z`` forward, ``T_N_X_Y`` right-and-up, ``R_Y`` a turn to the left about the up axis…), so
a stroke list is a ground-truth token string. World frame and quaternions follow SPEC
"Conventions": right-handed, +y up, scalar-last ``(x, y, z, w)`` world-from-figurine.

Models, and where they come from
--------------------------------
* **Stroke profile — minimum jerk.** Every translation and rotation follows the
  minimum-jerk profile ``s(τ) = 10τ³ − 15τ⁴ + 6τ⁵`` over its duration (Flash & Hogan 1985,
  "The coordination of arm movements: an experimentally confirmed mathematical model",
  J. Neurosci. 5(7):1688–1703): the smooth, bell-shaped velocity of unconstrained human
  point-to-point reaching. A translation moves the figurine by ``amplitude·scale`` metres
  along its local direction rotated into the world by the orientation at the stroke's start;
  a rotation is body-frame, ``q(τ) = q_start · exp(axis · amplitude · s(τ))``.
* **Variability.** A person never repeats a stroke exactly: each stroke's duration and
  amplitude are multiplied by a uniform factor in ``1 ± vary`` (default ±10 %).
* **Physiological tremor.** Healthy hands tremble at 8–12 Hz with sub-millimetre amplitude
  (Elble & Koller, *Tremor*, Johns Hopkins 1990; McAuley & Marsden 2000, "Physiological and
  pathological tremors and rhythmic central motor control", Brain 123:1545–1567). Modelled
  as a sum of 2–3 sinusoids at random frequencies in 8–12 Hz, random directions and phases,
  of total amplitude ``tremor`` metres on position (default 0.5 mm) and ``tremor/0.1``
  radians on orientation (the hand's ~0.1 m lever arm).
* **Drift.** A slow wander of the hand: 2 sinusoids at 0.02–0.08 Hz, total amplitude
  ``drift`` metres (default 3 mm), zero at the start.
* **Orientation wobble.** A hand translating a figurine does not hold it perfectly rigid:
  during each translation stroke the figurine tilts about a random local axis by at most
  ``wobble`` radians (default ≤ 0.03, always ≤ 0.05 unless asked) with a smooth bump
  ``16τ²(1−τ)²`` that is zero, with zero slope, at both ends — so it never accumulates and
  the stroke adds no net rotation. No other rotation happens outside ``R`` strokes.
* **Tracking noise.** Lighthouse (HTC Vive) tracking is sub-millimetre when static (Niehorster,
  Li & Lappe 2017, "The accuracy and precision of position and orientation tracking in the
  HTC Vive virtual reality system for scientific research", i-Perception 8(3); Borges et al.
  2018, "HTC Vive: analysis and accuracy improvement", IROS). Modelled as white Gaussian
  noise of std ``noise`` metres per position axis (default 0.3 mm) and ``noise/0.1`` radians
  per rotation-vector axis.
* **Sample clock.** A device delivers samples at a nominal rate with small timing jitter:
  times are ``i/rate`` plus uniform jitter of ±``jitter/rate`` (``jitter`` < 0.5 keeps them
  strictly increasing), with ``t[0] = 0``. The motion is a continuous function of time and
  is evaluated at those jittered times, so positions and times are consistent.

``scale`` stands for a uniformly scaled performer: it multiplies translation amplitudes,
position tremor, position noise and drift. Angles (rotation amplitudes, orientation tremor,
noise and wobble) do not scale.

Everything is seeded (``numpy.random.default_rng`` streams spawned from one
``SeedSequence(seed)``), vectorised over samples, and deterministic for a seed: a one-hour
doodle at 90 Hz (324,000 samples) is generated in about a second.

Public API: :class:`Stroke`, :func:`stroke`, :func:`synth_track`, :func:`synth_tracks`,
:func:`synth_doodle`, :func:`lost_tracking`, :func:`resample` (the strokes' profile is
:func:`doodle.core.profiles.min_jerk`).
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.spatial.transform import Rotation, Slerp

from doodle.core.model import Doodle, Track
from doodle.core.profiles import ORIENTATION_LEVER, min_jerk

__all__ = [
    "Stroke",
    "stroke",
    "synth_track",
    "synth_tracks",
    "synth_doodle",
    "lost_tracking",
    "resample",
    "DEFAULT_T_AMPLITUDE",
    "DEFAULT_R_AMPLITUDE",
]

DEFAULT_T_AMPLITUDE = 0.10  # metres
DEFAULT_R_AMPLITUDE = 1.2  # radians

_AXES = "XYZ"


@dataclass(frozen=True)
class Stroke:
    """One stroke of a synthetic performance.

    ``direction`` is in the figurine's local frame at the stroke's start (normalised by the
    generator); for ``"R"`` it is the rotation axis (right-hand rule); ignored for ``"S"``.
    """

    kind: str  # "T" translation, "R" rotation, "S" still (a pause)
    direction: tuple[float, float, float]
    duration: float  # seconds
    amplitude: float = 0.0  # metres for T, radians for R (0 for S)

    @property
    def token(self) -> str:
        """The Segmenter token this stroke should produce (``T_STILL`` for a pause).

        Each local axis contributes its sign when ``|dot(d̂, axis)| ≥ 0.5`` (SPEC Segmenter 5).
        """
        if self.kind == "S":
            return "T_STILL"
        d = np.asarray(self.direction, dtype=float)
        nrm = float(np.linalg.norm(d))
        if nrm == 0.0 or not np.isfinite(nrm):
            raise ValueError(f"stroke {self!r}: zero or non-finite direction")
        d = d / nrm * (1.0 if self.amplitude >= 0 else -1.0)
        parts = [self.kind]
        for c, axis in zip(d, _AXES):
            if abs(c) >= 0.5 - 1e-12:
                parts.append(("N_" if c < 0 else "") + axis)
        return "_".join(parts)


_TOKEN_RE = re.compile(r"^(T|R)((?:_(?:N_)?[XYZ])+)$")


def stroke(token: str, duration: float, amplitude: float | None = None) -> Stroke:
    """A stroke from a token name: ``"T_Z"``, ``"T_N_X_Y"``, ``"R_N_Z"``, ``"T_STILL"``…

    Axes appear in x, y, z order, each at most once; ``N_`` marks a negative axis. The
    direction is the normalised sum of the signed unit axes. Default amplitudes: 0.10 m for
    ``T``, 1.2 rad for ``R``. An unknown or malformed token raises ``ValueError`` naming it.
    """
    if not isinstance(token, str):
        raise ValueError(f"stroke token {token!r} is not a string")
    if not (duration > 0 and math.isfinite(duration)):
        raise ValueError(f"stroke {token!r}: duration must be positive and finite, got {duration!r}")
    if token in ("T_STILL", "STILL", "S"):
        if amplitude not in (None, 0, 0.0):
            raise ValueError(f"stroke {token!r}: a still stroke has no amplitude (got {amplitude!r})")
        return Stroke("S", (0.0, 0.0, 0.0), float(duration), 0.0)
    m = _TOKEN_RE.match(token)
    if not m:
        raise ValueError(f"unknown or malformed stroke token {token!r} (expected e.g. T_Z, T_N_X_Y, R_Y, T_STILL)")
    kind, rest = m.group(1), m.group(2)
    parts = rest.split("_")[1:]
    vec = [0.0, 0.0, 0.0]
    seen: list[int] = []
    sign = 1.0
    for part in parts:
        if part == "N":
            sign = -1.0
            continue
        i = _AXES.index(part)
        if seen and i <= seen[-1]:
            raise ValueError(f"malformed stroke token {token!r}: axes must appear once, in x, y, z order")
        seen.append(i)
        vec[i] = sign
        sign = 1.0
    d = np.asarray(vec) / math.sqrt(len(seen))
    if amplitude is None:
        amplitude = DEFAULT_T_AMPLITUDE if kind == "T" else DEFAULT_R_AMPLITUDE
    if not math.isfinite(amplitude):
        raise ValueError(f"stroke {token!r}: amplitude must be finite, got {amplitude!r}")
    return Stroke(kind, (float(d[0]), float(d[1]), float(d[2])), float(duration), float(amplitude))


# --------------------------------------------------------------------------- internals


def _check_stroke(s: Stroke, k: int) -> np.ndarray:
    if not isinstance(s, Stroke):
        raise ValueError(f"stroke {k}: expected a Stroke, got {s!r}")
    if s.kind not in ("T", "R", "S"):
        raise ValueError(f"stroke {k}: unknown kind {s.kind!r} (expected 'T', 'R' or 'S')")
    if not (s.duration > 0 and math.isfinite(s.duration)):
        raise ValueError(f"stroke {k}: duration must be positive and finite, got {s.duration!r}")
    if s.kind == "S":
        return np.zeros(3)
    if not math.isfinite(s.amplitude):
        raise ValueError(f"stroke {k}: amplitude must be finite, got {s.amplitude!r}")
    d = np.asarray(s.direction, dtype=float).reshape(3)
    nrm = float(np.linalg.norm(d))
    if not (nrm > 0 and np.isfinite(nrm)):
        raise ValueError(f"stroke {k}: {s.kind} stroke needs a non-zero direction, got {s.direction!r}")
    return d / nrm


@dataclass(frozen=True)
class _Plan:
    """A track's strokes after validation and random perturbation."""

    kinds: np.ndarray  # (m,) '<U1'
    dirs: np.ndarray  # (m, 3) unit local directions / axes
    durations: np.ndarray  # (m,)
    amplitudes: np.ndarray  # (m,) metres (already × scale) or radians


def _plan(strokes: Sequence[Stroke], rng: np.random.Generator, vary: float, scale: float) -> _Plan:
    strokes = list(strokes)
    if not strokes:
        raise ValueError("synthetic track needs at least one stroke")
    m = len(strokes)
    dirs = np.array([_check_stroke(s, k) for k, s in enumerate(strokes)]).reshape(m, 3)
    kinds = np.array([s.kind for s in strokes])
    dur_f = 1.0 + rng.uniform(-vary, vary, m)
    amp_f = 1.0 + rng.uniform(-vary, vary, m)
    durations = np.array([s.duration for s in strokes], dtype=float) * dur_f
    amps = np.array([s.amplitude for s in strokes], dtype=float) * amp_f
    amps[kinds == "S"] = 0.0
    amps[kinds == "T"] *= scale
    return _Plan(kinds, dirs, durations, amps)


def _pad(plan: _Plan, total: float) -> _Plan:
    extra = total - float(plan.durations.sum())
    if extra <= 1e-12:
        return plan
    return _Plan(
        np.append(plan.kinds, "S"),
        np.vstack([plan.dirs, np.zeros((1, 3))]),
        np.append(plan.durations, extra),
        np.append(plan.amplitudes, 0.0),
    )


def _clock(duration: float, rate: float, jitter: float, rng: np.random.Generator) -> np.ndarray:
    n = int(math.floor(duration * rate + 1e-9)) + 1
    t = np.arange(n, dtype=float)
    if n > 1 and jitter > 0:
        t[1:] += rng.uniform(-jitter, jitter, n - 1)
    return t / rate


def _unit_vectors(rng: np.random.Generator, k: int) -> np.ndarray:
    v = rng.normal(size=(k, 3))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _sines(t: np.ndarray, rng: np.random.Generator, total: float, fmin: float, fmax: float,
           count: int, zero_start: bool = False) -> np.ndarray:
    """(n, 3) sum of ``count`` sinusoids in random directions; peak norm ≤ ``total``."""
    if total == 0.0:
        return np.zeros((len(t), 3))
    f = rng.uniform(fmin, fmax, count)
    phase = rng.uniform(0.0, 2 * np.pi, count)
    w = rng.uniform(0.5, 1.0, count)
    w = w / w.sum() * total
    u = _unit_vectors(rng, count)
    s = np.sin(2 * np.pi * f[None, :] * t[:, None] + phase[None, :])
    if zero_start:
        s = s - np.sin(phase)[None, :]
        w = w / 2.0  # keeps the peak within `total`
    return (s * w[None, :]) @ u


def _continuous(q: np.ndarray) -> np.ndarray:
    """Flip quaternion signs so consecutive ones have a non-negative dot product."""
    if len(q) < 2:
        return q
    dots = np.einsum("ij,ij->i", q[1:], q[:-1])
    flips = np.concatenate([[1.0], np.where(dots < 0, -1.0, 1.0)])
    return q * np.cumprod(flips)[:, None]


def _render(plan: _Plan, t: np.ndarray, rng: np.random.Generator, *, name: str,
            start_p, start_q, tremor: float, noise: float, drift: float, wobble: float,
            scale: float) -> tuple[Track, list[tuple[int, int]]]:
    n = len(t)
    m = len(plan.kinds)
    p0 = np.asarray(start_p, dtype=float).reshape(3)
    q0 = np.asarray(start_q, dtype=float).reshape(4)
    if not np.all(np.isfinite(p0)):
        raise ValueError(f"track {name}: start_p must be finite, got {start_p!r}")
    qn = float(np.linalg.norm(q0))
    if not (qn > 0 and np.isfinite(qn)):
        raise ValueError(f"track {name}: start_q must be a non-zero quaternion (x, y, z, w), got {start_q!r}")
    q0 = q0 / qn

    # Stroke boundaries on the clock and each sample's stroke.
    bounds = np.concatenate([[0.0], np.cumsum(plan.durations)])
    k = np.searchsorted(bounds[1:-1], t, side="right")
    starts = np.searchsorted(t, bounds[:-1], side="left")
    ends = np.append(starts[1:], n)
    ranges = [(int(a), int(b)) for a, b in zip(starts, ends)]

    # Pose at each stroke's start (a loop over strokes, not samples).
    is_t = plan.kinds == "T"
    is_r = plan.kinds == "R"
    P = np.empty((m, 3))
    Q = np.empty((m, 4))
    wdir = np.zeros((m, 3))  # world displacement of each T stroke
    rotvec = np.zeros((m, 3))  # local rotation vector of each R stroke
    rotvec[is_r] = plan.dirs[is_r] * plan.amplitudes[is_r, None]
    p_cur = p0.copy()
    r_cur = Rotation.from_quat(q0)
    for j in range(m):
        P[j] = p_cur
        Q[j] = r_cur.as_quat()
        if is_t[j]:
            wdir[j] = r_cur.apply(plan.dirs[j]) * plan.amplitudes[j]
            p_cur = p_cur + wdir[j]
        elif is_r[j]:
            r_cur = r_cur * Rotation.from_rotvec(rotvec[j])

    tau = np.clip((t - bounds[k]) / plan.durations[k], 0.0, 1.0)
    s = min_jerk(tau)

    # Nominal motion.
    p = P[k] + s[:, None] * wdir[k]
    main = s[:, None] * rotvec[k]

    # Orientation wobble during translation strokes: smooth bump, zero at both ends.
    wob_axes = _unit_vectors(rng, m)
    wob_amp = rng.uniform(0.3, 1.0, m) * wobble * is_t
    bump = 16.0 * tau**2 * (1.0 - tau) ** 2
    small = (bump * wob_amp[k])[:, None] * wob_axes[k]

    # Human and device imperfections.
    ang_tremor = tremor / ORIENTATION_LEVER
    ang_noise = noise / ORIENTATION_LEVER
    p = p + _sines(t, rng, drift * scale, 0.02, 0.08, 2, zero_start=True)
    p = p + _sines(t, rng, tremor * scale, 8.0, 12.0, int(rng.integers(2, 4)))
    small = small + _sines(t, rng, ang_tremor, 8.0, 12.0, int(rng.integers(2, 4)))
    if noise > 0:
        p = p + rng.normal(0.0, noise * scale, (n, 3))
        small = small + rng.normal(0.0, ang_noise, (n, 3))

    rot = Rotation.from_quat(Q[k]) * Rotation.from_rotvec(main) * Rotation.from_rotvec(small)
    q = rot.as_quat()
    # Start in the hemisphere of start_q, then keep signs continuous.
    if n and np.dot(q[0], q0) < 0:
        q[0] = -q[0]
    q = _continuous(q)
    track = Track(name=name, t=t.copy(), p=p, q=q, valid=np.ones(n, dtype=bool))
    return track, ranges


def _check_common(rate: float, jitter: float, tremor: float, noise: float, drift: float,
                  wobble: float, vary: float, scale: float) -> None:
    if not (rate > 0 and math.isfinite(rate)):
        raise ValueError(f"rate must be positive and finite, got {rate!r}")
    if not (0.0 <= jitter < 0.5):
        raise ValueError(f"jitter must be in [0, 0.5) sample periods, got {jitter!r}")
    if not (0.0 <= vary < 1.0):
        raise ValueError(f"vary must be in [0, 1), got {vary!r}")
    if not (scale > 0 and math.isfinite(scale)):
        raise ValueError(f"scale must be positive and finite, got {scale!r}")
    for label, v in (("tremor", tremor), ("noise", noise), ("drift", drift), ("wobble", wobble)):
        if not (v >= 0 and math.isfinite(v)):
            raise ValueError(f"{label} must be non-negative and finite, got {v!r}")


def _per_track(value, name: str, default):
    if isinstance(value, Mapping):
        return value.get(name, default)
    return value


# --------------------------------------------------------------------------- public API


def synth_tracks(
    tracks: Mapping[str, Sequence[Stroke]],
    rate: float = 90.0,
    seed: int = 0,
    *,
    start_p=(0.0, 0.0, 0.0),
    start_q=(0.0, 0.0, 0.0, 1.0),
    tremor: float = 0.0005,
    noise: float = 0.0003,
    jitter: float = 0.1,
    scale: float = 1.0,
    drift: float = 0.003,
    wobble: float = 0.03,
    vary: float = 0.1,
) -> tuple[list[Track], dict[str, list[tuple[int, int]]]]:
    """Several tracks on one shared jittered clock, with each track's stroke sample ranges.

    Shorter performances are padded with a final still stroke so that all tracks last as
    long as the longest; the pad appears as an extra last range. ``start_p`` / ``start_q``
    may be one value for all tracks or a mapping from track name to value.
    """
    if not isinstance(tracks, Mapping) or not tracks:
        raise ValueError("synth_tracks needs a non-empty mapping of track name -> strokes")
    _check_common(rate, jitter, tremor, noise, drift, wobble, vary, scale)
    names = list(tracks)
    children = np.random.SeedSequence(seed).spawn(1 + len(names))
    clock_rng = np.random.default_rng(children[0])
    rngs = [np.random.default_rng(c) for c in children[1:]]
    plans = [_plan(tracks[nm], rng, vary, scale) for nm, rng in zip(names, rngs)]
    total = max(float(pl.durations.sum()) for pl in plans)
    t = _clock(total, rate, jitter, clock_rng)
    out: list[Track] = []
    ranges: dict[str, list[tuple[int, int]]] = {}
    for nm, pl, rng in zip(names, plans, rngs):
        tr, rg = _render(
            _pad(pl, total), t, rng, name=nm,
            start_p=_per_track(start_p, nm, (0.0, 0.0, 0.0)),
            start_q=_per_track(start_q, nm, (0.0, 0.0, 0.0, 1.0)),
            tremor=tremor, noise=noise, drift=drift, wobble=wobble, scale=scale,
        )
        out.append(tr)
        ranges[nm] = rg
    return out, ranges


def synth_track(
    strokes: Sequence[Stroke],
    rate: float = 90.0,
    seed: int = 0,
    name: str = "c0",
    start_p=(0.0, 0.0, 0.0),
    start_q=(0.0, 0.0, 0.0, 1.0),
    tremor: float = 0.0005,
    noise: float = 0.0003,
    jitter: float = 0.1,
    scale: float = 1.0,
    *,
    drift: float = 0.003,
    wobble: float = 0.03,
    vary: float = 0.1,
) -> tuple[Track, list[tuple[int, int]]]:
    """One synthetic track and, per stroke, the sample range ``[start, end)`` it covers.

    The ranges partition ``range(len(track))``: sample i belongs to the stroke whose
    (perturbed) time span ``[b_k, b_{k+1})`` contains ``t[i]``; samples after the last
    stroke's nominal end (clock jitter) belong to the last stroke. A range may be empty for
    a stroke shorter than a sample period. Set ``tremor = noise = drift = wobble = vary =
    jitter = 0`` for an exact, noise-free performance.
    """
    tracks, ranges = synth_tracks(
        {name: strokes}, rate, seed, start_p=start_p, start_q=start_q, tremor=tremor,
        noise=noise, jitter=jitter, scale=scale, drift=drift, wobble=wobble, vary=vary,
    )
    return tracks[0], ranges[name]


def synth_doodle(
    tracks: Mapping[str, Sequence[Stroke]] | Sequence[Stroke],
    rate: float = 90.0,
    seed: int = 0,
    device: str = "synthetic",
    **kw,
) -> Doodle:
    """A synthetic :class:`Doodle`: one track per key of ``tracks`` (or one track ``name``,
    default ``"c0"``, from a plain stroke list), all on the same jittered clock.

    Keyword arguments are those of :func:`synth_tracks`. A plain list gives the same track
    as :func:`synth_track` with the same seed.
    """
    if not isinstance(tracks, Mapping):
        tracks = {kw.pop("name", "c0"): list(tracks)}
    elif "name" in kw:
        raise ValueError("synth_doodle: 'name' applies to a plain stroke list, not a mapping")
    out, _ = synth_tracks(tracks, rate, seed, **kw)
    return Doodle(tuple(out), float(rate), device, "<synthetic>")


def lost_tracking(track: Track, start_s: float, end_s: float) -> Track:
    """A copy of ``track`` with lost tracking for ``start_s ≤ t ≤ end_s``: valid False, NaN poses."""
    if not end_s >= start_s:
        raise ValueError(f"lost_tracking: end {end_s!r} before start {start_s!r}")
    mask = (track.t >= start_s) & (track.t <= end_s)
    p = track.p.copy()
    q = track.q.copy()
    valid = track.valid.copy()
    p[mask] = np.nan
    q[mask] = np.nan
    valid[mask] = False
    return Track(track.name, track.t.copy(), p, q, valid, track.role, track.serial)


def _resample_times(t0: float, t1: float, rate: float, seed: int | None, jitter: float) -> np.ndarray:
    n = int(math.floor((t1 - t0) * rate + 1e-9)) + 1
    u = np.arange(n, dtype=float)
    if seed is not None and jitter > 0 and n > 1:
        u[1:] += np.random.default_rng(seed).uniform(-jitter, jitter, n - 1)
    t = t0 + u / rate
    return np.minimum(t, t1)


def _resample_track(track: Track, tn: np.ndarray) -> Track:
    n = len(tn)
    t = track.t
    good = track.valid & np.all(np.isfinite(track.p), axis=1) & np.all(np.isfinite(track.q), axis=1)
    # A new sample is valid when both original samples around it are.
    hi = np.clip(np.searchsorted(t, tn, side="left"), 0, len(t) - 1)
    lo = np.clip(np.searchsorted(t, tn, side="right") - 1, 0, len(t) - 1)
    valid = good[lo] & good[hi]
    p = np.full((n, 3), np.nan)
    q = np.full((n, 4), np.nan)
    idx = np.flatnonzero(good)
    if len(idx) == 1:
        p[valid] = track.p[idx[0]]
        q[valid] = track.q[idx[0]]
    elif len(idx) >= 2:
        tg = t[idx]
        for a in range(3):
            p[valid, a] = np.interp(tn[valid], tg, track.p[idx, a])
        slerp = Slerp(tg, Rotation.from_quat(track.q[idx]))
        q[valid] = slerp(np.clip(tn[valid], tg[0], tg[-1])).as_quat()
        qv = q[valid]
        if len(qv):
            # Keep the sign of the nearest original sample, then continuity.
            ref = track.q[lo[valid]]
            qv[np.einsum("ij,ij->i", qv, ref) < 0] *= -1.0
            q[valid] = _continuous(qv)
    return Track(track.name, tn.copy(), p, q, valid, track.role, track.serial)


def resample(track: Track | Doodle, rate: float, seed: int | None = None, jitter: float = 0.1):
    """Resample at another rate: linear interpolation for positions, slerp for quaternions.

    New times are uniform, ``t[0] + i/rate`` up to the last original time; with a ``seed``
    they get the synthetic device's clock jitter (±``jitter``/rate, seeded). Invalid samples
    are skipped; a new sample is valid only when the original samples on both sides are.
    A :class:`Doodle` is resampled track by track on one shared clock and gets ``rate``.
    """
    if not (rate > 0 and math.isfinite(rate)):
        raise ValueError(f"resample: rate must be positive and finite, got {rate!r}")
    if not (0.0 <= jitter < 0.5):
        raise ValueError(f"resample: jitter must be in [0, 0.5), got {jitter!r}")
    if isinstance(track, Doodle):
        ref = track.t
        tn = _resample_times(float(ref[0]), float(ref[-1]), rate, seed, jitter)
        return Doodle(tuple(_resample_track(tr, tn) for tr in track.tracks), float(rate),
                      track.device, track.source, dict(track.meta))
    if len(track) == 0:
        raise ValueError(f"resample: track {track.name} is empty")
    tn = _resample_times(float(track.t[0]), float(track.t[-1]), rate, seed, jitter)
    return _resample_track(track, tn)


def perform(tokens: Sequence[str], rate: float = 90.0, seed: int = 0, name: str = "c0",
            stroke_s: float = 0.3, pause_s: float = 0.4, **kw) -> Track:
    """A track performing a token string: one brisk stroke per token (``T_STILL`` a pause).

    Brisk strokes (0.3 s, 0.1 m or 1.2 rad) slow down only for a few samples where they
    join, so the Segmenter reads the string back without stillness in between.
    """
    strokes = [stroke(tok, pause_s if tok in ("T_STILL", "STILL", "S") else stroke_s) for tok in tokens]
    return synth_track(strokes, rate=rate, seed=seed, name=name, **kw)[0]
