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
from doodle.core.tokens import CODES
from doodle.input.segmenter import SegmenterParams, tokenize
from grammar import shapes
from grammar.automata import compile_expression
from grammar.expr import Alt, Cat, Repeat, Sym, parse
from grammar.matcher import Automaton, _insertion_closure

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
    seconds: tuple = ()  # each example's motion: from its first token's start to its last's end, pauses left out
    spans: tuple = ()  # each example's motion as samples (first token's start, last token's end)


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


def _sq_costs(a: np.ndarray, bs: np.ndarray) -> np.ndarray:
    """``cost[k, i, j] = |a[i] − bs[k, j]|²`` (k, n, m): for few dimensions summed one
    dimension at a time — the same additions, in the same order, as numpy's sum over a short
    last axis (under 8 values: one after the other), without the (k, n, m, d) temporary."""
    d = a.shape[1]
    if d >= 8:  # numpy sums 8 or more values pairwise: keep its order
        return ((a[None, :, None, :] - bs[:, None, :, :]) ** 2).sum(axis=3)
    cost = np.zeros((len(bs), len(a), bs.shape[1]))
    diff = np.empty_like(cost)
    for c in range(d):
        np.subtract(a[None, :, None, c], bs[:, None, :, c], out=diff)
        np.multiply(diff, diff, out=diff)
        cost += diff
    return cost


