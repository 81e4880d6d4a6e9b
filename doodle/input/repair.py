"""Checks and repairs of raw track samples before segmentation.

Documented repair for lost tracking (``valid == False``):

* a gap inside the track of at most ``max_gap`` seconds (from the last tracked sample to the
  next) is filled by interpolation — positions linearly, orientations by normalised linear
  interpolation in the shorter direction;
* a longer interior gap is an error naming the track and the time span (trim the doodle or
  raise ``--max-gap``): interpolating seconds of missing motion would invent a stroke;
* untracked samples before the first or after the last tracked one take that sample's pose
  (the figurine reads as still there).

:func:`fill_gaps` is the batch form; :class:`GapFiller` the streaming one, which holds
untracked samples until tracking returns and then releases them, with identical values.
"""

from __future__ import annotations

import numpy as np

from doodle.core import quat
from doodle.core.errors import DoodleError


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
