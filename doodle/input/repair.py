"""Checks and repairs of raw track samples before segmentation.

Physically impossible samples are lost tracking too (:func:`impossible`, applied by the file
readers through :func:`drop_impossible`, with a warning naming the file, line and column): a
tracked position more than :data:`MAX_RADIUS` from the origin (no tracked space is that
large), or one the hand could only have reached from the samples around it faster than
:data:`MAX_SPEED` (a real hand peaks at 10–15 m/s; the real recordings' fastest step between
samples, jitter included, is about 21 m/s). Such a sample is a tracking glitch, not motion:
kept, one 1000 m spike would be a stroke the Matcher reads as a gesture.

Documented repair for lost tracking (``valid == False``):

* a gap inside the track of at most ``max_gap`` seconds (from the last tracked sample to the
  next) is filled by interpolation — positions linearly, orientations by normalised linear
  interpolation in the shorter direction;
* a longer interior gap is an error naming the track and the time span (trim the doodle or
  raise ``--max-gap``): interpolating seconds of missing motion would invent a stroke;
* untracked samples before the first or after the last tracked one take that sample's pose
  (the figurine reads as still there).

:func:`fill_gaps` is the batch form; :class:`GapFiller` the streaming one, which holds
untracked samples until tracking returns and then releases them, with identical values;
:func:`repaired` applies :func:`fill_gaps` to every track of a doodle, for the stages after
the Segmenter that read the poses themselves (the compiler's path, placement and Effort).
"""

from __future__ import annotations

import warnings

import numpy as np

from doodle.core import quat
from doodle.core.errors import DoodleError, where
from doodle.core.model import Doodle, Track

MAX_RADIUS = 100.0  # m from the origin, per axis: ten times the largest tracked room
MAX_SPEED = 50.0  # m/s between samples: over twice the fastest step of real recordings
SLACK = 0.02  # m: tracking noise allowed on top, so samples close in time need not agree exactly
SHOWN = 5  # lines of impossible samples a warning lists


def impossible(t: np.ndarray, p: np.ndarray, valid: np.ndarray) -> np.ndarray:
    """Which tracked samples are physically impossible (see the module docstring).

    Speeds are judged against the last plausible sample, so a spike is one or a few samples
    flagged, while a jump of tracking to a new place (re-localisation) is flagged only until
    a hand at :data:`MAX_SPEED` could have got there. The judging starts from the longest
    run of samples that agree with each other — motion, not glitches — forwards and back.
    """
    far = valid & ~(np.abs(p) <= MAX_RADIUS).all(axis=1)
    idx = np.flatnonzero(valid & ~far)
    if len(idx) < 2:
        return far
    t, p = t[idx], p[idx]  # plausible-so-far samples, coordinates within ±MAX_RADIUS: no overflow
    fine = np.linalg.norm(np.diff(p, axis=0), axis=1) <= MAX_SPEED * np.diff(t) + SLACK
    if fine.all():
        return far
    edges = np.flatnonzero(np.diff(np.concatenate([[0], fine.astype(np.int8), [0]])))
    runs = edges.reshape(-1, 2)  # [start, end) of runs of agreeing pairs
    anchor = int(runs[np.argmax(runs[:, 1] - runs[:, 0]), 0]) if len(runs) else 0
    bad = np.zeros(len(idx), dtype=bool)
    tl, pl = t.tolist(), p.tolist()
    for order in (range(anchor + 1, len(idx)), range(anchor - 1, -1, -1)):
        last = anchor
        for k in order:
            d = sum((a - b) ** 2 for a, b in zip(pl[k], pl[last])) ** 0.5
            if d <= MAX_SPEED * abs(tl[k] - tl[last]) + SLACK:
                last = k
            else:
                bad[k] = True
    far[idx[bad]] = True
    return far


