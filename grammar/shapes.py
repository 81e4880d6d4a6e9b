"""Shapes of learned actions: where the tokens are not enough to tell two gestures apart.

The Segmenter's tokens quantise a path to 26 directions and pauses; two whole-body gestures
of one person (a left and a right hook, an uppercut and a golf swing) often give token
strings 5–10 edits apart between repetitions and as close to each other's expressions as to
their own. A learned action therefore keeps the *shapes* of its examples as well: each
example's path resampled to :data:`POINTS` points by arc length with the controller's
orientation there (:func:`sample`; a two-handed action's tracks resampled together, along
their summed arc length). Its features per step (:func:`features`) are the unit direction
of the step and how the controller has turned (weighted by :data:`TURN`, unless a
library's own examples show another weight clearly better, :func:`choose_turn`), in the
room's frame — a performer faces the table, so left and right mean something, and how the
hand turns tells one person's uppercut from their hook; the turn is read relative to the
window, so however each person holds the controller, the same hand movement reads the
same. The shape distance of a performance to an action is the smallest DTW cost between
its features and an example's, per step; an action is rejected past a distance derived from
its examples (:func:`reject_distances`). How the distances re-decide the Matcher's segments
is :mod:`grammar.refiner`'s.

DTW costs of one performance against every template are computed at once (one row
recurrence vectorised over templates), about 0.2 ms for 33 templates of 31 steps.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

POINTS = 32  # points per resampled path (31 steps)
CHUNK = 2048  # paths × templates compared at once (a few MB)
MAX_METRES = 1000.0  # a shape file's coordinates beyond this are not a hand's path but a corrupt file


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


def dtw_costs(x: np.ndarray, templates: np.ndarray, part: tuple | None = None) -> np.ndarray:
    """DTW cost (squared l2, steps (1,1), (1,0), (0,1)) of x (n, d) — or of each of a batch
    (B, n, d) — against every template (k, m, d) at once, divided by the longer length:
    (k,), or (B, k). With ``part = (lo, hi)``, open-ended: x against the template's
    beginning that fits it best, from ``lo`` to ``hi`` of its steps (x as the start of a
    performance of it; open-end DTW)."""
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
            - 2.0 * np.matmul(xb[:, None], templates.transpose(0, 2, 1)[None]))
    cost = np.maximum(cost, 0.0).reshape(b * k, n, m)
    row = np.cumsum(cost[:, 0, :], axis=1)
    inf = np.full((b * k, 1), np.inf)
    for i in range(1, n):
        base = cost[:, i, :] + np.concatenate([inf, np.minimum(row[:, :-1], row[:, 1:])], axis=1)
        base[:, 0] = cost[:, i, 0] + row[:, 0]
        c = np.cumsum(cost[:, i, :], axis=1)
        row = np.minimum.accumulate(base - c, axis=1) + c  # from (i, j-1): a prefix minimum
    if part is None:
        out = row[:, -1].reshape(b, k) / max(n, m)
    else:
        j = np.arange(m)
        ends = (j >= int(part[0] * (m - 1))) & (j <= int(part[1] * (m - 1)))
        out = np.where(ends, row / np.maximum(n, j + 1), np.inf).min(axis=1).reshape(b, k)
    return out[0] if single else out


# --- poses of one or several tracks: resampled together, as features ---------------------

PACE = 2.0  # weight of the share of time gone by beside the path's directions (`make bench` shows it held out)
TURN = 0.5  # weight of the controller's turn beside the path's directions (a library's examples may
#             overrule it: choose_turn; `make bench` shows it held out)


def sample(poses, points: int = POINTS) -> tuple[np.ndarray, np.ndarray]:
    """Tracks performed together — ``[(p (n, 3), q (n, 4)), …]``, the same samples —
    resampled to ``points`` points equally spaced along their *summed* arc length (one
    time axis for both hands: the one that moves drives it, the other is read at the same
    moments): paths (T, points, 3) from their first points, orientations (T, points, 4)."""
    poses = [(np.asarray(p, dtype=float), np.asarray(q, dtype=float)) for p, q in poses]
    s = _summed_arc(poses)
    paths, quats = [], []
    for p, q in poses:
        q = np.where(np.isfinite(q).all(axis=1, keepdims=True), q, [0.0, 0.0, 0.0, 1.0])
        q = q / np.maximum(np.linalg.norm(q, axis=1, keepdims=True), 1e-12)
        q = q * np.where(np.cumsum(np.concatenate([[False], (q[1:] * q[:-1]).sum(1) < 0])) % 2 == 1, -1.0, 1.0)[:, None]
        if s[-1] <= 0:
            paths.append(np.zeros((points, 3)))
            quats.append(np.repeat(q[:1], points, axis=0))
            continue
        u = np.linspace(0.0, s[-1], points)
        paths.append(np.column_stack([np.interp(u, s, p[:, k] - p[0, k]) for k in range(3)]))
        r = np.column_stack([np.interp(u, s, q[:, k]) for k in range(4)])
        quats.append(r / np.maximum(np.linalg.norm(r, axis=1, keepdims=True), 1e-12))
    return np.array(paths), np.array(quats)


def _summed_arc(poses) -> np.ndarray:
    """The tracks' summed path length at each sample, from 0."""
    s = np.zeros(len(poses[0][0]))
    for p, _ in poses:
        s[1:] += np.cumsum(np.linalg.norm(np.diff(np.asarray(p, dtype=float), axis=0), axis=1))
    return s