def _dtw_paths(a: np.ndarray, bs: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Indices (i, j) of the optimal DTW alignment (squared l2 cost) of a (n, d) with each
    of bs (k, m, d) — the cumulative costs of all k computed at once, row by row; each path
    walked back from the end by the moves chosen for every cell at once (diagonal, then up,
    then left on ties)."""
    a = np.asarray(a, dtype=float)
    bs = np.asarray(bs, dtype=float)
    k, m, _ = bs.shape
    n = len(a)
    cost = _sq_costs(a, bs)  # (k, n, m)
    c = np.cumsum(cost, axis=2)  # per row, from (i, j-1): a prefix minimum
    D = np.empty((k, n, m))
    D[:, 0] = c[:, 0]
    row = np.empty((k, m))
    for i in range(1, n):
        prev = D[:, i - 1]
        row[:, 0] = prev[:, 0]
        np.minimum(prev[:, :-1], prev[:, 1:], out=row[:, 1:])  # from (i-1, j-1) or (i-1, j)
        row += cost[:, i]
        row -= c[:, i]
        np.minimum.accumulate(row, axis=1, out=row)
        np.add(row, c[:, i], out=D[:, i])
    # the move into each cell (i, j ≥ 1): 0 diagonal, 1 up, 2 left
    diag, up, left = D[:, :-1, :-1], D[:, :-1, 1:], D[:, 1:, :-1]
    moves = np.where((diag <= up) & (diag <= left), 0, np.where(up <= left, 1, 2)).astype(np.uint8).tobytes()
    out = []
    for kk in range(k):
        base = kk * (n - 1) * (m - 1)
        i, j = n - 1, m - 1
        ii, jj = [i], [j]
        while i and j:
            move = moves[base + (i - 1) * (m - 1) + j - 1]
            if move == 0:
                i, j = i - 1, j - 1
            elif move == 1:
                i -= 1
            else:
                j -= 1
            ii.append(i)
            jj.append(j)
        if i:
            ii += range(i - 1, -1, -1)
            jj += [0] * i
        elif j:
            jj += range(j - 1, -1, -1)
            ii += [0] * j
        out.append((np.array(ii[::-1]), np.array(jj[::-1])))
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
    stacked, stacked_q = np.array(feats), np.array(quats)
    dist = shapes.dtw_costs(stacked, stacked)  # (examples, examples), all pairs at once
    medoid = int(np.argmin(dist.sum(axis=1)))
    avg, avg_q = feats[medoid].copy(), quats[medoid].copy()
    for _ in range(iterations):
        # every example's aligned samples in one list, example after example (the sums
        # below add them in that order)
        paths = _dtw_paths(avg, stacked)
        i = np.concatenate([rows for rows, _ in paths])
        which = np.concatenate([np.full(len(cols), k) for k, (_, cols) in enumerate(paths)])
        j = np.concatenate([cols for _, cols in paths])
        sums, qsum, counts = np.zeros_like(avg), np.zeros_like(avg_q), np.zeros(points)
        np.add.at(sums, i, stacked[which, j])
        qq = stacked_q[which, j]
        signs = np.where(np.sum(qq * avg_q[i], axis=1) < 0, -1.0, 1.0)
        np.add.at(qsum, i, qq * signs[:, None])
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
    return tuple(k.name for k in _motion_tokens(track, rate, params))


def _motion_tokens(track: Track, rate: float, params: SegmenterParams) -> list:
    """A track's tokens without leading and trailing pauses."""
    tokens = tokenize(track, rate, params)
    while tokens and tokens[0].name == "T_STILL":
        tokens.pop(0)
    while tokens and tokens[-1].name == "T_STILL":
        tokens.pop()
    return tokens


def _align(ref: list[str], seq: list[str]) -> list[tuple[int | None, int | None]]:
    """Levenshtein alignment of seq to ref: pairs (ref index | None, seq index | None)."""
    n, m = len(ref), len(seq)
    D = [list(range(m + 1))] + [[i] + [0] * m for i in range(1, n + 1)]  # edit counts (ints)
    for i in range(1, n + 1):
        above, row, r = D[i - 1], D[i], ref[i - 1]
        for j in range(1, m + 1):
            row[j] = min(above[j] + 1, row[j - 1] + 1, above[j - 1] + (r != seq[j - 1]))
    pairs, i, j = [], n, m
    while i or j:
        if i and j and D[i][j] == D[i - 1][j - 1] + (ref[i - 1] != seq[j - 1]):
            pairs.append((i - 1, j - 1))
            i, j = i - 1, j - 1
        elif i and D[i][j] == D[i - 1][j] + 1:
            pairs.append((i - 1, None))
            i -= 1
        else:
            pairs.append((None, j - 1))
            j -= 1
    return pairs[::-1]


def expression_of(strings: list[tuple[str, ...]], reference: int = -1) -> Learned:
    """The compact expression of §4.2.5 accepting every string; mandatory columns are
    aligned to ``strings[reference]`` (the average's)."""
    return _expression(strings, reference)[0]


def _expression(strings: list[tuple[str, ...]], reference: int = -1) -> tuple[Learned, object]:
    """:func:`expression_of`, and the expression's tree as :func:`grammar.expr.parse` reads
    its text (built alongside it: no parsing)."""
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
    parts, nodes = [], []

    def sym(x):
        return Sym(CODES[x])

    for k in range(columns + 1):
        runs = sorted({tuple(g[k]) for g in gaps})
        if len(runs) == 1 and runs[0]:
            parts.append(" ".join(runs[0]))  # every string has this run: a quick intentional gesture
            nodes += [sym(x) for x in runs[0]]
        elif any(runs):
            options = [" ".join(r) for r in runs if r]
            parts.append("(" + " | ".join(f"({o})" if " " in o else o for o in options) + ")*")
            alts = [sym(r[0]) if len(r) == 1 else Cat(tuple(sym(x) for x in r)) for r in runs if r]
            nodes.append(Repeat(alts[0] if len(alts) == 1 else Alt(tuple(alts)), 0, True))
        if k < columns:
            tokens = sorted({c[k] for c in cells if c[k] is not None})
            body = tokens[0] if len(tokens) == 1 else "(" + " | ".join(tokens) + ")"
            every = all(c[k] is not None for c in cells)
            parts.append(body + ("+" if every else "*"))
            nodes.append(Repeat(sym(tokens[0]) if len(tokens) == 1 else Alt(tuple(sym(x) for x in tokens)),
                                1 if every else 0, True))
    return Learned(" ".join(parts), tuple(strings), mandatory), nodes[0] if len(nodes) == 1 else Cat(tuple(nodes))


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
    strings, seconds, spans = [], [], []
    for k, (t, p, q) in enumerate(examples):
        tokens = _motion_tokens(Track(f"example {k + 1}", t, p, q, np.ones(len(t), dtype=bool)), rate, params)
        if not tokens:
            raise DoodleError(f"example {k + 1} is all still: nothing was performed")
        strings.append(tuple(k.name for k in tokens))
        seconds.append(max(float(t[tokens[-1].end - 1] - t[tokens[0].start]), 1.0 / rate))
        spans.append((tokens[0].start, tokens[-1].end))
    average = token_string(dba(examples), rate, params)
    learned = replace(expression_of(strings + ([average] if average else [])),
                      paths=np.array([shapes.resample(p) for _, p, _ in examples]), seconds=tuple(seconds),
                      spans=tuple(spans))
    return replace(learned, tolerance=tolerance(learned.strings, len(strings))) if with_tolerance else learned


def distances(expressions: list[str], string: tuple[str, ...], cap: float = 40.0) -> np.ndarray:
    """Edit distance (insert, delete, substitute: 1 each) from a token string to each
    expression's language, capped at ``cap``."""
    return _run(_automaton(expressions, cap), string)


def _automaton(expressions: list[str], cap: float):
    return Automaton([str(k) for k in range(len(expressions))],
                     [compile_expression(parse(e)) for e in expressions], threshold=cap, protect_still=False)


def _run(auto, string: tuple[str, ...]) -> np.ndarray:
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
    # the distance is the language's, whatever DFA accepts it: the subset construction's
    # serves as well as the minimal one (and the tree is the one the expression's text parses to)
    worst = max(_edit_distance(compile_expression(_expression([s for j, s in enumerate(strings) if j != k])[1],
                                                  minimal=False), strings[k], MAX_TOLERANCE) for k in held)
    return float(np.clip(worst + 1.0, MIN_TOLERANCE, MAX_TOLERANCE))


def _edit_distance(dfa, string: tuple[str, ...], cap: float) -> float:
    """Edit distance (1 per insertion, deletion, substitution) from a token string to one
    DFA's language, capped — the Matcher's recurrence for one action without building its
    tables for every token."""
    reach = _insertion_closure(dfa, cap + 1.0)  # fewest insertions from p to r
    src, sym = np.nonzero(dfa.table >= 0)
    dst = dfa.table[src, sym]
    d = np.minimum(reach[0], cap + 1.0)
    for name in string:
        new = d + 1.0  # the token deleted
        np.minimum.at(new, dst, d[src] + (sym != CODES[name]))  # matched or substituted along an edge
        d = np.minimum((new[:, None] + reach).min(axis=0), cap + 1.0)  # then insertions
    return float(min(d[dfa.accept].min(), cap + 1.0))
