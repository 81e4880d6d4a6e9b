"""Shapes of learned actions: where the tokens are not enough to tell two gestures apart.

The Segmenter's tokens quantise a path to 26 directions and pauses; two whole-body gestures
of one person (a left and a right hook, an uppercut and a golf swing) often give token
strings 5–10 edits apart between repetitions and as close to each other's expressions as to
their own. A learned action therefore keeps the *shapes* of its examples as well: each
example's path resampled to :data:`POINTS` points by arc length, as the unit directions of
its :data:`POINTS` − 1 steps (in the room's frame — a performer faces the table, so left
and right mean something). The shape distance of a performance to an action is the smallest
DTW cost between its directions and an example's, per step (the mean squared difference of
unit directions, 0 … 4). It is the representation of the nearest-neighbour baseline of
the learning benchmark (Kristensson & Zhai's direction features resampled by arc length, compared with
DTW); here it ranks the actions whose expressions the Matcher found: ``edits +``
:data:`WEIGHT` ``× shape distance``.

DTW costs of one performance against every template are computed at once (one row
recurrence vectorised over templates), about 0.2 ms for 33 templates of 31 steps.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

POINTS = 32  # points per resampled path (31 steps)
CHUNK = 2048  # paths × templates compared at once (a few MB)
MAX_METRES = 1000.0  # a shape file's coordinates beyond this are not a hand's path but a corrupt file
WEIGHT = 31.0  # edits one unit of shape distance counts as (a step whose direction is 1 apart, each step)


def resample(p: np.ndarray, points: int = POINTS) -> np.ndarray:
    """A path (n, 3) resampled to ``points`` points equally spaced along its length, from
    its first point (a path that does not move: ``points`` copies of the origin)."""
    p = np.asarray(p, dtype=float)
    p = p - p[0]
    s = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(p, axis=0), axis=1))])
    if s[-1] <= 0:
        return np.zeros((points, 3))
    u = np.linspace(0.0, s[-1], points)
    return np.column_stack([np.interp(u, s, p[:, k]) for k in range(3)])


def directions(path: np.ndarray) -> np.ndarray:
    """Unit directions of a resampled path's steps, (points − 1, 3)."""
    v = np.diff(path, axis=0)
    return v / np.maximum(np.linalg.norm(v, axis=1, keepdims=True), 1e-9)


def dtw_costs(x: np.ndarray, templates: np.ndarray) -> np.ndarray:
    """DTW cost (squared l2, steps (1,1), (1,0), (0,1)) of x (n, d) — or of each of a batch
    (B, n, d) — against every template (k, m, d) at once, divided by the longer length:
    (k,), or (B, k)."""
    templates = np.asarray(templates, dtype=float)
    if templates.ndim == 2:
        templates = templates[None]
    x = np.asarray(x, dtype=float)
    single = x.ndim == 2
    xb = x[None] if single else x
    b, n, _ = xb.shape
    k, m, _ = templates.shape
    # (b, k, n, m) squared distances, as |x|² + |t|² − 2 x·t
    cost = ((xb ** 2).sum(-1)[:, None, :, None] + (templates ** 2).sum(-1)[None, :, None, :]
            - 2.0 * np.einsum("bnd,kmd->bknm", xb, templates))
    cost = np.maximum(cost, 0.0).reshape(b * k, n, m)
    row = np.cumsum(cost[:, 0, :], axis=1)
    inf = np.full((b * k, 1), np.inf)
    for i in range(1, n):
        base = cost[:, i, :] + np.concatenate([inf, np.minimum(row[:, :-1], row[:, 1:])], axis=1)
        base[:, 0] = cost[:, i, 0] + row[:, 0]
        c = np.cumsum(cost[:, i, :], axis=1)
        row = np.minimum.accumulate(base - c, axis=1) + c  # from (i, j-1): a prefix minimum
    out = row[:, -1].reshape(b, k) / max(n, m)
    return out[0] if single else out


# --- a library's shapes, and segments refined by them ------------------------------------