def times(poses, t: np.ndarray, motion: tuple | None = None, points: int = POINTS) -> np.ndarray:
    """The share of the motion's time gone by at each of :func:`sample`'s points (points,),
    0 to 1: ``t`` the samples' times, ``motion`` the times ``(t0, t1)`` the motion lasts
    (default: the first to the last sample; a learned example's still ends are left out so,
    as a window holds no pause at its ends)."""
    t = np.asarray(t, dtype=float)
    t0, t1 = (t[0], t[-1]) if motion is None else motion
    s = _summed_arc(poses)
    if s[-1] <= 0 or t1 <= t0:
        return np.linspace(0.0, 1.0, points)
    at = np.interp(np.linspace(0.0, s[-1], points), s, t)
    return np.clip((at - t0) / (t1 - t0), 0.0, 1.0)


def features(paths: np.ndarray, quats: np.ndarray | None, turn: float | None = None,
             elapsed: np.ndarray | None = None, pace: float | None = None) -> np.ndarray:
    """Per step of resampled tracks (T, n, 3) — and their orientations (T, n, 4) — the unit
    direction of each track's step and, weighted by ``turn`` (default :data:`TURN`), how its
    controller is turned from its mean orientation over the path ``q̄``: the rotation
    ``q(s) q̄⁻¹`` in the room's frame applied to the room's three axes (n − 1, T·3) or
    (n − 1, T·12).

    The turn, not the controller's orientation itself: a controller held in the hand at a
    grip offset ``g`` reads ``q = h g`` (``h`` the hand's orientation), whose mean is
    ``h̄ g``, so ``q(s) q̄⁻¹ = h(s) h̄⁻¹`` — the same for every way of holding it. The mean,
    not the first sample, is the reference: a window that starts while the wrist turns in
    place (no path, so no weight in the arc-length resampling) would otherwise shift every
    step's feature. How the hand
    turns as it moves (a hook's forearm roll, an uppercut's lift) is the person's gesture;
    how they hold the controller is not.

    With ``elapsed`` (:func:`times`, the share of the motion's time gone by at each point), a
    last column, weighted by ``pace`` (default :data:`PACE`): that share at each step's
    middle. Arc-length resampling alone is blind to time — a still stretch, however long, is
    a few steps of noise — so a window holding a gesture and a small one beside it (a combo,
    then a hook that barely moves this hand) reads as the first alone; with time, the
    stretch the small one lasts moves every later step's share away from the examples'."""
    from doodle.core import quat

    turn = TURN if turn is None else turn
    pace = PACE if pace is None else pace
    cols = []
    for k, path in enumerate(paths):
        cols.append(directions(path))
        if quats is not None and turn > 0:
            q = quats[k]
            mid = q[1:] + q[:-1] * np.where((q[1:] * q[:-1]).sum(1, keepdims=True) < 0, -1.0, 1.0)
            mid = mid / np.maximum(np.linalg.norm(mid, axis=1, keepdims=True), 1e-12)
            mean = mid.sum(axis=0)
            mean = mean / max(float(np.linalg.norm(mean)), 1e-12)
            since = quat.multiply(mid, quat.conjugate(np.broadcast_to(mean, mid.shape)))
            cols += [turn * quat.rotate(since, axis) for axis in np.eye(3)]
    if elapsed is not None and pace > 0:
        cols.append(pace * 0.5 * (elapsed[1:] + elapsed[:-1])[:, None])
    return np.hstack(cols)


