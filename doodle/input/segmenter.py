"""The Segmenter: samples → motion tokens (thesis §4.2.2; SPEC "Segmenter").

Per track: repair lost tracking, smooth, compute local velocities ``(v, ω)`` in the moving
frame, then give each sample a bin:

* ``T_STILL`` when ``‖(v, θω)‖ ≤ ε`` — the stillness norm uses the same metre-per-radian
  exchange rate θ as the next test, so both speeds are in m/s;
* a translation bin when ``‖v‖ ≥ θ‖ω‖``, else a rotation bin; the bin is the direction
  class of v (or ω) among 26 (see :mod:`doodle.core.tokens`).

Debounce (α): a bin becomes a token once it has held for α consecutive samples; shorter
excursions are absorbed by the current token. Tokens therefore partition the samples —
token k covers ``[start_k, start_{k+1})`` — and no two neighbours share a name (the stream
is already compacted). The first token also covers the samples before its run.

Units. ε (m/s) and θ (m/rad) are physical, so they do not depend on the device rate; α and
the smoothing kernel are set in seconds and converted to samples per rate
(α = 5 samples at 90 Hz, ``α_d = 5·F_d/90``). The thesis gives ε ∈ [0.02, 0.05] and θ = 300 in
unstated per-sample units; the defaults here were chosen on real Vive recordings (see
``bench/``). Scaling a doodle by s and ε, θ by s (``params.scaled(s)``) leaves its tokens
unchanged — a larger prop with proportionally calibrated thresholds is the same doodle.

:func:`tokenize` (batch, vectorised) and :class:`Segmenter` (streaming: push one sample, get
zero or more tokens; ``close`` flushes) give identical tokens.
"""

from __future__ import annotations

import copy
import math
from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from doodle.core import quat
from doodle.input.deliberate import Absorber, absorb, extent
from doodle.core.errors import DoodleError
from doodle.input.frame import local_velocities, local_velocity
from doodle.input.levelling import IDENTITY, level, levels, unrotate
from doodle.core.model import Doodle, Track
from doodle.input.repair import GapFiller, check_samples, fill_gaps
from doodle.input.smoothing import StreamingSmoother, laplacian_kernel, savgol_kernel, smooth
from doodle.core.tokens import CODES, NAMES, R_BASE, STILL, T_BASE, Token, direction_index, direction_indices, signs_of


# The largest value of each parameter: far beyond any calibration, and small enough that its
# squares stay finite and its kernels (seconds × rate) a sane length.
LIMITS = {"eps": 1e3, "theta": 1e3, "alpha_s": 10.0, "smooth_s": 1.0, "savgol_window_s": 10.0, "max_gap": 3600.0,
          "pause_s": 10.0, "significance": 1e3, "min_extent_s": 10.0, "window": 100, "level_cap": 90.0}


@dataclass(frozen=True)
class SegmenterParams:
    """The Segmenter's thresholds and filters (``doodle calibrate`` measures a prop's own)."""

    eps: float = 0.05  # m/s: a sample is still when ‖(v, θω)‖ ≤ eps
    theta: float = 0.3  # m/rad: translation when ‖v‖ ≥ theta·‖ω‖
    alpha_s: float = 5 / 90  # seconds a bin must hold to become a token (5 samples at 90 Hz)
    smoothing: str = "laplacian"  # or "savgol"
    smooth_s: float = 0.03  # Laplacian: temporal std of the kernel, seconds
    savgol_window_s: float = 0.1  # Savitzky–Golay: window length, seconds (cubic)
    max_gap: float = 0.5  # seconds of lost tracking repaired by interpolation
    # deliberate motion (doodle.input.deliberate, doodle.input.levelling)
    pause_s: float = 0.12  # a still between movements shorter than this is a hold, not a pause
    significance: float = 0.2  # a token covering less than this share of its neighbours' extent is a blip
    min_extent_s: float = 0.2  # ... as is one covering less than eps × this (metres)
    window: int = 2  # neighbours looked at on each side for significance
    level_cap: float = 35.0  # degrees: a rest tilted less than this is stood upright (0: no levelling)

    def __post_init__(self) -> None:
        if self.smoothing not in ("laplacian", "savgol"):
            raise DoodleError(f"smoothing must be 'laplacian' or 'savgol', not {self.smoothing!r}")
        for field, most in LIMITS.items():
            value = getattr(self, field)
            if not (np.isfinite(value) and 0 <= value <= most):
                raise DoodleError(f"segmenter parameter {field} must be a number from 0 to {most:g}, not {value!r}")

    def alpha(self, rate: float) -> int:
        """α in samples for a device rate: ``round(alpha_s · rate)``, at least 1."""
        return max(1, int(round(self.alpha_s * rate)))

    def kernel(self, rate: float) -> np.ndarray:
        if self.smoothing == "savgol":
            return savgol_kernel(self.savgol_window_s, rate)
        return laplacian_kernel(self.smooth_s, rate)

    def absorber(self, rate: float) -> Absorber:
        """The stage that absorbs holds and blips (:mod:`doodle.input.deliberate`)."""
        return Absorber(rate, self.pause_s, self.significance, self.eps * self.min_extent_s, int(self.window))

    @property
    def cos_cap(self) -> float | None:
        """cos of the levelling cap, None when levelling is off."""
        return math.cos(math.radians(self.level_cap)) if self.level_cap > 0 else None

    def scaled(self, s: float) -> "SegmenterParams":
        """Thresholds for a doodle uniformly scaled by ``s``."""
        return replace(self, eps=self.eps * s, theta=self.theta * s)