def drop_impossible(t, p, q, valid, source: str, linenos, track: str, columns):
    """``(valid, p, q)`` with the :func:`impossible` samples marked lost (values NaN), and a
    warning naming the first one's file, line and column (``columns``: of px, py, pz)."""
    bad = impossible(t, p, valid)
    if not bad.any():
        return valid, p, q
    rows = np.flatnonzero(bad)
    i = int(rows[0])
    far = np.abs(p[i]) > MAX_RADIUS
    if far.any():
        j = int(np.argmax(np.abs(p[i])))
        why = f"{p[i, j]:g} m is beyond any tracked space (±{MAX_RADIUS:g} m)"
    else:
        k = np.flatnonzero(valid & ~bad)
        k = k[k < i][-1] if (k < i).any() else k[k > i][0]
        j = int(np.argmax(np.abs(p[i] - p[k])))
        speed = np.linalg.norm(p[i] - p[k]) / abs(t[i] - t[k])
        why = f"a jump of {np.linalg.norm(p[i] - p[k]):.3g} m at {speed:.3g} m/s from line {int(linenos[k])}, " \
              f"faster than any hand ({MAX_SPEED:g} m/s)"
    lines = ", ".join(str(int(linenos[r])) for r in rows[:SHOWN]) + (", …" if len(rows) > SHOWN else "")
    warnings.warn(f"{where(source, int(linenos[i]), columns[j])}: track {track}: {why}; {len(rows)} impossible "
                  f"sample{'s' * (len(rows) != 1)} (line{'s' * (len(rows) != 1)} {lines}) treated as lost tracking",
                  stacklevel=2)
    valid = valid & ~bad
    p, q = p.copy(), q.copy()
    p[bad] = np.nan
    q[bad] = np.nan
    return valid, p, q


def check_samples(name: str, t: np.ndarray, p: np.ndarray, q: np.ndarray, valid: np.ndarray, source: str) -> None:
    """Raise DoodleError on what no repair can fix: too few samples, bad clock, NaN poses."""
    n = len(t)
    if n < 2:
        raise DoodleError(f"{source}: track {name} has {n} sample{'s' if n != 1 else ''}; a doodle needs at least two")
    if not np.all(np.isfinite(t)):
        i = int(np.flatnonzero(~np.isfinite(t))[0])
        raise DoodleError(f"{source}: track {name} sample {i}: time is not a finite number")
    bad = np.flatnonzero(np.diff(t) <= 0)
    if len(bad):
        i = int(bad[0]) + 1
        raise DoodleError(
            f"{source}: track {name} sample {i}: time {t[i]:.6f} s does not come after {t[i - 1]:.6f} s"
        )
    finite = np.isfinite(p).all(axis=1) & np.isfinite(q).all(axis=1)
    broken = np.flatnonzero(valid & ~finite)
    if len(broken):
        i = int(broken[0])
        raise DoodleError(f"{source}: track {name} sample {i} (t={t[i]:.6f} s): tracked pose is NaN or infinite")
    norms = np.where(valid, np.linalg.norm(np.where(valid[:, None], q, 0.0), axis=1), 1.0)
    off = np.flatnonzero(np.abs(norms - 1.0) > 0.1)
    if len(off):
        i = int(off[0])
        raise DoodleError(
            f"{source}: track {name} sample {i} (t={t[i]:.6f} s): quaternion norm {norms[i]:.3g} is not 1"
        )
    if not valid.any():
        raise DoodleError(f"{source}: track {name} was never tracked (every sample is flagged lost)")


def _gap_error(name: str, source: str, ta: float, tb: float, max_gap: float) -> DoodleError:
    return DoodleError(
        f"{source}: track {name} lost tracking for {tb - ta:.2f} s ({ta:.2f}-{tb:.2f} s), more than "
        f"the {max_gap:g} s that are repaired; trim the doodle or raise --max-gap"
    )


def _interpolate(ta, pa, qa, tb, pb, qb, t):
    """Poses at times ``t`` (m,) between two tracked samples; the shared arithmetic."""
    f = ((t - ta) / (tb - ta))[:, None]
    dot = qa[0] * qb[0] + qa[1] * qb[1] + qa[2] * qb[2] + qa[3] * qb[3]
    qb = -qb if dot < 0 else qb
    return pa + (pb - pa) * f, quat.normalise(qa + (qb - qa) * f)


