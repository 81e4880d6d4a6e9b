"""Learning an action's expression from a few performed examples (thesis §4.2.5).

1. **Average** the examples with DTW barycenter averaging (Petitjean, Ketterlin & Gançarski
   2011, "A global averaging method for dynamic time warping", Pattern Recognition 44(3);
   the thesis follows Ciccone et al. 2017): each example is put in its own starting frame
   (positions relative to the first sample, in the first orientation's axes; orientations
   relative to the first), resampled to :data:`POINTS` samples, and the average — started
   from the medoid — is refined by aligning every example to it with DTW and taking the mean
   of the points aligned to each of its samples (quaternions: the normalised mean of the
   sign-aligned ones). It gets the examples' mean duration.
2. **Tokenise** the n examples and the average (leading and trailing pauses dropped): n + 1
   token strings.
3. **Mandatory tokens**: a token that occurs in more than two of the strings (the thesis's
   "repeated more than twice") is mandatory, any other optional.
4. **Align** the strings' mandatory subsequences — each to the average's, by the
   Levenshtein alignment (the thesis parses them "in parallel" position by position; an
   alignment keeps a missing or extra token from shifting every later column) — into
   columns ``r_k = (m_k0 | … | m_kn)``, written ``r_k+`` when every string has a token in the
   column and ``r_k*`` otherwise (the thesis's rule for columns past the shortest string).
5. **Optional tokens** between two columns go in a group before the later one,
   ``((o…)|(o…)|…)*`` with one alternative per string that has any there — or, when every
   string has the same non-empty run there, as that run itself (a "quick intentional"
   gesture, mandatory).

By construction every example's (and the average's) token string is accepted; the tests
check it as a property. :func:`learn` returns the expression and the token strings it came
from; :func:`collisions` tells which library actions accept some string it accepts.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from doodle.core import quat
from doodle.core.errors import DoodleError
from doodle.core.model import Track
from doodle.input.segmenter import SegmenterParams, tokenize
from grammar import shapes

POINTS = 128  # samples per example for the DTW average
ITERATIONS = 8
LEVER = 0.1  # m: orientations weigh in DTW as rotation vectors times a hand's lever arm
MIN_EXAMPLES = 2
MIN_TOLERANCE = 2.0  # the Matcher's default: a learned action is never stricter
MAX_TOLERANCE = 12.0


@dataclass(frozen=True)
class Learned:
    expression: str
    strings: tuple[tuple[str, ...], ...]  # the examples' token strings, then the average's
    mandatory: frozenset
    tolerance: float | None = None  # edits a new performance may be from the expression
    paths: np.ndarray | None = None  # the examples' paths resampled by arc length (grammar.shapes)


def canonical(t: np.ndarray, p: np.ndarray, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An example in its own starting frame: times from 0, positions from the first sample
    in the first orientation's axes, orientations relative to the first."""
    q = quat.make_continuous(quat.normalise(q))
    q0 = np.broadcast_to(q[0], q.shape)
    return (t - t[0], quat.rotate_inverse(q0, p - p[0]),
            quat.make_continuous(quat.multiply(quat.conjugate(q0), q)))


def _resample(t, x, n):
    grid = np.linspace(t[0], t[-1], n)
    return np.column_stack([np.interp(grid, t, c) for c in x.T])


