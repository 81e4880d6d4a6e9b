"""Effort applied to real neutral movement, and the ways a path can be presented to a classifier.

Effort-labelled data here must not come only from this project's own generator
(:mod:`laban.synth`): a classifier trained and tested on one generator learns the generator.
This module holds a published procedure that turns a *real* neutral path (a hand or the
root of motion capture) into Sudden / Sustained and Strong / Light variants — an
**EMOTE-style timing procedure** — and the presentation of any path at a size and a
sampling rate (:func:`presented`). The other real-motion procedure, the thesis's
stylisation operators (§5.4, ``retarget.stylize``), works on whole skeletons and lives with
the application (``doodle.app.effort_corpus``), which may import both stages.

EMOTE-style timing (Chi, Costa, Zhao & Badler 2000, "The EMOTE model for effort and shape",
SIGGRAPH, §4.2–4.3): EMOTE keeps a movement's *path* (its keypoints) and changes how it is
*timed* through each stroke between keypoints — the stroke's duration, the inflection time
``t_i`` where the velocity peaks, the time exponent ``t_exp`` shaping the velocity curve —
and adds anticipation (a small move back before a stroke) and overshoot (past the goal and
back) to Strong movement. We follow that structure; the coefficients are ours (EMOTE's own
table maps its low-level parameters to all eight Effort elements together and is not
reproduced here):

* keypoints are the path's speed minima (a dip of at least 20 % of the peak speed); a stroke
  is the path between two keypoints, a hold a stroke whose arc length is under 3 % of the
  path's (kept as it is);
* **Time** sets each stroke's duration (Sudden × 0.35–0.55, Sustained × 1.7–2.5, moving
  towards × 1 as the strength falls — but never so short that the path moves faster than real
  hands do, 12 m/s, :data:`doodle.core.profiles.FASTEST`, unless the neutral stroke itself is
  that fast: then as long as it; EMOTE's own timing knew no such bound, and 13 % of its Sudden
  Strong paths here reached 12–21 m/s, training data no performer could give) and its rise
  — the share of the stroke before peak velocity, EMOTE's ``t_i`` (Sudden 0.12–0.22: the
  impulsive onset of thesis §4.3; Sustained 0.40–0.50);
* **Weight** sets the time exponent of the velocity curve ``g = sin²(πτ/2)^t_exp`` on both
  sides of the peak: *Strong* ``t_exp`` 2–3 — the energy concentrated in a sharp peak — with
  an anticipation of 2–4 % of the stroke's length before it and an overshoot of 3–7 %
  braked back to the goal in a tenth of the stroke's time (the impact; EMOTE's ``v0`` and
  ``v1``); *Light* ``t_exp`` 0.3–0.6 — a flat-topped, even, buoyant curve that lands softly.

Progress along each stroke is by arc length (the path is unchanged); orientation follows
the same time warp. Overshoot continues along the stroke's last tangent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doodle.core import quat
from doodle.core.profiles import FASTEST

HOLD = 0.03  # a stroke shorter than this share of the path's arc length is a hold
DIP = 0.2  # a keypoint is a speed minimum this share of the peak speed below its neighbours
RATES = (30.0, 60.0, 90.0, 144.0)  # Hz: the tracking rates every evaluation is made at
NOISE = 0.0003  # m: white tracking noise of a consumer tracker (Niehorster, Li & Lappe 2017)
JITTER = 0.1  # sample clock jitter, as a share of the period


@dataclass(frozen=True, eq=False)
class Effortful:
    """One effort-labelled path: samples, Time (+1 Sudden / −1 Sustained) and Weight (+1
    Strong / −1 Light) — 0 where the procedure did not give the path that Factor —, where it
    came from (``source``: generator, emote, stylize), a group (the performer or the neutral
    clip) for held-out splits, and which path of the clip it is (``role``)."""

    t: np.ndarray
    p: np.ndarray
    q: np.ndarray
    time: int
    weight: int
    source: str
    group: str
    role: str = ""


def _bell(x: np.ndarray) -> np.ndarray:
    """sin²(πx/2) on [0, 1]: 0 → 1 with zero slope at both ends."""
    return np.sin(0.5 * np.pi * np.clip(x, 0.0, 1.0)) ** 2


def _profile(u: np.ndarray, time: int, weight: int, strength: float, rng: np.random.Generator):
    """Progress s(u) along a stroke (arc-length share, u the stroke's time share) and the
    stroke's duration factor; s may leave [0, 1] for anticipation and overshoot."""
    k = strength
    if time > 0:
        factor, rise = np.exp(k * np.log(rng.uniform(0.35, 0.55))), rng.uniform(0.12, 0.22)
    else:
        factor, rise = np.exp(k * np.log(rng.uniform(1.7, 2.5))), rng.uniform(0.40, 0.50)
    rise = 0.5 + k * (rise - 0.5) if time < 0 else 0.45 + k * (rise - 0.45)
    if weight > 0:  # a peaked velocity curve: energy concentrated in the stroke's peak
        texp = 1.0 + k * rng.uniform(1.0, 2.0)
        over, back = k * rng.uniform(0.03, 0.07), k * rng.uniform(0.02, 0.04)
    else:  # flat-topped: even, buoyant
        texp = 1.0 - k * rng.uniform(0.4, 0.7)
        over = back = 0.0
    g = np.where(u < rise, _bell(u / rise) ** texp, _bell((1 - u) / (1 - rise)) ** texp)
    s = np.concatenate([[0.0], np.cumsum(0.5 * (g[1:] + g[:-1]))])
    s = s / s[-1]
    if weight > 0:  # anticipation: a dip back as the stroke starts; overshoot: past the goal at the stop
        s = (1 + over) * s - back * np.sin(np.pi * np.clip(u / 0.15, 0.0, 1.0))
    return s, float(factor), float(over)


def _keypoints(t: np.ndarray, p: np.ndarray) -> list[int]:
    from scipy.ndimage import gaussian_filter1d
    from scipy.signal import find_peaks

    dt = float(np.median(np.diff(t)))
    v = np.linalg.norm(np.gradient(gaussian_filter1d(p, 0.05 / dt, axis=0, mode="nearest"), dt, axis=0), axis=1)
    lows, _ = find_peaks(-v, prominence=DIP * v.max())
    return [0, *[int(i) for i in lows], len(t) - 1]


def emote(t: np.ndarray, p: np.ndarray, q: np.ndarray, time: int, weight: int, rng: np.random.Generator,
          strength: float = 1.0, rate: float = 120.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The neutral path ``(t, p, q)`` performed Sudden (``time`` +1) or Sustained (−1) and
    Strong (``weight`` +1) or Light (−1) by the EMOTE-style timing above, ``strength`` in
    (0, 1]; returned densely sampled at ``rate`` Hz."""
    t = np.asarray(t, float)
    p = np.asarray(p, float)
    q = quat.make_continuous(quat.normalise(np.asarray(q, float)))
    arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    keys = _keypoints(t, p)
    out_t, out_p, out_q = [np.array([0.0])], [p[:1]], [q[:1]]
    clock = 0.0
    for a, b in zip(keys[:-1], keys[1:]):
        length, duration = arc[b] - arc[a], t[b] - t[a]
        if b <= a or duration <= 0:
            continue
        if length < HOLD * max(arc[-1], 1e-12):  # a hold: as it was
            n = max(2, int(round(duration * rate)) + 1)
            tt = np.linspace(t[a], t[b], n)
            out_t.append(clock + (tt[1:] - t[a]))
            out_p.append(np.column_stack([np.interp(tt, t, p[:, k]) for k in range(3)])[1:])
            out_q.append(_interp_q(t, q, tt)[1:])
            clock += duration
            continue
        u = np.linspace(0.0, 1.0, 1024)
        s, factor, over = _profile(u, time, weight, strength, rng)
        new = duration * factor
        fastest = length * float(np.abs(np.gradient(s, u)).max())  # m/s over one second: no faster than people
        new = max(new, min(fastest / FASTEST, duration))
        extra = 0.1 * new if over > 0 else 0.0  # the return after the overshoot
        n = max(3, int(round((new + extra) * rate)) + 1)
        w = np.linspace(0.0, new + extra, n)[1:]
        prog = np.interp(np.minimum(w, new) / new, u, s)
        if extra:  # back from the overshoot to the goal, braking hard
            prog = np.where(w > new, 1.0 + over * (1.0 - _bell((w - new) / extra)), prog)
        target = arc[a] + prog * length
        inside = np.clip(target, arc[a], arc[b])
        tn = np.interp(inside, arc[a:b + 1], t[a:b + 1]) if np.all(np.diff(arc[a:b + 1]) > 0) else \
            np.interp(inside, *_strictly(arc[a:b + 1], t[a:b + 1]))
        pos = np.column_stack([np.interp(tn, t, p[:, k]) for k in range(3)])
        beyond = target - inside  # anticipation (< 0) and overshoot (> 0) continue the stroke's end tangents
        seg_arc, seg_t = _strictly(arc[a:b + 1], t[a:b + 1])  # the directions it leaves and arrives in,
        near = np.interp([seg_arc[0] + 0.05 * length, seg_arc[-1] - 0.05 * length], seg_arc, seg_t)  # rests skipped
        head = np.array([np.interp(near[0], t, p[:, k]) for k in range(3)]) - p[a]
        tail = p[b] - np.array([np.interp(near[1], t, p[:, k]) for k in range(3)])
        head = head / max(np.linalg.norm(head), 1e-12)
        tail = tail / max(np.linalg.norm(tail), 1e-12)
        pos += np.where(beyond[:, None] < 0, beyond[:, None] * head, beyond[:, None] * tail)
        out_t.append(clock + w)
        out_p.append(pos)
        out_q.append(_interp_q(t, q, tn))
        clock += new + extra
    return np.concatenate(out_t), np.concatenate(out_p), quat.normalise(np.concatenate(out_q))


def _strictly(arc: np.ndarray, t: np.ndarray):
    keep = np.concatenate([[True], np.diff(arc) > 0])
    return arc[keep], t[keep]


def _interp_q(t: np.ndarray, q: np.ndarray, at: np.ndarray) -> np.ndarray:
    """Normalised linear interpolation of sign-continuous quaternions (fine at mocap rates)."""
    return quat.normalise(np.column_stack([np.interp(at, t, q[:, k]) for k in range(4)]))


def presented(t: np.ndarray, p: np.ndarray, q: np.ndarray, scale: float, rate: float, rng: np.random.Generator,
              noise: float = NOISE, jitter: float = JITTER) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The path as a tracker would give it: scaled by ``scale`` about its first point (a
    figurine ×0.1–0.2, a person ×1), sampled at ``rate`` Hz with ``jitter`` of the period
    on the clock and ``noise`` metres of white tracking noise (absolute: a tracker's noise
    does not shrink with the figurine), starting at t = 0."""
    from scipy.interpolate import CubicSpline

    t = np.asarray(t, float)
    p = np.asarray(p, float)
    q = quat.make_continuous(quat.normalise(np.asarray(q, float)))
    duration = float(t[-1] - t[0])
    n = max(int(duration * rate), 1) + 1
    g = np.arange(n) / rate
    g[1:-1] += rng.uniform(-jitter, jitter, n - 2) / rate
    g = np.minimum(g, duration)
    g[-1] = duration
    g = np.maximum.accumulate(g)
    keep = np.concatenate([[True], np.diff(g) > 1e-6 / rate])
    g = g[keep]
    x = CubicSpline(t - t[0], p, axis=0)(g)
    x = p[0] + scale * (x - p[0]) + rng.normal(0.0, noise, x.shape) if noise else p[0] + scale * (x - p[0])
    return g, x, _interp_q(t - t[0], q, g)