# --- a library's shapes ----------------------------------------------------------------

@dataclass(frozen=True, eq=False)
class Group:
    """Actions whose examples read the same tracks the same way: one DTW batch.

    ``tracks`` are the tracks read, in order, the first being the one the action is
    recognised on (one track: that track or, for actions not bound to one, whichever is
    refined — stored as ``(None,)``); ``oriented`` whether orientations were kept."""

    tracks: tuple
    oriented: bool
    templates: np.ndarray  # (K, POINTS - 1, D) features of every example of the group's actions
    owner: np.ndarray  # (K,) index into ShapeSet.names, sorted
    turn: float = TURN  # the weight of orientation in its features (:func:`choose_turn`)
    pace: float = 0.0  # the weight of the time gone by in its features (0: its examples' times are not known)


@dataclass(frozen=True, eq=False)
class ShapeSet:
    """The learned actions that carry shapes, ready to rank segments."""

    names: tuple[str, ...]
    groups: tuple  # of Group
    reject: np.ndarray  # (len(names),) shape distance above which a segment is not that action
    automaton: object  # grammar.matcher.Automaton of the names' expressions (edit distances, capped)
    tracks: tuple = ()  # per name, the track it is recognised on (None: any)
    partners: tuple = ()  # per name, the other tracks it is performed with (two-handed actions), or ()
    longest: np.ndarray | None = None  # per name, its longest example's seconds (inf: not known)
    shortest: np.ndarray | None = None  # per name, its shortest example's seconds (0: not known)

    def allowed(self, track: str | None, present=None) -> np.ndarray:
        """Which actions may be recognised on ``track`` (two-handed ones: when every track
        they read is among ``present``)."""
        bound = self.tracks or (None,) * len(self.names)
        partners = self.partners or ((),) * len(self.names)
        return np.array([(b is None or track is None or b == track)
                         and (not others or present is None or all(o in present for o in others))
                         for b, others in zip(bound, partners)])

    def distances_of(self, windows: list, read, part: tuple | None = None) -> np.ndarray:
        """Per window and action, the shape distance (inf where the action was not scored).
        ``read(group, window)`` gives a window's (paths, quats, elapsed) for a group's tracks
        (:func:`sample`, :func:`times`), or None. With ``part``, to the examples' beginnings
        (:func:`dtw_costs`; the time gone by left out: a beginning's share of its example's
        time is not a window's of its own)."""
        out = np.full((len(windows), len(self.names)), np.inf)
        for g in self.groups:
            pace = g.pace if part is None else 0.0
            feats, rows = [], []
            for w, window in enumerate(windows):
                pq = read(g, window)
                if pq is not None:
                    feats.append(features(pq[0], pq[1] if g.oriented else None, g.turn, pq[2], pace))
                    rows.append(w)
            if rows:
                templates = g.templates if pace == g.pace else g.templates[..., :-1]
                out[np.array(rows)[:, None], np.unique(g.owner)[None, :]] = _nearest(g, np.array(feats), part,
                                                                                     templates)
        return out

    def distances(self, x: np.ndarray) -> np.ndarray:
        """Per action, the distance of features x (n, D) — or of a batch (B, n, D) — to its
        examples, for a set of one group (inf for actions of other shapes)."""
        single = x.ndim == 2
        xb = x[None] if single else x
        out = np.full((len(xb), len(self.names)), np.inf)
        for g in self.groups:
            if g.templates.shape[-1] == xb.shape[-1]:
                out[:, np.unique(g.owner)] = _nearest(g, xb)
        return out[0] if single else out