def _norms(v: np.ndarray, w: np.ndarray, theta2: float) -> tuple[np.ndarray, np.ndarray]:
    v2 = v[:, 0] * v[:, 0] + v[:, 1] * v[:, 1] + v[:, 2] * v[:, 2]
    return v2, theta2 * (w[:, 0] * w[:, 0] + w[:, 1] * w[:, 1] + w[:, 2] * w[:, 2])


def sample_codes(v: np.ndarray, w: np.ndarray, params: SegmenterParams, c: np.ndarray | None = None) -> np.ndarray:
    """Bin code per velocity sample (vectorised; see :func:`sample_code`); directions are
    read in the frames turned by the levelling ``c`` (n, 4) when given."""
    theta2, eps2 = params.theta * params.theta, params.eps * params.eps
    v2, tw2 = _norms(v, w, theta2)
    if c is not None:
        cx, cy, cz, cw = c[:, 0], c[:, 1], c[:, 2], c[:, 3]
        v = np.column_stack(unrotate(cx, cy, cz, cw, v[:, 0], v[:, 1], v[:, 2]))
        w = np.column_stack(unrotate(cx, cy, cz, cw, w[:, 0], w[:, 1], w[:, 2]))
    codes = np.where(v2 >= tw2, T_BASE + direction_indices(v), R_BASE + direction_indices(w))
    return np.where(v2 + tw2 <= eps2, STILL, codes)


def sample_code(vel: tuple, theta2: float, eps2: float, c: tuple = IDENTITY) -> int:
    """Bin code of one ``(vx, vy, vz, ωx, ωy, ωz)``; the arithmetic of :func:`sample_codes`."""
    vx, vy, vz, wx, wy, wz = vel
    v2 = vx * vx + vy * vy + vz * vz
    tw2 = theta2 * (wx * wx + wy * wy + wz * wz)
    if v2 + tw2 <= eps2:
        return STILL
    if v2 >= tw2:
        return T_BASE + direction_index(*unrotate(*c, vx, vy, vz))
    return R_BASE + direction_index(*unrotate(*c, wx, wy, wz))


def _corners() -> dict:
    """(code a, code b) → the code of the diagonal between two single-axis translations on
    different axes (``T_Y``, ``T_N_Z`` → ``T_Y_N_Z``)."""
    out = {}
    single = {}
    for name, code in CODES.items():
        kind, signs = signs_of(name)
        if kind == "T" and sum(map(abs, signs)) == 1:
            single[code] = signs
    for a, sa in single.items():
        for b, sb in single.items():
            if not any(x and y for x, y in zip(sa, sb)):
                out[(a, b)] = CODES[_name_of(tuple(x + y for x, y in zip(sa, sb)))]
    return out


def _name_of(signs) -> str:
    return next(n for n, c in CODES.items() if signs_of(n) == ("T", tuple(signs)))


CORNERS = _corners()
CORNER_LEAST = 2  # samples of the diagonal a rounded corner must pass through to be a token