def fill_gaps(name, t, p, q, valid, max_gap: float, source: str = "<memory>"):
    """Repaired copies ``(p, q)`` of a track's samples (see the module docstring)."""
    p, q = p.copy(), q.copy()
    if valid.all():
        return p, q
    idx = np.arange(len(t))
    tracked = np.flatnonzero(valid)
    first, last = tracked[0], tracked[-1]
    p[:first], q[:first] = p[first], q[first]
    p[last + 1 :], q[last + 1 :] = p[last], q[last]
    # interior gaps: runs of untracked samples between two tracked ones
    inner = ~valid & (idx > first) & (idx < last)
    starts = np.flatnonzero(inner & ~np.concatenate([[False], inner[:-1]]))
    ends = np.flatnonzero(inner & ~np.concatenate([inner[1:], [False]]))
    for s, e in zip(starts, ends):
        a, b = s - 1, e + 1
        if t[b] - t[a] > max_gap:
            raise _gap_error(name, source, t[a], t[b], max_gap)
        p[s : e + 1], q[s : e + 1] = _interpolate(t[a], p[a], q[a], t[b], p[b], q[b], t[s : e + 1])
    return p, q


def repaired(doodle: Doodle, max_gap: float) -> Doodle:
    """``doodle`` with every track's lost samples repaired (:func:`fill_gaps`), after the
    checks of :func:`check_samples`: every pose finite, ``valid`` kept as recorded (repairing
    again gives the same poses). The doodle itself when nothing was lost. Raises DoodleError
    naming the file, track and time span of a gap longer than ``max_gap``."""
    tracks = []
    for tr in doodle.tracks:
        check_samples(tr.name, tr.t, tr.p, tr.q, tr.valid, doodle.source)
        if tr.valid.all():
            tracks.append(tr)
            continue
        p, q = fill_gaps(tr.name, tr.t, tr.p, tr.q, tr.valid, max_gap, doodle.source)
        tracks.append(Track(tr.name, tr.t, p, q, tr.valid, tr.role, tr.serial))
    if all(a is b for a, b in zip(tracks, doodle.tracks)):
        return doodle
    return Doodle(tuple(tracks), doodle.rate, doodle.device, doodle.source, doodle.meta)


class GapFiller:
    """Streaming :func:`fill_gaps` on tuples of floats: ``push`` returns the samples that are
    final, in order, as ``(t, (px, py, pz), (qx, qy, qz, qw))``."""

    def __init__(self, name: str, max_gap: float, source: str = "<stream>"):
        self.name, self.max_gap, self.source = name, max_gap, source
        self.last: tuple | None = None  # the last tracked sample
        self.held: list[float] = []  # times of untracked samples waiting for tracking

    def push(self, t: float, p: tuple, q: tuple, valid: bool) -> list[tuple]:
        if not valid:
            self.held.append(t)
            return []
        sample = (t, p, q)
        if not self.held:
            self.last = sample
            return [sample]
        if self.last is None:
            out = [(ti, p, q) for ti in self.held]
        else:
            ta, pa, qa = self.last
            if t - ta > self.max_gap:
                raise _gap_error(self.name, self.source, ta, t, self.max_gap)
            ps, qs = _interpolate(ta, np.array(pa), np.array(qa), t, np.array(p), np.array(q), np.array(self.held))
            out = [(ti, tuple(pi), tuple(qi)) for ti, pi, qi in zip(self.held, ps.tolist(), qs.tolist())]
        self.held = []
        self.last = sample
        out.append(sample)
        return out

    def close(self) -> list[tuple]:
        if self.last is None:
            if self.held:
                raise DoodleError(f"{self.source}: track {self.name} was never tracked (every sample is flagged lost)")
            return []
        _, p, q = self.last
        out = [(ti, p, q) for ti in self.held]
        self.held = []
        return out