def _nearest(group: Group, x: np.ndarray, part: tuple | None = None, templates: np.ndarray | None = None) -> np.ndarray:
    """(B, actions of the group): the smallest DTW cost of each of x to each action's examples
    (with ``part``, to their beginnings: :func:`dtw_costs`; ``templates`` instead of the
    group's own, the same examples' features read otherwise)."""
    templates = group.templates if templates is None else templates
    if len(x) * len(templates) > CHUNK:  # bounded memory: in chunks
        step = max(1, CHUNK // len(templates))
        return np.concatenate([_nearest(group, x[k:k + step], part, templates) for k in range(0, len(x), step)])
    costs = dtw_costs(x, templates, part)
    starts = np.searchsorted(group.owner, np.unique(group.owner))
    return np.minimum.reduceat(costs, starts, axis=-1)


FORMAT = 2
STRADDLES = 4  # synthetic negatives per example: joined to this many others, spread over the library


def save_paths(path, paths: np.ndarray, quats: np.ndarray | None = None, seconds=None, elapsed=None) -> None:
    """Write example shapes to ``path`` (.npz, no pickles), atomically: paths (k, n, 3) of
    one track (format 1), or paths (k, T, n, 3) with orientations (k, T, n, 4) of T tracks
    read together (format 2); with ``seconds`` (k,), how long each example lasted, and with
    ``elapsed`` (k, n), the share of its time gone by at each point (:func:`times`)."""
    from doodle.core.files import atomic_path

    extra = {} if seconds is None else {"seconds": np.asarray(seconds, dtype=float)}
    if elapsed is not None:
        extra["elapsed"] = np.asarray(elapsed, dtype=float)
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            if quats is None:
                np.savez(f, paths=np.asarray(paths, dtype=float), format=np.array(1), **extra)
            else:
                np.savez(f, paths=np.asarray(paths, dtype=float), quats=np.asarray(quats, dtype=float),
                         format=np.array(2), **extra)


def load_paths(path, action: str = "") -> np.ndarray:
    """Example paths (k, n, 3) of the first track of a shape file; DoodleError naming the file and action."""
    return load_shape(path, action)[0][:, 0]


def load_shape(path, action: str = "") -> tuple:
    """Example paths (k, T, n, 3), orientations (k, T, n, 4) or None (format 1, paths
    alone), each example's duration in seconds (k,) and the share of its time gone by at
    each point (k, n), each None where the file was written without; DoodleError naming the
    file and action."""
    from doodle.core.errors import DoodleError
    from doodle.core.npz import read_npz

    where = f"{path}" + (f" (shape of action {action!r})" if action else "")
    arrays = read_npz(path, where)
    if "paths" not in arrays:
        raise DoodleError(f"{where}: no 'paths' array in it")
    version = 1
    if "format" in arrays:
        v = arrays["format"]
        if v.shape != () or v.dtype.kind not in "iu" or int(v) not in (1, 2):
            raise DoodleError(f"{where}: shape format {v.tolist()!r} is not supported (this version reads 1 and 2)")
        version = int(v)
    paths = arrays["paths"]
    quats = arrays.get("quats") if version == 2 else None
    if paths.dtype.kind == "f" and paths.ndim == 3:
        paths = paths[:, None]
    if paths.dtype.kind != "f" or paths.ndim != 4 or paths.shape[0] < 1 or paths.shape[2:] != (POINTS, 3):
        raise DoodleError(f"{where}: 'paths' must be a float array (examples, points = {POINTS}, 3) or (examples, "
                          f"tracks, points = {POINTS}, 3), got {paths.dtype} {paths.shape}")
    if quats is not None and (quats.dtype.kind != "f" or quats.shape != paths.shape[:3] + (4,)):
        raise DoodleError(f"{where}: 'quats' must be a float array {paths.shape[:3] + (4,)}, got "
                          f"{quats.dtype} {quats.shape}")
    if not np.isfinite(paths).all() or (quats is not None and not np.isfinite(quats).all()):
        raise DoodleError(f"{where}: 'paths' or 'quats' holds NaN or infinite values")
    if np.abs(paths).max() > MAX_METRES:
        raise DoodleError(f"{where}: 'paths' reaches {np.abs(paths).max():.3g} m from its start; "
                          f"a hand's path stays within {MAX_METRES:g} m")
    if quats is not None and np.abs(quats).max() > 2.0:
        raise DoodleError(f"{where}: 'quats' are not unit quaternions")
    seconds = arrays.get("seconds")
    if seconds is not None and (seconds.dtype.kind not in "fiu" or seconds.shape != paths.shape[:1]
                                or not np.isfinite(seconds).all() or seconds.min() <= 0):
        raise DoodleError(f"{where}: 'seconds' must be one positive duration per example ({paths.shape[0]}), "
                          f"got {seconds.dtype} {seconds.shape}")
    elapsed = arrays.get("elapsed")
    if elapsed is not None and (elapsed.dtype.kind != "f" or elapsed.shape != (paths.shape[0], POINTS)
                                or not np.isfinite(elapsed).all() or elapsed.min() < 0 or elapsed.max() > 1
                                or (np.diff(elapsed, axis=1) < 0).any()):
        raise DoodleError(f"{where}: 'elapsed' must be a float array ({paths.shape[0]}, {POINTS}) rising from 0 "
                          f"to 1 along each example, got {elapsed.dtype} {elapsed.shape}")
    return paths.astype(float), (None if quats is None else quats.astype(float)), \
        (None if seconds is None else seconds.astype(float)), (None if elapsed is None else elapsed.astype(float))


def shape_set(named: dict, expressions: dict, tracks: dict | None = None, cap: float = 20.0,
              automaton=None, partners: dict | None = None) -> ShapeSet | None:
    """A :class:`ShapeSet` from ``{action: example shapes}`` — paths (k, n, 3), or
    ``(paths (k, T, n, 3), quats (k, T, n, 4) | None[, seconds (k,) | None[, elapsed (k, n) |
    None]])`` (:func:`load_shape`) — the actions' expressions, the
    tracks they are recognised on (``{action: track}``, default none) and, for actions read
    on several tracks, the others (``{action: (track, …)}``); None when no action has
    shapes. Edit distances count up to ``cap``; ``automaton``, when given, is a ready one
    of the same expressions in the same order (no pause protection)."""
    if not named:
        return None
    from grammar.automata import compile_expression
    from grammar.expr import parse
    from grammar.matcher import Automaton

    names = tuple(named)
    tracks, partners = tracks or {}, partners or {}
    keyed, longest, shortest = {}, np.full(len(names), np.inf), np.zeros(len(names))
    for k, n in enumerate(names):
        shape = named[n]
        paths, quats, seconds, elapsed = ((shape, None, None, None) if isinstance(shape, np.ndarray)
                                          else (tuple(shape) + (None, None))[:4])
        longest[k] = np.inf if seconds is None else float(np.max(seconds))
        shortest[k] = 0.0 if seconds is None else float(np.min(seconds))
        paths = np.asarray(paths, dtype=float)
        if paths.ndim == 3:
            paths = paths[:, None]
        others = tuple(partners.get(n, ()))
        timed = elapsed is not None and PACE > 0
        key = ((tracks.get(n),) + others if others else (None,), quats is not None, paths.shape[1], timed)
        keyed.setdefault(key, []).append((k, paths, quats, np.asarray(elapsed, dtype=float) if timed else None,
                                          np.ones(len(paths)) if seconds is None else np.asarray(seconds, dtype=float)))
    groups, reject = [], np.zeros(len(names))
    for (read, oriented, _, timed), shapes in keyed.items():
        owner = np.concatenate([np.full(len(paths), k) for k, paths, *_ in shapes])
        pace = PACE if timed else 0.0
        turn = choose_turn(shapes, owner, pace) if oriented else 0.0
        oriented = oriented and turn > 0
        members = [(k, np.array([features(paths[j], quats[j] if oriented else None, turn,
                                          None if elapsed is None else elapsed[j], pace) for j in range(len(paths))]),
                    paths, quats if oriented else None, elapsed, seconds) for k, paths, quats, elapsed, seconds in shapes]
        templates = np.concatenate([f for _, f, *_ in members])
        group = Group(read, oriented, templates, owner, turn, pace)
        groups.append(group)
        reject[[k for k, *_ in members]] = reject_distances(group, members)
    auto = automaton or Automaton(list(names), [compile_expression(parse(expressions[n], n)) for n in names],
                                  threshold=cap, protect_still=False)
    return ShapeSet(names, tuple(groups), reject, auto, tuple(tracks.get(n) for n in names),
                    tuple(tuple(partners.get(n, ())) for n in names), longest, shortest)


TURNS = (0.0, 0.25, 0.5, 1.0)  # the orientation weights a library may choose among (:func:`choose_turn`)
EVIDENCE = 0.05  # a library leaves TURN only when its examples show another weight better at this level


def choose_turn(shapes: list, owner: np.ndarray, pace: float = 0.0) -> float:
    """The weight of the controllers' turn in a group's features: :data:`TURN` unless the
    group's own examples (``[(action, paths, quats[, elapsed, …])]``, ``owner`` their
    actions in order; ``pace`` the group's weight of the time gone by)
    show clearly that another weight of :data:`TURNS` tells their actions apart better.
    Each example is left out in turn and read by its nearest other example; the best other
    weight (most examples read right; on a tie, the larger mean log ratio of each example's
    distance to the nearest example of another action over that to the nearest of its own)
    is taken only when it reads right significantly more of them than :data:`TURN` does —
    a one-sided exact sign test on the examples the two weights read differently, at
    :data:`EVIDENCE` shared among the weights tried (Bonferroni).

    Why a test and not the best count: three examples per action give a few dozen reads,
    and the counts of the weights differ by one or two by chance. Chosen freely, the
    weight followed that noise — on the Vive recordings with examples from three other
    people it went from 0 to 1 between libraries, and read a fifth person's gestures worse
    than the default did (by the nearest example alone, on c0, over every such library:
    0.88 of them right against 0.90). A gesture set told apart by the turn alone (a
    twist left and a twist right along one path), or by the path alone (a controller held
    loosely), still moves it. Examples from several people show whether their turns agree
    (an example left out is then read by the others' examples alone); nothing is tuned on
    the performances to be recognised."""
    if len(set(owner.tolist())) < 2 or len(owner) < 3:
        return TURN
    reads, keys = {}, {}
    for turn in sorted(set(TURNS) | {TURN}):
        feats = np.array([features(paths[j], quats[j] if turn > 0 else None, turn,
                                   rest[0][j] if rest and rest[0] is not None else None, pace)
                          for _, paths, quats, *rest in shapes for j in range(len(paths))])
        everyone = np.concatenate([dtw_costs(feats[k:k + CHUNK // len(feats) + 1], feats)
                                   for k in range(0, len(feats), CHUNK // len(feats) + 1)])  # (K, K)
        right, ratios = [], []
        for i in range(len(feats)):
            costs, rest = np.delete(everyone[i], i), np.delete(owner, i)
            own, other = costs[rest == owner[i]], costs[rest != owner[i]]
            right.append(bool(rest[int(np.argmin(costs))] == owner[i]))
            if len(own) and len(other):
                ratios.append(other.min() / max(own.min(), 1e-9))
        reads[turn] = np.array(right)
        keys[turn] = (int(np.sum(right)), float(np.mean(np.log(ratios))) if ratios else 0.0)
    others = [turn for turn in reads if turn != TURN]
    best = max(others, key=lambda turn: keys[turn])
    gained = int(np.sum(reads[best] & ~reads[TURN]))
    lost = int(np.sum(reads[TURN] & ~reads[best]))
    return best if _sign_test(gained, gained + lost) < EVIDENCE / len(others) else TURN


def _sign_test(k: int, n: int) -> float:
    """One-sided exact sign test: the chance of at least ``k`` successes in ``n`` fair coin tosses."""
    from math import comb

    return sum(comb(n, j) for j in range(k, n + 1)) / 2.0 ** n if n else 1.0


SPREAD = 0.95  # an action's spread admits this share of new performances like its examples (:func:`prediction_bound`)


@lru_cache(maxsize=None)
def prediction_bound(level: float, draws: int) -> float:
    """How many root mean squares of ``draws`` draws of a zero-mean normal a new draw's
    magnitude stays within, with probability ``level``: the two-sided quantile of Student's
    t with ``draws`` degrees of freedom (the new draw over the root mean square is t
    distributed, the variance being estimated, not known). With the variance known it would
    be the normal's quantile (1.96 at 0.95); from three draws it is 3.18 — three distances
    say little about the fourth. Computed as ``√ν tan θ``, θ where the integral of
    ``cos^(ν−1)`` from 0 reaches ``level`` of its integral to π/2 (T = √ν tan θ)."""
    if level <= 0 or draws < 1:
        return 0.0
    theta = np.linspace(0.0, np.pi / 2, 4097)
    w = np.cos(theta) ** (draws - 1)
    cdf = np.concatenate([[0.0], np.cumsum((w[1:] + w[:-1]) / 2)])
    return float(np.sqrt(draws) * np.tan(np.interp(min(level, 0.9999) * cdf[-1], cdf, theta)))


def reject_distances(group: Group, members: list) -> np.ndarray:
    """How far from its examples a performance of each action of a group may be — derived
    from the examples, nothing tuned: midway between how far the action's own examples are
    from each other and how near it
    comes to *straddles* — the second half of one example joined to the first half of
    another, of any action: what a window across two performances looks like in a stream
    (the synthetic negatives of Jackknife, Taranta et al. 2017, spliced from the
    examples). Where the straddles come nearer than the own examples, the own examples'
    spread stands (a performance like the examples is never rejected).

    The spread: each example's distance to the nearest of the others (leave one out) is
    taken as a draw from a half-normal — a performance's deviation from a template as
    noise — and a new performance bounded where it falls with probability :data:`SPREAD`
    (95 %): their root mean square times :func:`prediction_bound` (3.18 for three
    examples, the variance being estimated from three draws); never less than the largest
    of them. The largest of three alone would reject a quarter of new performances like
    them (a fourth draw exceeds the largest of three with probability ¼), and more from a
    person the examples did not come from."""
    pieces = []  # (paths (T, n, 3), quats or None, times (n,) in seconds or None) of every example
    for _, _, paths, quats, elapsed, seconds in members:
        pieces += [(paths[j], None if quats is None else quats[j], None if elapsed is None else elapsed[j] * seconds[j])
                   for j in range(len(paths))]
    half = POINTS // 2
    n = len(pieces)  # each example followed by STRADDLES others spread over the library
    pairs = sorted({(i, (i + 1 + m * max(1, (n - 1) // STRADDLES)) % n) for i in range(n)
                    for m in range(min(STRADDLES, n - 1))})
    straddles = []
    for i, j in pairs:
        (pa, qa, ta), (pb, qb, tb) = pieces[i], pieces[j]
        poses = []
        for t in range(len(pa)):
            join = pa[t, -1] - pa[t, half]  # b's first half moved on from where a's second half ends
            p = np.concatenate([pa[t, half:] - pa[t, half], pb[t, :half + 1] - pb[t, 0] + join])
            q = (np.concatenate([qa[t, half:], qb[t, :half + 1]]) if qa is not None
                 else np.tile([0.0, 0.0, 0.0, 1.0], (len(p), 1)))
            poses.append((p, q))
        paths, quats = sample(poses)
        elapsed = None if ta is None else times(poses, np.concatenate([ta[half:], ta[-1] + tb[:half + 1]]))
        straddles.append(features(paths, quats if qa is not None else None, group.turn, elapsed, group.pace))
    near = _nearest(group, np.array(straddles)).min(axis=0) if straddles else None
    out = []
    for slot, (k, *_) in enumerate(members):
        own = group.templates[group.owner == k]
        if len(own) < 2:
            spread = 0.0
        else:
            loo = [float(dtw_costs(own[j], np.delete(own, j, axis=0)).min()) for j in range(len(own))]
            spread = max(max(loo), prediction_bound(SPREAD, len(loo)) * float(np.sqrt(np.mean(np.square(loo)))))
        if near is None:
            out.append(2.0 * spread)
            continue
        out.append(max(spread, 0.5 * (spread + float(near[slot]))))
    return np.array(out)