REACH = 3  # tokens a refined segment may extend past the Matcher's at either end
TRIM = 3  # tokens it may give up at either end
UNKNOWN_REACH = 8  # tokens it may take from a neighbouring unknown run
SPOT_TOKENS, SPOT_MAX = 4, 40  # unknown runs of this many tokens are searched for a learned action…
SPOT = 0.5  # …found when its shape distance is under this part of the action's rejection distance
MIN_REJECT = 0.4  # shape distance under which a learned action is never rejected


@dataclass(frozen=True, eq=False)
class ShapeSet:
    """The learned actions that carry shapes, ready to rank segments."""

    names: tuple[str, ...]
    templates: np.ndarray  # (K, POINTS - 1, 3) directions of every example of every action
    owner: np.ndarray  # (K,) index into names, sorted
    reject: np.ndarray  # (len(names),) shape distance above which a segment is not that action
    automaton: object  # grammar.matcher.Automaton of the names' expressions (edit distances, capped)
    tracks: tuple = ()  # per name, the track it is bound to (None: any)

    def allowed(self, track: str | None) -> np.ndarray:
        """Which actions may be recognised on ``track``."""
        bound = self.tracks or (None,) * len(self.names)
        return np.array([b is None or track is None or b == track for b in bound])

    def distances(self, x: np.ndarray) -> np.ndarray:
        """Per action, the shape distance of directions x (n, 3), or of each of a batch (B, n, 3)."""
        if x.ndim == 3 and len(x) * len(self.templates) > CHUNK:  # bounded memory: in chunks of windows
            step = max(1, CHUNK // len(self.templates))
            return np.concatenate([self.distances(x[k:k + step]) for k in range(0, len(x), step)])
        costs = dtw_costs(x, self.templates)
        return np.minimum.reduceat(costs, np.searchsorted(self.owner, np.arange(len(self.names))), axis=-1)


FORMAT = 1


def save_paths(path, paths: np.ndarray) -> None:
    """Write example paths (k, n, 3) to ``path`` (.npz, no pickles), atomically."""
    from doodle.core.files import atomic_path

    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            np.savez(f, paths=np.asarray(paths, dtype=float), format=np.array(FORMAT))


def load_paths(path, action: str = "") -> np.ndarray:
    """Example paths (k, n, 3) from a shape file; DoodleError naming the file and action."""
    from doodle.core.errors import DoodleError
    from doodle.core.npz import read_npz

    where = f"{path}" + (f" (shape of action {action!r})" if action else "")
    arrays = read_npz(path, where)
    if "paths" not in arrays:
        raise DoodleError(f"{where}: no 'paths' array in it")
    if "format" in arrays:
        version = arrays["format"]
        if version.shape != () or version.dtype.kind not in "iu" or int(version) != FORMAT:
            raise DoodleError(f"{where}: shape format {version.tolist()!r} is not supported (this version reads {FORMAT})")
    paths = arrays["paths"]
    if paths.dtype.kind != "f" or paths.ndim != 3 or paths.shape[0] < 1 or paths.shape[1:] != (POINTS, 3):
        raise DoodleError(f"{where}: 'paths' must be a float array (examples, points = {POINTS}, 3), got "
                          f"{paths.dtype} {paths.shape}")
    if not np.isfinite(paths).all():
        raise DoodleError(f"{where}: 'paths' holds NaN or infinite values")
    if np.abs(paths).max() > MAX_METRES:
        raise DoodleError(f"{where}: 'paths' reaches {np.abs(paths).max():.3g} m from its start; "
                          f"a hand's path stays within {MAX_METRES:g} m")
    return paths.astype(float)


def shape_set(named: dict, expressions: dict, tracks: dict | None = None, cap: float = 20.0,
              automaton=None) -> ShapeSet | None:
    """A :class:`ShapeSet` from ``{action: example paths (k, POINTS, 3)}``, the actions'
    expressions and the tracks they are bound to (``{action: track}``, default none); None
    when no action has shapes. Edit distances count up to ``cap``; ``automaton``, when
    given, is a ready one of the same expressions in the same order (no pause protection)."""
    if not named:
        return None
    from grammar.automata import compile_expression
    from grammar.expr import parse
    from grammar.matcher import Automaton

    names = tuple(named)
    dirs = [np.array([directions(p) for p in named[n]]) for n in names]
    owner = np.concatenate([np.full(len(d), k) for k, d in enumerate(dirs)])
    auto = automaton or Automaton(list(names), [compile_expression(parse(expressions[n], n)) for n in names],
                                  threshold=cap, protect_still=False)
    return ShapeSet(names, np.concatenate(dirs), owner, np.array([reject_distance(d) for d in dirs]), auto,
                    tuple((tracks or {}).get(n) for n in names))


def reject_distance(templates: np.ndarray) -> float:
    """How far from its examples a performance of an action may be: twice the largest
    distance of an example to the others (leave one out), at least :data:`MIN_REJECT`."""
    if len(templates) < 2:
        return MIN_REJECT
    loo = [dtw_costs(templates[k], np.delete(templates, k, axis=0)).min() for k in range(len(templates))]
    return max(MIN_REJECT, 2.0 * float(max(loo)))


def refine(segments: list, tokens: list, p: np.ndarray, valid: np.ndarray, shapes: ShapeSet,
           track: str | None = None) -> list:
    """Batch form of :class:`Refiner`: every segment of a track re-decided."""
    refiner = Refiner(shapes, p, valid, track)
    refiner.tokens.extend(tokens)
    return refiner.push(segments) + refiner.close()


class Refiner:
    """The Matcher's segments of one track, re-decided by the learned actions' shapes.

    Segments are taken in order. One whose action has shapes is re-decided once the next
    segment and the :data:`REACH` tokens after it are known: every window of whole tokens
    from up to :data:`REACH` tokens before to :data:`TRIM` after its first token, and
    likewise around its last — or, when the next segment has shapes too, around the next
    one's last (the Matcher, with a learned action's large tolerance, may cut one long
    gesture in two) — no window starting or ending on a pause or reaching back into what
    is already decided, is scored for every shaped action as ``edits + WEIGHT × shape distance``; the
    best window and action win — or, when its shape distance is over that action's
    :attr:`ShapeSet.reject`, the segment is unknown. A window may also take back up to
    :data:`UNKNOWN_REACH` tokens of the unknown run before it, or reach as far into the
    unknown run after it. Tokens a window takes from the next segment are taken from it;
    tokens it gives up are unknown. An unknown run of :data:`SPOT_TOKENS` to
    :data:`SPOT_MAX` tokens is searched the same way and reported as a learned action when
    one fits within :data:`SPOT` of its rejection distance. Other segments pass through
    (less any tokens taken). The batch form (:func:`refine`) is this run to the end, so
    streaming equals batch.

    ``tokens`` is the track's token list (append as the Segmenter gives them); ``p`` and
    ``valid`` the track's samples, at least as far as the tokens go; ``track`` its name
    (actions bound to other tracks are not considered).
    """

    def __init__(self, shapes: ShapeSet, p: np.ndarray, valid: np.ndarray, track: str | None = None):
        self.shapes, self.p, self.valid = shapes, p, valid
        self._allowed = shapes.allowed(track)
        self.tokens: list = []
        self._waiting: list = []
        self._done = 0  # tokens before this are decided
        self._unknown = None

    def push(self, segments: list) -> list:
        """Segments from the Matcher (in order) → segments decided so far."""
        self._waiting += segments
        out = []
        while self._waiting and self._ready():
            after = self._waiting[1] if len(self._waiting) > 1 else None
            out += self._decide(self._waiting.pop(0), after, len(self.tokens))
        return out

    def _ready(self) -> bool:
        first = self._waiting[0]
        if first.action not in self.shapes.names:
            return True
        if len(self._waiting) < 2:  # the next segment decides how far a window may reach
            return False
        after = self._waiting[1]
        return len(self.tokens) >= (after.stop if after.action in self.shapes.names else first.stop) + REACH

    def close(self) -> list:
        out = []
        while self._waiting:
            after = self._waiting[1] if len(self._waiting) > 1 else None
            out += self._decide(self._waiting.pop(0), after, len(self.tokens))
        if self._unknown is not None:
            out.append(self._unknown)
            self._unknown = None
        return out

    def _decide(self, seg, after, known: int) -> list:
        from grammar.matcher import UNKNOWN

        first = max(seg.first, self._done)
        if first >= seg.stop:
            return []
        if seg.action == UNKNOWN and SPOT_TOKENS <= seg.stop - first <= SPOT_MAX:
            best = self._best(range(first, seg.stop), [(first + 2, seg.stop)], known, SPOT)
        elif seg.action in self.shapes.names:
            pending = self._unknown is not None and self._unknown.stop == first
            lowest = self._unknown.first if pending else first  # it may take back tokens of an unknown run
            back = UNKNOWN_REACH if pending else REACH
            ends = [(seg.stop - TRIM, seg.stop + REACH)]
            if after is not None and after.action in self.shapes.names:  # one gesture the Matcher cut in two
                ends.append((after.stop - TRIM, after.stop + REACH))
            elif after is not None and after.action == UNKNOWN:
                ends.append((seg.stop, min(after.stop, seg.stop + UNKNOWN_REACH)))
            best = self._best(range(max(lowest, seg.first - back), min(seg.stop, seg.first + TRIM + 1)), ends, known)
        else:
            return self._emit(seg.action, first, seg.stop, seg.exact, seg.distance)
        if best is None:
            return self._emit(UNKNOWN, first, seg.stop, False, None)
        f, e, k, edits = best
        if f < first:  # taken back from the pending unknown run
            pending = self._unknown
            self._unknown = None if f <= pending.first else replace(pending, stop=f, end=self.tokens[f - 1].end)
            self._done = f
        return (self._emit(UNKNOWN, first, f, False, None) + self._emit(self.shapes.names[k], f, e, edits == 0.0, edits)
                + self._emit(UNKNOWN, e, seg.stop, False, None))

    def _best(self, starts: range, ends: list, known: int, strict: float = 1.0):
        """The best (first, stop, action, edits) over windows starting in ``starts`` and
        ending in one of the ``ends`` intervals, or None when its shape distance is over
        ``strict`` × the action's rejection distance."""
        from doodle.core.tokens import CODES

        names = [k.name for k in self.tokens]
        auto = self.shapes.automaton
        last = min(known, max(hi for _, hi in ends))
        windows, edits, dirs = [], [], []
        for f in starts:
            if names[f] == "T_STILL":
                continue
            d = auto.initial.copy()
            for e in range(f + 1, last + 1):
                d = auto.step(d, CODES[names[e - 1]])
                if not any(lo <= e <= hi for lo, hi in ends) or names[e - 1] == "T_STILL":
                    continue
                a, b = self.tokens[f].start, self.tokens[e - 1].end
                path = self.p[a:b][self.valid[a:b]]
                if len(path) >= 3:
                    windows.append((f, e))
                    edits.append(auto.accept_costs(d))
                    dirs.append(directions(resample(path)))
        if not windows:
            return None
        ds = self.shapes.distances(np.array(dirs))  # (windows, actions)
        edits = np.array(edits)
        score = np.where(self._allowed, edits + WEIGHT * ds, np.inf)
        w, k = np.unravel_index(int(np.argmin(score)), score.shape)
        if not np.isfinite(score[w, k]) or ds[w, k] > strict * self.shapes.reject[k]:
            return None
        return windows[w][0], windows[w][1], int(k), float(edits[w, k])

    def _emit(self, action: str, f: int, e: int, exact: bool, distance) -> list:
        from grammar.matcher import UNKNOWN, Segment

        if e <= f:
            return []
        self._done = e
        t0, t1 = self.tokens[f], self.tokens[e - 1]
        if action == UNKNOWN:  # neighbouring unknowns are one
            prev = self._unknown
            self._unknown = Segment(UNKNOWN, f if prev is None else prev.first, e,
                                    t0.start if prev is None else prev.start, t1.end, False, None)
            return []
        out = [self._unknown] if self._unknown is not None else []
        self._unknown = None
        return out + [Segment(action, f, e, t0.start, t1.end, exact, distance)]