def _corner(between: list, a: int, b: int) -> int | None:
    """Of the runs ``(code, length)`` between two confirmed runs of codes a and b, the one
    that is their corner's diagonal (the first longest), when the runs of that diagonal
    hold at least :data:`CORNER_LEAST` samples; else None."""
    diagonal = CORNERS.get((a, b))
    if diagonal is None:
        return None
    best, total = None, 0
    for k, (code, length) in enumerate(between):
        if code == diagonal:
            total += length
            if best is None or length > between[best][1]:
                best = k
    return best if total >= CORNER_LEAST else None


def debounce(codes: np.ndarray, alpha: int) -> list[Token]:
    """Tokens from per-sample codes: runs of ≥ α samples, shorter excursions absorbed —
    except the diagonal a hand passes through when it rounds a corner between two
    single-axis translations (up, then back: ``T_Y_N_Z`` between ``T_Y`` and ``T_N_Z``), kept
    when it lasts :data:`CORNER_LEAST` samples or more: a quick rounded corner crosses the
    diagonal's 30° band in fewer than α samples, yet the performer drew it."""
    n = len(codes)
    if n == 0:
        return []
    change = np.flatnonzero(codes[1:] != codes[:-1]) + 1
    starts = np.concatenate([[0], change])
    lengths = np.diff(np.concatenate([starts, [n]]))
    confirmed = lengths >= alpha
    run_codes = codes[starts]
    kept = np.flatnonzero(confirmed)
    for a, b in zip(kept[:-1], kept[1:]):
        if b - a > 1:
            k = _corner([(int(run_codes[r]), int(lengths[r])) for r in range(a + 1, b)], int(run_codes[a]),
                        int(run_codes[b]))
            if k is not None:
                confirmed[a + 1 + k] = True
    c_codes, c_starts = codes[starts[confirmed]], starts[confirmed]
    if len(c_codes) == 0:
        return []
    new = np.concatenate([[True], c_codes[1:] != c_codes[:-1]])
    t_codes, t_starts = c_codes[new], c_starts[new]
    t_starts[0] = 0
    ends = np.concatenate([t_starts[1:], [n]])
    return [Token(NAMES[c], int(s), int(e)) for c, s, e in zip(t_codes, t_starts, ends)]


def smoothed_track(track: Track, rate: float, params: SegmenterParams, source: str = "<memory>") -> np.ndarray:
    """Rows ``(t, px, py, pz, qx, qy, qz, qw)`` after repair, sign continuity and smoothing."""
    check_samples(track.name, track.t, track.p, track.q, track.valid, source)
    p, q = fill_gaps(track.name, track.t, track.p, track.q, track.valid, params.max_gap, source)
    rows = smooth(np.column_stack([track.t, p, quat.make_continuous(q)]), params.kernel(rate))
    rows[:, 4:] = quat.normalise(rows[:, 4:])
    return rows


def codes_of_rows(rows: np.ndarray, rate: float, params: SegmenterParams) -> tuple[np.ndarray, np.ndarray]:
    """Bin code of every smoothed sample (sample 0 takes sample 1's bin), directions read in
    the frame levelled at the latest rest (:mod:`doodle.input.levelling`), and the squared speed
    ``‖(v, θω)‖²`` of each."""
    v, w = local_velocities(rows[:, 0], rows[:, 1:4], rows[:, 4:], rate)
    v, w = np.vstack([v[:1], v]), np.vstack([w[:1], w])
    v2, tw2 = _norms(v, w, params.theta * params.theta)
    c = None
    if params.cos_cap is not None and len(rows):
        c = levels(rows[:, 4:], v2 + tw2 <= params.eps * params.eps, params.alpha(rate), params.cos_cap)
    return sample_codes(v, w, params, c), v2 + tw2


def sample_codes_of(track: Track, rate: float, params: SegmenterParams, source: str = "<memory>") -> np.ndarray:
    """Bin code of every sample of a track (sample 0 takes sample 1's bin)."""
    return codes_of_rows(smoothed_track(track, rate, params, source), rate, params)[0]


def tokenize(track: Track, rate: float, params: SegmenterParams = SegmenterParams(), source: str = "<memory>") -> list[Token]:
    """Batch Segmenter: the tokens of one track sampled at nominal ``rate`` Hz."""
    rows = smoothed_track(track, rate, params, source)
    codes, speed2 = codes_of_rows(rows, rate, params)
    raw = debounce(codes, params.alpha(rate))
    last = len(rows) - 1
    extents = [extent(rows[k.start].tolist(), rows[min(k.end, last)].tolist(), params.theta) for k in raw]
    fast = speed2 >= 4.0 * params.eps * params.eps
    ramps = []
    for k in raw:  # samples from the token's start to its first, and from its last, sample over 2ε
        on = np.flatnonzero(fast[k.start:k.end])
        ramps.append((int(on[0]), int(k.end - k.start - 1 - on[-1])) if len(on) else (k.end - k.start,) * 2)
    return absorb(raw, extents, ramps, params.absorber(rate))