def _dtw_paths(a: np.ndarray, bs: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Indices (i, j) of the optimal DTW alignment (squared l2 cost) of a (n, d) with each
    of bs (k, m, d) — the cumulative costs of all k computed at once, row by row."""
    bs = np.asarray(bs, dtype=float)
    k, m, _ = bs.shape
    n = len(a)
    cost = ((a[None, :, None, :] - bs[:, None, :, :]) ** 2).sum(axis=3)  # (k, n, m)
    D = np.empty((k, n, m))
    D[:, 0] = np.cumsum(cost[:, 0], axis=1)
    for i in range(1, n):
        base = np.empty((k, m))
        base[:, 0] = cost[:, i, 0] + D[:, i - 1, 0]
        base[:, 1:] = cost[:, i, 1:] + np.minimum(D[:, i - 1, :-1], D[:, i - 1, 1:])  # from (i-1, j-1) or (i-1, j)
        c = np.cumsum(cost[:, i], axis=1)  # from (i, j-1): a prefix minimum
        D[:, i] = np.minimum.accumulate(base - c, axis=1) + c
    out = []
    for Dk in D.tolist():  # Python floats: the walk back reads them one by one
        i, j = n - 1, m - 1
        path = [(i, j)]
        while i > 0 or j > 0:
            if i == 0:
                j -= 1
            elif j == 0:
                i -= 1
            else:
                diag, up, left = Dk[i - 1][j - 1], Dk[i - 1][j], Dk[i][j - 1]
                if diag <= up and diag <= left:
                    i, j = i - 1, j - 1
                elif up <= left:
                    i -= 1
                else:
                    j -= 1
            path.append((i, j))
        ij = np.array(path[::-1])
        out.append((ij[:, 0], ij[:, 1]))
    return out


def _dtw_path(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Indices (i, j) of the optimal DTW alignment of a (n, d) and b (m, d), squared l2 cost."""
    return _dtw_paths(a, b[None])[0]


def dba(examples: list[tuple[np.ndarray, np.ndarray, np.ndarray]], points: int = POINTS,
        iterations: int = ITERATIONS) -> Track:
    """The DTW barycenter average of examples ``(t, p, q)`` as a track."""
    feats, quats = [], []
    for t, p, q in examples:
        t, p, q = canonical(t, p, q)
        qs = _resample(t, q, points)
        quats.append(qs / np.linalg.norm(qs, axis=1, keepdims=True))
        feats.append(np.column_stack([_resample(t, p, points), LEVER * quat.log(quats[-1])]))
    from grammar.shapes import dtw_costs

    stacked = np.array(feats)
    dist = np.array([dtw_costs(f, stacked) for f in feats])
    medoid = int(np.argmin(dist.sum(axis=1)))
    avg, avg_q = feats[medoid].copy(), quats[medoid].copy()
    for _ in range(iterations):
        sums, qsum, counts = np.zeros_like(avg), np.zeros_like(avg_q), np.zeros(points)
        for f, qq, (i, j) in zip(feats, quats, _dtw_paths(avg, stacked)):
            np.add.at(sums, i, f[j])
            signs = np.where(np.sum(qq[j] * avg_q[i], axis=1) < 0, -1.0, 1.0)
            np.add.at(qsum, i, qq[j] * signs[:, None])
            np.add.at(counts, i, 1)
        new = sums / counts[:, None]
        avg_q = qsum / np.linalg.norm(qsum, axis=1, keepdims=True)
        if np.allclose(new, avg, atol=1e-6):
            avg = new
            break
        avg = new
    duration = float(np.mean([t[-1] - t[0] for t, _, _ in examples]))
    t = np.linspace(0.0, duration, points)
    return Track("average", t, avg[:, :3], quat.make_continuous(avg_q), np.ones(points, dtype=bool))


def _dtw_cost(a, b) -> float:
    i, j = _dtw_path(a, b)
    return float(((a[i] - b[j]) ** 2).sum())


def token_string(track: Track, rate: float, params: SegmenterParams = SegmenterParams()) -> tuple[str, ...]:
    """A track's compacted token names without leading and trailing pauses."""
    names = [k.name for k in tokenize(track, rate, params)]
    while names and names[0] == "T_STILL":
        names.pop(0)
    while names and names[-1] == "T_STILL":
        names.pop()
    return tuple(names)


def _align(ref: list[str], seq: list[str]) -> list[tuple[int | None, int | None]]:
    """Levenshtein alignment of seq to ref: pairs (ref index | None, seq index | None)."""
    n, m = len(ref), len(seq)
    D = np.zeros((n + 1, m + 1))
    D[:, 0], D[0, :] = np.arange(n + 1), np.arange(m + 1)
    for i in range(1, n + 1):
        for j in range(1, m + 1):
            D[i, j] = min(D[i - 1, j] + 1, D[i, j - 1] + 1, D[i - 1, j - 1] + (ref[i - 1] != seq[j - 1]))
    pairs, i, j = [], n, m
    while i or j:
        if i and j and D[i, j] == D[i - 1, j - 1] + (ref[i - 1] != seq[j - 1]):
            pairs.append((i - 1, j - 1))
            i, j = i - 1, j - 1
        elif i and D[i, j] == D[i - 1, j] + 1:
            pairs.append((i - 1, None))
            i -= 1
        else:
            pairs.append((None, j - 1))
            j -= 1
    return pairs[::-1]


def expression_of(strings: list[tuple[str, ...]], reference: int = -1) -> Learned:
    """The compact expression of §4.2.5 accepting every string; mandatory columns are
    aligned to ``strings[reference]`` (the average's)."""
    strings = [tuple(s) for s in strings]
    if not any(strings):
        raise DoodleError("every example is still: nothing to learn (move the controller while recording)")
    present = {}
    for s in strings:
        for name in set(s):
            present[name] = present.get(name, 0) + 1
    mandatory = frozenset(n for n, c in present.items() if c > 2 or (len(strings) <= 2 and c == len(strings)))
    ref_index = reference % len(strings)
    ref_m = [x for x in strings[ref_index] if x in mandatory]
    if not ref_m:  # the average lost them: the longest mandatory subsequence leads
        ref_index = max(range(len(strings)), key=lambda k: sum(x in mandatory for x in strings[k]))
        ref_m = [x for x in strings[ref_index] if x in mandatory]
    columns = len(ref_m)
    # per string: the token in each column (or None) and the optional runs in each gap
    # (gap k comes before column k; gap `columns` after the last)
    cells, gaps = [], []
    for s in strings:
        mand = [(k, x) for k, x in enumerate(s) if x in mandatory]
        col = [None] * columns
        gap = [[] for _ in range(columns + 1)]
        where = {}  # position in s → column it was aligned to, or the gap before the next column
        next_col = 0
        for r, k in _align(ref_m, [x for _, x in mand]):
            if r is not None:
                next_col = r + 1
            if k is None:
                continue
            pos = mand[k][0]
            if r is not None and col[r] is None:
                col[r] = s[pos]
                where[pos] = ("col", r)
            else:
                where[pos] = ("gap", next_col if r is None else r + 1)
        next_col = 0
        for pos, x in enumerate(s):  # optional tokens (and unaligned mandatory ones) go in gaps
            kind = where.get(pos)
            if kind is not None and kind[0] == "col":
                next_col = kind[1] + 1
                continue
            gap[kind[1] if kind else next_col].append(x)
        cells.append(col)
        gaps.append(gap)
    parts = []
    for k in range(columns + 1):
        runs = sorted({tuple(g[k]) for g in gaps})
        if len(runs) == 1 and runs[0]:
            parts.append(" ".join(runs[0]))  # every string has this run: a quick intentional gesture
        elif any(runs):
            options = [" ".join(r) for r in runs if r]
            parts.append("(" + " | ".join(f"({o})" if " " in o else o for o in options) + ")*")
        if k < columns:
            tokens = sorted({c[k] for c in cells if c[k] is not None})
            body = tokens[0] if len(tokens) == 1 else "(" + " | ".join(tokens) + ")"
            parts.append(body + ("+" if all(c[k] is not None for c in cells) else "*"))
    return Learned(" ".join(parts), tuple(strings), mandatory)


def learn(examples: list[tuple[np.ndarray, np.ndarray, np.ndarray]], rate: float,
          params: SegmenterParams = SegmenterParams(), with_tolerance: bool = True) -> Learned:
    """The expression of §4.2.5 for examples ``(t, p, q)`` of one track each (and its
    :func:`tolerance`, unless ``with_tolerance`` is False)."""
    if len(examples) < MIN_EXAMPLES:
        raise DoodleError(f"learning needs at least {MIN_EXAMPLES} examples, got {len(examples)}")
    durations = [float(t[-1] - t[0]) for t, _, _ in examples]
    if min(durations) <= 0 or max(durations) > 10 * min(durations):
        raise DoodleError(f"examples last {', '.join(f'{d:.2f}' for d in durations)} s: one is more than 10× "
                          "another — were they all the same gesture?")
    strings = []
    for k, (t, p, q) in enumerate(examples):
        s = token_string(Track(f"example {k + 1}", t, p, q, np.ones(len(t), dtype=bool)), rate, params)
        if not s:
            raise DoodleError(f"example {k + 1} is all still: nothing was performed")
        strings.append(s)
    average = token_string(dba(examples), rate, params)
    learned = replace(expression_of(strings + ([average] if average else [])),
                      paths=np.array([shapes.resample(p) for _, p, _ in examples]))
    return replace(learned, tolerance=tolerance(learned.strings, len(strings))) if with_tolerance else learned


def distances(expressions: list[str], string: tuple[str, ...], cap: float = 40.0) -> np.ndarray:
    """Edit distance (insert, delete, substitute: 1 each) from a token string to each
    expression's language, capped at ``cap``."""
    return _run(_automaton(expressions, cap), string)


def _automaton(expressions: list[str], cap: float):
    from grammar.automata import compile_expression
    from grammar.expr import parse
    from grammar.matcher import Automaton

    return Automaton([str(k) for k in range(len(expressions))],
                     [compile_expression(parse(e)) for e in expressions], threshold=cap, protect_still=False)


def _run(auto, string: tuple[str, ...]) -> np.ndarray:
    from doodle.core.tokens import CODES

    d = auto.initial.copy()
    for name in string:
        d = auto.step(d, CODES[name])
    return auto.accept_costs(d)


def tolerance(strings: tuple[tuple[str, ...], ...], examples: int) -> float:
    """How far a new performance may be from the expression: each example's distance to the
    expression learned without it (leave one out), the largest, and one edit more — at
    least the Matcher's default, at most :data:`MAX_TOLERANCE`."""
    held = [k for k in range(examples) if any(s for j, s in enumerate(strings) if j != k)]
    if not held:
        return MIN_TOLERANCE
    from grammar.automata import compile_expression
    from grammar.expr import parse

    worst = max(_edit_distance(compile_expression(parse(expression_of([s for j, s in enumerate(strings)
                                                                        if j != k]).expression)),
                               strings[k], MAX_TOLERANCE) for k in held)
    return float(np.clip(worst + 1.0, MIN_TOLERANCE, MAX_TOLERANCE))


def _edit_distance(dfa, string: tuple[str, ...], cap: float) -> float:
    """Edit distance (1 per insertion, deletion, substitution) from a token string to one
    DFA's language, capped — the Matcher's recurrence for one action without building its
    tables for every token."""
    from doodle.core.tokens import CODES
    from grammar.matcher import _insertion_closure

    reach = _insertion_closure(dfa, cap + 1.0)  # fewest insertions from p to r
    src, sym = np.nonzero(dfa.table >= 0)
    dst = dfa.table[src, sym]
    d = np.minimum(reach[0], cap + 1.0)
    for name in string:
        new = d + 1.0  # the token deleted
        np.minimum.at(new, dst, d[src] + (sym != CODES[name]))  # matched or substituted along an edge
        d = np.minimum((new[:, None] + reach).min(axis=0), cap + 1.0)  # then insertions
    return float(min(d[dfa.accept].min(), cap + 1.0))
