"""The Matcher: compacted motion tokens → action segments (§4.2.3, Algorithm 1, SPEC).

Reading one track's tokens in order from the start of the current segment, the Matcher keeps
for every action the *edit distance* from the tokens read so far to the action's language,
per state of the action's DFA (dynamic programming over the automaton: a token is matched
or substituted along a transition, deleted in place, or a token is inserted by following a
transition without reading). That is the distance to the whole regular language — nothing is
enumerated. All actions' DFAs are stacked into one array so one token costs a few numpy
operations, whatever the number of actions.

Policy (Algorithm 1 with SPEC's refinements):

* a *candidate* is an action whose accepting states are within the threshold (default 2)
  after some prefix of the tokens read, and — so that one stray token is not
  "approximately" any short action — within half the length of that prefix; an *exact*
  candidate has distance 0;
* exact beats approximate; among exact candidates the longest wins (so a cyclic action such
  as Walk keeps absorbing tokens while it still matches); among approximate ones the
  smallest distance, then the longest; when two actions match the same tokens equally well
  because their languages overlap (§4.2.4), the more specific one wins — the one accepting
  fewer token strings of that length (Stomp's ``T_Y T_N_Y`` over Jump's) — then the one
  listed first;
* reading continues while some action could still extend an exact candidate (once one is
  known) or could still come within the threshold (before that); then the best candidate is
  emitted and reading restarts from the first token it did not consume; when there is no
  candidate, the first token becomes an explicit ``unknown`` segment (consecutive unknowns
  are merged).

A known weakness of this greedy policy (kept because it is the thesis's and SPEC's): a
noisy gesture whose first token is on its own an exact action (``T_N_Z`` is Walk Back) is
split there rather than matched approximately as a whole; a segmentation-level dynamic
programme would fix that.

Substitution costs are 1 (Levenshtein) or, with ``direction_costs=True``, depend on how far
apart two directions are: ``0.5 + 0.5·angle/π`` between tokens of the same kind, 1 otherwise
(the thesis's own suggestion, §4.2.7).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass

import numpy as np

from doodle.tokens import CODES, N_CODES, NAMES, Token, signs_of
from grammar.automata import DFA

UNKNOWN = "unknown"
INF = 1e9
MAX_COUNTED = 64  # string lengths up to which languages are counted for specificity


def _string_counts(dfa: DFA, longest: int) -> np.ndarray:
    """Number of accepted strings of each length 0..longest (as floats: they grow fast)."""
    ways = np.zeros(dfa.size)
    ways[0] = 1.0
    out = np.zeros(longest + 1)
    s, a = np.nonzero(dfa.table >= 0)
    t = dfa.table[s, a]
    for length in range(longest + 1):
        out[length] = ways[dfa.accept].sum()
        ways = np.bincount(t, weights=ways[s], minlength=dfa.size)
    return out


@dataclass(frozen=True)
class Segment:
    """One recognised action: tokens ``[first, stop)`` of the track, samples ``[start, end)``."""

    action: str
    first: int
    stop: int
    start: int
    end: int
    exact: bool
    distance: float


def substitution_costs(direction_costs: bool = False) -> np.ndarray:
    """``C[x, a]``: cost of reading token ``x`` where the language has ``a``."""
    cost = np.ones((N_CODES, N_CODES))
    np.fill_diagonal(cost, 0.0)
    if direction_costs:
        kinds = {}
        for name, code in CODES.items():
            kind, signs = signs_of(name)
            v = np.array(signs, dtype=float)
            kinds[code] = (kind, v / np.linalg.norm(v) if kind != "S" else v)
        for x, (kx, vx) in kinds.items():
            for a, (ka, va) in kinds.items():
                if x != a and kx == ka and kx != "S":
                    angle = np.arccos(np.clip(vx @ va, -1.0, 1.0))
                    cost[x, a] = 0.5 + 0.5 * angle / np.pi
    return cost


class Automaton:
    """The DFAs of a list of actions stacked for vectorised edit-distance steps."""

    def __init__(self, names: list[str], dfas: list[DFA], threshold: float = 2.0, direction_costs: bool = False):
        if not names:
            raise ValueError("no actions to match")
        self.names, self.threshold = list(names), float(threshold)
        sizes = [d.size for d in dfas]
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        self.n = int(offsets[-1])
        self.act_offsets = offsets[:-1]
        self.starts = offsets[:-1].copy()
        self.accept = np.concatenate([d.accept for d in dfas])
        src, sym, dst = [], [], []
        for off, d in zip(offsets, dfas):
            s, a = np.nonzero(d.table >= 0)
            src.append(s + off)
            sym.append(a)
            dst.append(d.table[s, a] + off)
        src, sym, dst = np.concatenate(src), np.concatenate(sym), np.concatenate(dst)
        costs = substitution_costs(direction_costs)
        states = np.arange(self.n)
        # read step: along an edge (match / substitute) or stay (delete the token), by target
        r_src = np.concatenate([src, states])
        r_dst = np.concatenate([dst, states])
        order = np.argsort(r_dst, kind="stable")
        self.read_src = r_src[order]
        self.read_off = np.searchsorted(r_dst[order], states)
        self.read_cost = np.concatenate([costs[:, sym], np.ones((N_CODES, self.n))], axis=1)[:, order]
        # insertion step: stay (0) or follow an edge without reading (1)
        i_src = np.concatenate([states, src])
        i_dst = np.concatenate([states, dst])
        order = np.argsort(i_dst, kind="stable")
        self.ins_src = i_src[order]
        self.ins_off = np.searchsorted(i_dst[order], states)
        self.ins_cost = np.concatenate([np.zeros(self.n), np.ones(len(src))])[order]
        self.ins_rounds = int(np.floor(self.threshold))
        self.cap = self.threshold + 1.0
        self.initial = self._insert(np.where(np.isin(states, self.starts), 0.0, self.cap))
        self.counts = np.array([_string_counts(d, MAX_COUNTED) for d in dfas])  # specificity

    def most_specific(self, candidates: np.ndarray, length: int) -> int:
        """Among candidate actions, the one accepting the fewest strings of ``length``."""
        counts = self.counts[candidates, min(length, MAX_COUNTED)]
        return int(candidates[int(np.argmin(counts))])

    def _insert(self, d: np.ndarray) -> np.ndarray:
        for _ in range(self.ins_rounds):
            d = np.minimum.reduceat(d[self.ins_src] + self.ins_cost, self.ins_off)
        return np.minimum(d, self.cap)

    def step(self, d: np.ndarray, code: int) -> np.ndarray:
        """Costs per state after reading one more token."""
        return self._insert(np.minimum.reduceat(d[self.read_src] + self.read_cost[code], self.read_off))

    def accept_costs(self, d: np.ndarray) -> np.ndarray:
        """Per action, the smallest cost of an accepting state."""
        return np.minimum.reduceat(np.where(self.accept, d, INF), self.act_offsets)


class Matcher:
    """Streaming Matcher for one track: ``push`` a token, get the segments it completes."""

    def __init__(self, automaton: Automaton, track: str = "c0"):
        self.auto, self.track = automaton, track
        self._queue: deque = deque()  # tokens waiting to be read (re-read after an emit)
        self._buf: list = []  # (index, Token) read since the segment start
        self._next = 0  # index of the next pushed token
        self._reset()
        self._unknown: Segment | None = None

    def _reset(self) -> None:
        self._d = self.auto.initial
        self._best: tuple | None = None  # (length, action, distance) of the best candidate

    def push(self, token: Token) -> list[Segment]:
        self._queue.append((self._next, token))
        self._next += 1
        return self._run(final=False)

    def close(self) -> list[Segment]:
        out = self._run(final=True)
        if self._unknown is not None:
            out.append(self._unknown)
            self._unknown = None
        return out

    def _run(self, final: bool) -> list[Segment]:
        out: list[Segment] = []
        while True:
            while self._queue:
                item = self._queue.popleft()
                self._read(item)
                if not self._alive():
                    self._emit(out)
            if not final or not self._buf:
                return out
            self._emit(out)

    def _read(self, item) -> None:
        _, token = item
        self._buf.append(item)
        self._d = self.auto.step(self._d, CODES[token.name])
        costs = self.auto.accept_costs(self._d)
        length = len(self._buf)
        low = float(costs.min())
        best = self._best
        if low == 0.0:
            pass  # exact: the longest so far
        elif (best is not None and best[2] <= low) or low > min(self.auto.threshold, length / 2):
            return  # approximate and no better than what we have (or none at all)
        action = self.auto.most_specific(np.flatnonzero(costs == low), length)
        self._best = (length, action, low)

    def _alive(self) -> bool:
        if self._best is not None and self._best[2] == 0.0:
            return bool((self._d == 0.0).any())
        return bool(self._d.min() <= self.auto.threshold)

    def _emit(self, out: list[Segment]) -> None:
        if self._best is not None:
            length, action, distance = self._best
        else:
            length, action, distance = 1, None, float("nan")
        used, rest = self._buf[:length], self._buf[length:]
        (first, t0), (last, t1) = used[0], used[-1]
        name = UNKNOWN if action is None else self.auto.names[action]
        seg = Segment(name, first, last + 1, t0.start, t1.end, distance == 0.0, distance)
        if name == UNKNOWN:
            prev = self._unknown
            self._unknown = seg if prev is None else Segment(UNKNOWN, prev.first, seg.stop, prev.start, seg.end, False, float("nan"))
        else:
            if self._unknown is not None:
                out.append(self._unknown)
                self._unknown = None
            out.append(seg)
        self._buf = []
        self._queue.extendleft(reversed(rest))
        self._reset()


def match(tokens: list[Token], automaton: Automaton, track: str = "c0") -> list[Segment]:
    """Batch form: every segment of a token list (the streaming Matcher run to the end)."""
    matcher = Matcher(automaton, track)
    out = []
    for token in tokens:
        out += matcher.push(token)
    return out + matcher.close()


def edit_distance(dfa: DFA, codes: list[int], costs: np.ndarray | None = None) -> float:
    """Reference edit distance from a token string to a DFA's language (plain DP, for tests)."""
    costs = substitution_costs() if costs is None else costs
    n = dfa.size
    edges = [(q, a, int(dfa.table[q, a])) for q in range(n) for a in np.flatnonzero(dfa.table[q] >= 0)]

    def relax(d):
        changed = True
        while changed:
            changed = False
            for q, a, r in edges:
                if d[q] + 1 < d[r]:
                    d[r], changed = d[q] + 1, True
        return d

    d = relax(np.where(np.arange(n) == 0, 0.0, np.inf))
    for x in codes:
        new = d + 1.0
        for q, a, r in edges:
            new[r] = min(new[r], d[q] + costs[x, a])
        d = relax(new)
    return float(np.min(np.where(dfa.accept, d, np.inf)))