def tokenize_doodle(doodle: Doodle, params: SegmenterParams = SegmenterParams()) -> dict[str, list[Token]]:
    """Tokens of every track of a doodle, by track name."""
    return {tr.name: tokenize(tr, doodle.rate, params, doodle.source) for tr in doodle.tracks}


class Segmenter:
    """Streaming Segmenter for one track: ``push`` a sample, get the tokens it completes.

    A token is final when the next one is confirmed (α samples into it) or at :meth:`close`;
    :attr:`pending` shows the token in progress for live feedback. Samples must come in
    time order; lost-tracking samples (``valid=False``) are held until tracking returns.
    """

    def __init__(self, rate: float, params: SegmenterParams = SegmenterParams(), name: str = "c0", source: str = "<stream>"):
        self.rate, self.params, self.name, self.source = rate, params, name, source
        self.alpha = params.alpha(rate)
        self._theta2, self._eps2 = params.theta * params.theta, params.eps * params.eps
        self._gaps = GapFiller(name, params.max_gap, source)
        self._smoother = StreamingSmoother(params.kernel(rate), 8)
        self._pushed = 0  # samples pushed
        self._last_t: float | None = None
        self._raw_q: tuple | None = None  # previous raw quaternion, as given
        self._sign = 1.0  # sign applied to it for continuity
        self._prev: tuple | None = None  # previous smoothed sample
        self._n = 0  # samples classified so far
        self._cur: int | None = None  # code of the token in progress
        self._cur_start = 0
        self._run_code = -1
        self._run_start = 0
        self._run_len = 0
        self._cos_cap = params.cos_cap
        self._level = IDENTITY  # levelling from the latest rest
        self._still_run = 0
        self._row0 = self._cur_row = self._run_row = self._last_row = None  # rows at token boundaries
        self._absorber = params.absorber(rate)
        self._fast2 = 4.0 * params.eps * params.eps
        self._tok_fast = self._run_fast = None  # (first, last) sample over 2ε: token before the run, the run
        self._since: list = []  # runs shorter than α since the last confirmed one (corner candidates)
        # of the still :meth:`held` last read: (start, samples classified from which it may be a
        # pause, ... from which it is one whatever follows)
        self._pause: tuple | None = None
        self.held_hold = False  # whether the still :meth:`held` last gave as a pause may yet be a hold
        self._recent: deque = deque(maxlen=self.alpha + 1)  # the latest samples pushed, raw (:meth:`_slowing`)

    @property
    def pending(self) -> Token | None:
        """The token in progress (its end is the number of samples classified so far)."""
        return None if self._cur is None else Token(NAMES[self._cur], self._cur_start, self._n)

    def push(self, t: float, p, q, valid: bool = True) -> list[Token]:
        """Add one sample (time in s, position (3), quaternion xyzw (4)); the tokens it completes."""
        t = float(t)
        px, py, pz = p.tolist() if hasattr(p, "tolist") else map(float, p)
        qx, qy, qz, qw = q.tolist() if hasattr(q, "tolist") else map(float, q)
        if not (t - t == 0.0 and (self._last_t is None or t > self._last_t)):
            self._bad_sample(t, "time")
        if valid:
            total = px + py + pz + qx + qy + qz + qw
            norm2 = qx * qx + qy * qy + qz * qz + qw * qw
            if not (total - total == 0.0 and 0.81 <= norm2 <= 1.21):
                self._bad_sample(t, "pose", norm2)
        self._last_t = t
        self._pushed += 1
        out: list[Token] = []
        for sample in self._gaps.push(t, (px, py, pz), (qx, qy, qz, qw), valid):
            self._smooth(sample, out)
        return out

    def _bad_sample(self, t: float, what: str, norm2: float = 1.0):
        at = f"{self.source}: track {self.name} sample {self._pushed}"
        if what == "time":
            if not np.isfinite(t):
                raise DoodleError(f"{at}: time is not a finite number")
            raise DoodleError(f"{at}: time {t:.6f} s does not come after {self._last_t:.6f} s")
        if np.isfinite(norm2) and np.isfinite(t):
            norm = float(np.sqrt(norm2))
            if abs(norm - 1.0) > 0.1:
                raise DoodleError(f"{at} (t={t:.6f} s): quaternion norm {norm:.3g} is not 1")
        raise DoodleError(f"{at} (t={t:.6f} s): tracked pose is NaN or infinite")

    def close(self) -> list[Token]:
        """Flush: the remaining tokens, including the one in progress."""
        n = self._pushed
        if n < 2:
            raise DoodleError(f"{self.source}: track {self.name} has {n} sample{'s' if n != 1 else ''}; a doodle needs at least two")
        out: list[Token] = []
        for sample in self._gaps.close():
            self._smooth(sample, out)
        for row in self._smoother.close():
            self._classify(row, out)
        return out + self.cut()

    def cut(self) -> list[Token]:
        """End the stream where classification stands, without the samples still being
        smoothed (tracking lost for good): the tokens held back and the one in progress."""
        out: list[Token] = []
        if self._cur is not None:
            self._join_run()
            tok = Token(NAMES[self._cur], self._cur_start, self._n)
            out += self._absorber.push(tok, extent(self._cur_row, self._last_row, self.params.theta), self._ramps(tok))
            self._cur = None
        return out + self._absorber.close()

    def held(self) -> list[Token]:
        """The tokens not final yet, as they stand (provisional): what :meth:`close` would
        give were the stream to end now, worked out on a copy — the samples still being
        smoothed read as at the end of a file, so that a hand come to rest is read still
        without waiting for the smoothing kernel's half-width. A still in progress is left
        out while it could not be a pause yet — were a movement to begin now, by the
        Absorber's rule (:meth:`Absorber.pause_from`): it may be a hold, the movement before
        it going on. :attr:`held_hold` says whether one given may still turn out a hold
        (the next movement starting slowly), not being a pause whatever follows yet."""
        peek, out = self._fork(), []
        for row in peek._smoother.close():
            peek._classify(row, out)
        self.held_hold = False
        if peek._cur == STILL:
            may, sure = peek._absorber.pause_from(Token(NAMES[STILL], peek._cur_start, peek._n))
            ahead = peek._n - self._n  # ... once this many samples are classified
            self._pause = (self._cur_start, may - ahead, sure - ahead)
            if peek._n < may:
                return out + peek._absorber.close()
            self.held_hold = peek._n < sure
        return out + peek.cut()

    def held_key(self) -> tuple:
        """What :meth:`held` depends on, cheaply (for every frame): the token in progress and
        where it starts; for a movement, whether it has covered the floor under which it
        is absorbed, and while the hand moves slowly (:meth:`_slowing`) the samples pushed,
        since the ones still being smoothed may end in a still by now; for a still, whether
        it may be a pause by now (as :meth:`held` last found) — or, while :meth:`held` has
        not read it as a still yet (the samples still being smoothed end in a movement),
        the samples classified, since each may change that."""
        if self._cur is None:
            return (None,)
        if self._cur == STILL:
            if self._pause is None or self._pause[0] != self._cur_start:
                return self._cur, self._cur_start, self._n
            return self._cur, self._cur_start, self._n >= self._pause[1], self._n >= self._pause[2]
        return (self._cur, self._cur_start,
                extent(self._cur_row, self._last_row, self.params.theta) >= self._absorber.floor,
                self._pushed if self._slowing() else None)

    def _slowing(self) -> bool:
        """Whether the latest α samples pushed moved less than at 2ε (the speed under which a
        movement is slowing to rest, :meth:`_ramps`) — a cheap sign, from the raw samples, that
        the ones still being smoothed may read still."""
        recent = self._recent
        return (len(recent) > self.alpha
                and extent(recent[0], recent[-1], self.params.theta) <= 2.0 * self.params.eps * self.alpha / self.rate)

    def _fork(self) -> "Segmenter":
        """An independent copy for :meth:`held` (no more samples are pushed to it)."""
        other = copy.copy(self)
        other._absorber, other._since = self._absorber.copy(), list(self._since)
        other._smoother = self._smoother.fork()
        return other

    def _smooth(self, sample: tuple, out: list[Token]) -> None:
        t, (px, py, pz), (qx, qy, qz, qw) = sample
        a = self._raw_q
        if a is not None and qx * a[0] + qy * a[1] + qz * a[2] + qw * a[3] < 0:
            self._sign = -self._sign  # as quat.hemisphere_signs: parity of flips so far
        self._raw_q = (qx, qy, qz, qw)
        s = self._sign
        row = (t, px, py, pz, qx * s, qy * s, qz * s, qw * s)
        self._recent.append(row)
        for r in self._smoother.push(row):
            self._classify(r, out)

    def _classify(self, row: np.ndarray, out: list[Token]) -> None:
        t, px, py, pz, x, y, z, w = row.tolist()
        norm = math.sqrt(x * x + y * y + z * z + w * w)
        cur = (t, px, py, pz, x / norm, y / norm, z / norm, w / norm)
        prev, self._prev = self._prev, cur
        if prev is None:
            return
        vel = local_velocity(prev, cur, self.rate)
        if self._n == 0:
            self._sample(vel, prev, out)  # sample 0 takes sample 1's bin
        self._sample(vel, cur, out)

    def _sample(self, vel: tuple, row: tuple, out: list[Token]) -> None:
        code = sample_code(vel, self._theta2, self._eps2, self._level)
        vx, vy, vz, wx, wy, wz = vel
        speed2 = vx * vx + vy * vy + vz * vz + self._theta2 * (wx * wx + wy * wy + wz * wz)
        self._step(code, row, speed2, out)
        if self._cos_cap is None:
            return
        still = speed2 <= self._eps2
        self._still_run = self._still_run + 1 if still else 0
        if self._still_run >= self.alpha:  # at rest: the world's up says where the prop's is
            c, ok = level(row[4], row[5], row[6], row[7], self._cos_cap)
            self._level = c if ok else IDENTITY

    def _step(self, code: int, row: tuple, speed2: float, out: list[Token]) -> None:
        i = self._n
        self._n += 1
        self._last_row = row
        if i == 0:
            self._row0 = row
        if code == self._run_code:
            self._run_len += 1
        else:
            if 0 < self._run_len < self.alpha:  # a short run: kept aside in case it is a corner
                self._since.append((self._run_code, self._run_start, self._run_len, self._run_row, self._run_fast,
                                    self._tok_fast))
            self._join_run()  # the run so far belongs to the token in progress
            self._run_code, self._run_start, self._run_len = code, i, 1
            self._run_row = row
        if speed2 >= self._fast2:  # first and last sample over 2ε, in the run
            self._run_fast = (i if self._run_fast is None else self._run_fast[0], i)
        if self._run_len == self.alpha:
            since, self._since = self._since, []
            if self._cur is None:
                self._cur, self._cur_start, self._cur_row = code, 0, self._row0
            elif code != self._cur:
                k = _corner([(c, n) for c, _, n, _, _, _ in since], self._cur, code) if since else None
                if k is not None:  # the token in progress ends at the corner; the corner is a token
                    c_code, c_start, _, c_row, _, before = since[k]
                    raw = Token(NAMES[self._cur], self._cur_start, c_start)
                    out += self._absorber.push(raw, extent(self._cur_row, c_row, self.params.theta),
                                               self._ramps(raw, before))
                    fast = [f for *_, f, _ in since[k:] if f is not None]
                    self._cur, self._cur_start, self._cur_row = c_code, c_start, c_row
                    self._tok_fast = (fast[0][0], fast[-1][1]) if fast else None
                raw = Token(NAMES[self._cur], self._cur_start, self._run_start)
                out += self._absorber.push(raw, extent(self._cur_row, self._run_row, self.params.theta),
                                           self._ramps(raw))
                self._cur, self._cur_start, self._cur_row = code, self._run_start, self._run_row
                self._tok_fast = None  # the token now starts at the run

    def _join_run(self) -> None:
        if self._run_fast is not None:
            self._tok_fast = self._run_fast if self._tok_fast is None else (self._tok_fast[0], self._run_fast[1])
        self._run_fast = None

    def _ramps(self, tok: Token, fast="token") -> tuple[int, int]:
        """Samples from a token's start to its first sample over 2ε, and from its last one to
        its end (``fast``: that first and last sample; by default the token in progress's)."""
        fast = self._tok_fast if fast == "token" else fast
        if fast is None:
            return tok.end - tok.start, tok.end - tok.start
        return fast[0] - tok.start, tok.end - 1 - fast[1]
