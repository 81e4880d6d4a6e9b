"""The Matcher: compacted motion tokens → action segments (§4.2.3, Algorithm 1, SPEC).

Reading one track's tokens in order from the start of the current segment, the Matcher keeps
for every action the *edit distance* from the tokens read so far to the action's language,
per state of the action's DFA (dynamic programming over the automaton: a token is matched
or substituted along a transition, deleted in place, or a token is inserted by following a
transition without reading). That is the distance to the whole regular language — nothing is
enumerated. All actions' DFAs are stacked into one array so one token costs a few numpy
operations, whatever the number of actions.

Segmentation. Algorithm 1 reads greedily and lets an exact match beat any approximate one.
On the thesis's table that fails badly: single-token actions (Walk ``T_Z``, Walk Back
``T_N_Z``, Side Walk ``T_X``, Idle ``T_STILL``) match exactly at the start of most noisy
gestures, so a Punch with one stray token became "Walk Back" plus debris — about 80 % of
strings one or two edits from an action were split that way (measured during development
with the sampling of ``test_strings_within_distance_two_are_recognised_approximately``;
this policy recognises over 95 % of them). Here
the Matcher chooses the *segmentation* of the token stream with the lowest cost, by dynamic
programming over token positions:

* a segment is an action whose language is within the threshold (default 2) of the tokens
  it covers, and — so a stray token or two are not "approximately" any short action — under
  half their number (more than half must match); it costs ``1 + 0.75·distance``;
* a token left unexplained costs 1.5 (an ``unknown`` segment; neighbours are merged);
* ties go to the smaller total distance; between actions matching the same tokens equally
  well because their languages overlap (§4.2.4), the simplest explanation wins: the action
  with the narrower language — fewer accepted strings up to 64 tokens — not the one that
  is merely wider (Stomp's ``T_Y T_N_Y`` over Jump's, Jump's ``T_Y T_Z T_N_Y`` over Flip's,
  whose many optional groups accept orders of magnitude more strings), then the one
  listed first;
* a pause is never noise: an input ``T_STILL`` can only be matched by ``T_STILL``.

An exact one-shot segment that begins with a walk (tokens some cyclic action reads exactly,
the one-shot still exact without them) is split into the walk and the one-shot
(:meth:`Matcher._peel`): a walk that flows into a stomp is Walk, Stomp — not a Jump with a
run-up; so is one that ends with a walk lasting longer than the rest of it.

Fewer segments at equal exactness means longer matches, so a cyclic action such as Walk
keeps absorbing tokens while it matches — and across a stray token (``T_Z T_X_Z T_Y T_Z``
is one Walk at distance 1, Algorithm 1's cyclic rule) — and an exact segmentation beats an
approximate one unless it needs more segments than the edits it saves.

Streaming. Every token position that may start a segment keeps a row of edit costs (one
per state of every action); a row dies once it can give no segment any more — no action
within its limit that could still be more than half matched, however the tokens go on
(:mod:`grammar.blocks`) — so only a short window is alive. A segment is returned as soon as
every segmentation that can still be extended agrees on it — typically at the token that
ends it, or the next. Rows are interned (:mod:`grammar.rows`): a token costs a list look-up
per live row, the arithmetic of :meth:`Automaton.step` being done once per new row and
token, with bit sets. ``match`` (batch) is the same code run to the end of the stream.
:meth:`Matcher.fork` copies a Matcher, to ask what tokens that may yet change would decide
(provisional actions, :class:`grammar.recognizer.Live`).

Substitution costs are 1 (Levenshtein) or, with ``direction_costs=True``, depend on how far
apart two directions are: ``0.5 + 0.5·angle/π`` between tokens of the same kind, 1 otherwise
(the thesis's own suggestion, §4.2.7).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass

import numpy as np

from doodle.core.tokens import CODES, N_CODES, Token, signs_of
from grammar.automata import DFA
from grammar.rows import NONE, RowTable

UNKNOWN = "unknown"
INF = 1e9
EDIT_WEIGHT = 0.75  # cost of one edit, relative to one more segment
UNKNOWN_COST = 1.5  # cost of leaving one token unexplained (more than a one-token segment)
MAX_COUNTED = 64  # string lengths up to which languages are counted for specificity


def _insertion_closure(dfa: DFA, cap: float) -> np.ndarray:
    """``R[p, r]``: fewest transitions from state p to r (0 on the diagonal), capped."""
    q = dfa.size
    reach = np.full((q, q), cap)
    np.fill_diagonal(reach, 0.0)
    frontier = np.eye(q, dtype=bool)
    adjacent = np.zeros((q, q), dtype=bool)
    p, a = np.nonzero(dfa.table >= 0)
    adjacent[p, dfa.table[p, a]] = True
    for k in range(1, int(cap)):
        frontier = (frontier.astype(int) @ adjacent.astype(int)) > 0
        reach = np.where(frontier & (reach > k), float(k), reach)
    return reach


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
    distance: float | None  # None for an unknown segment


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

    def __init__(self, names: list[str], dfas: list[DFA], threshold: float = 2.0, direction_costs: bool = False,
                 cyclic: list[bool] | None = None, protect_still: bool = True, limits: list[float] | None = None,
                 tables: dict | None = None):
        """``tables``: what :meth:`tables` returned for an automaton of the same arguments
        (read back from a cache): the step tables are taken from it instead of computed."""
        if not names:
            raise ValueError("no actions to match")
        # per action, the edit distance it may be matched within (learned actions carry
        # their own tolerance); the automaton is built for the largest
        self.limits = np.array(limits if limits is not None else [threshold] * len(names), dtype=float)
        self.names, self.threshold = list(names), float(self.limits.max())
        self.cyclic = list(cyclic) if cyclic is not None else [False] * len(names)
        self.dfas = list(dfas)
        sizes = [d.size for d in dfas]
        offsets = np.concatenate([[0], np.cumsum(sizes)])
        self.n = int(offsets[-1])
        self.act_offsets = offsets[:-1]
        self.sizes = sizes
        self.starts = offsets[:-1].copy()
        self.accept = np.concatenate([d.accept for d in dfas])
        self.cap = self.threshold + 1.0
        if tables is not None:
            self._restore(tables)
            return
        costs = substitution_costs(direction_costs)
        delete = np.ones(N_CODES)
        if protect_still:  # a pause is never noise: a T_STILL read must be matched by T_STILL
            still = CODES["T_STILL"]
            costs[still, np.arange(N_CODES) != still] = INF
            delete[still] = INF
        # Per token x, one step = read x (match, substitute along an edge, or delete in
        # place) then insert up to `threshold` tokens (follow edges without reading): the
        # two composed once here, per action block, as min-plus products.
        blocks, initial, self.reads = [], [], []
        for off, d, limit in zip(offsets, dfas, self.limits):
            q = d.size
            reach = _insertion_closure(d, self.cap)  # (q, q) fewest insertions from p to r
            read = np.full((N_CODES, q, q), INF)
            p_idx, a_idx = np.nonzero(d.table >= 0)
            for p, a in zip(p_idx, a_idx):
                t = d.table[p, a]
                read[:, p, t] = np.minimum(read[:, p, t], costs[:, a])
            diag = np.arange(q)
            read[:, diag, diag] = np.minimum(read[:, diag, diag], delete[:, None])
            # min-plus product over the finite entries of `read` only (edges and the diagonal),
            # grouped by source state: memory (K, q) per token instead of (x, q, q, q)
            src, dst = np.unique(np.concatenate([np.column_stack([p_idx, d.table[p_idx, a_idx]]),
                                                 np.column_stack([diag, diag])]), axis=0).T
            groups = np.flatnonzero(np.concatenate([[True], src[1:] != src[:-1]]))
            both = np.stack([np.minimum.reduceat(read[x, src, dst][:, None] + reach[dst], groups, axis=0)
                             for x in range(N_CODES)])  # (x, p, r); every p has its diagonal entry
            blocks.append((off, both, limit))
            self.reads.append(np.where(both <= limit, both, INF))  # per token, the block's step (grammar.rows)
            initial.append(np.minimum(reach[0], self.cap))
        self.initial = np.concatenate(initial)
        self.step_src, self.step_off, self.step_cost = [], [], []
        states = np.arange(self.n)
        for x in range(N_CODES):
            src, dst, cost = [states], [states], [np.full(self.n, self.cap)]  # every state gets an entry
            for off, both, limit in blocks:
                p, r = np.nonzero(both[x] <= limit)
                src.append(p + off)
                dst.append(r + off)
                cost.append(both[x][p, r])
            src, dst, cost = np.concatenate(src), np.concatenate(dst), np.concatenate(cost)
            order = np.argsort(dst, kind="stable")
            self.step_src.append(src[order])
            self.step_off.append(np.searchsorted(dst[order], states))
            self.step_cost.append(cost[order])
        self.sizes_counted = np.array([_string_counts(d, MAX_COUNTED).sum() for d in dfas])  # specificity
        self.rows = RowTable(self)  # the rows met so far, each stepped once per token (grammar.rows)

    def tables(self) -> dict[str, np.ndarray]:
        """The computed tables as plain arrays (the per-token ones concatenated, with their
        lengths), for a cache: ``Automaton(..., tables=automaton.tables())`` is this automaton."""
        return {"initial": self.initial, "sizes_counted": self.sizes_counted,
                "step_lengths": np.array([len(a) for a in self.step_src], dtype=np.int64),
                "step_src": np.concatenate(self.step_src), "step_cost": np.concatenate(self.step_cost),
                "step_off": np.stack(self.step_off), "reads": np.concatenate([r.ravel() for r in self.reads])}

    def _restore(self, tables: dict) -> None:
        """The tables of :meth:`tables`, checked against this automaton's shape (ValueError if
        they do not fit: a cache entry of another automaton)."""
        lengths = np.asarray(tables["step_lengths"])
        src, cost, off = (np.asarray(tables[k]) for k in ("step_src", "step_cost", "step_off"))
        initial, counted = np.asarray(tables["initial"], dtype=float), np.asarray(tables["sizes_counted"], dtype=float)
        if (lengths.shape != (N_CODES,) or lengths.min() < self.n or src.shape != (int(lengths.sum()),)
                or cost.shape != src.shape or off.shape != (N_CODES, self.n) or initial.shape != (self.n,)
                or counted.shape != (len(self.names),) or src.min() < 0 or src.max() >= self.n):
            raise ValueError("automaton tables do not fit")
        cuts = np.cumsum(lengths)[:-1]
        self.initial, self.sizes_counted = initial, counted
        self.step_src = [a.astype(np.int64) for a in np.split(src, cuts)]
        self.step_cost = [a.astype(float) for a in np.split(cost, cuts)]
        self.step_off = [a.astype(np.int64) for a in off]
        reads = np.asarray(tables["reads"], dtype=float)
        counts = [N_CODES * q * q for q in self.sizes]
        if reads.shape != (sum(counts),):
            raise ValueError("automaton tables do not fit")
        self.reads = [r.reshape(N_CODES, q, q) for r, q in zip(np.split(reads, np.cumsum(counts)[:-1]), self.sizes)]
        self.rows = RowTable(self)

    def most_specific(self, candidates: np.ndarray) -> int:
        """Among candidate actions, the one with the narrowest language: the fewest accepted
        strings up to :data:`MAX_COUNTED` tokens (then the first listed)."""
        return int(candidates[int(np.argmin(self.sizes_counted[candidates]))])

    def step(self, d: np.ndarray, code: int) -> np.ndarray:
        """Costs per state (last axis; any leading axes) after reading one more token."""
        out = np.minimum.reduceat(d[..., self.step_src[code]] + self.step_cost[code], self.step_off[code], axis=-1)
        return np.minimum(out, self.cap, out=out)

    def accept_costs(self, d: np.ndarray) -> np.ndarray:
        """Per action, the smallest cost of an accepting state."""
        return np.minimum.reduceat(np.where(self.accept, d, INF), self.act_offsets, axis=-1)


class Matcher:
    """Streaming Matcher for one track: ``push`` a token, get the segments that became final.

    Every token position that is the start of a possible segment keeps a row of edit costs
    (one per state of every action, interned: an id in ``automaton.rows``); rows die once
    they can give no segment any more. The best segmentation of the tokens up to each position is kept with a back pointer; a
    segment is final — and returned — once every segmentation that can still be extended
    agrees on it.
    """

    def __init__(self, automaton: Automaton, track: str = "c0", edit_weight: float = EDIT_WEIGHT,
                 unknown_cost: float = UNKNOWN_COST):
        self.auto, self.track = automaton, track
        self.edit_weight, self.unknown_cost = edit_weight, unknown_cost
        self._tokens: dict[int, Token] = {}
        self._ids: list[int] = []  # the live rows (ids in automaton.rows), oldest first
        self._starts: list[int] = []  # the position each live row started at
        self._best = {0: (0.0, 0.0)}  # position -> (cost, total distance) of the best segmentation
        self._back: dict[int, tuple] = {}  # position -> (start, action or None, distance)
        self._n = 0
        self._done = 0  # segments before this position were returned
        self._unknown: Segment | None = None

    @property
    def done(self) -> int:
        """The token position up to which segments have been returned."""
        return self._done

    @property
    def unknown(self) -> Segment | None:
        """The unknown run held back until what follows it is decided (it may grow)."""
        return self._unknown

    def fork(self) -> "Matcher":
        """An independent copy: what it is pushed leaves this Matcher as it is (the row
        table is shared; it only grows)."""
        other = copy.copy(self)
        other._tokens, other._best, other._back = dict(self._tokens), dict(self._best), dict(self._back)
        other._ids, other._starts = list(self._ids), list(self._starts)
        return other

    def push(self, token: Token) -> list[Segment]:
        e = self._n
        self._tokens[e] = token
        self._n = e + 1
        code = CODES[token.name]
        table = self.auto.rows
        moves, low, pick, shortest = table.next, table.low, table.pick, table.shortest
        cost, dist = self._best[e]
        best, back = (cost + self.unknown_cost, dist), (e, None, None)
        ids, starts = [], []
        for s, i in zip(self._starts + [e], self._ids + [table.start]):
            j = moves[i][code]
            if j == NONE:
                j = table.move(i, code)
            length = e + 1 - s
            d_k = low[j]
            if d_k == 0.0 or 2.0 * d_k < length:  # a segment: more than half its tokens match
                c, d = self._best[s]
                option = (c + 1.0 + self.edit_weight * d_k, d + d_k)
                if option < best:
                    best, back = option, (s, pick[j], d_k)
            if length > shortest[j]:  # it may give a segment later
                ids.append(j)
                starts.append(s)
        self._ids, self._starts = ids, starts
        self._best[e + 1], self._back[e + 1] = best, back
        return self._emit_until(self._settled(set(starts) | {e + 1}))

    def close(self) -> list[Segment]:
        out = self._emit_until(self._n)
        if self._unknown is not None:
            out.append(self._unknown)
            self._unknown = None
        self._ids, self._starts = [], []
        return out

    def _settled(self, frontier: set) -> int:
        """The latest position every best segmentation of the frontier positions passes."""
        positions = frontier
        while len(positions) > 1:
            p = max(positions)
            positions.discard(p)
            positions.add(self._back[p][0])
        return positions.pop()

    def _peel(self, s: int, p: int, action: int) -> list[tuple[int, int, int]]:
        """An exact one-shot segment whose first tokens are a walk on their own, with the
        action still exact without them, is that walk and then the action: locomotion
        leading into a one-shot is animated as locomotion (Algorithm 1 lets a cyclic action
        keep what it matches). Jump's optional run-up ``(T_Z)*`` would otherwise swallow a
        walk that flows into a stomp (``T_Z T_Y T_N_Y``: Walk, then Stomp). Its last tokens
        are split off the same way when they last longer than the rest of it — a walk that
        follows without a pause, not a follow-through that returns the prop (Pick up's
        closing ``T_N_Z``, Crescent Kick's ``T_X``). What remains is re-decided between the
        actions accepting it (the narrowest language)."""
        auto = self.auto
        if auto.cyclic[action]:
            return [(s, p, action)]
        codes = [CODES[self._tokens[k].name] for k in range(s, p)]
        walks = [a for a in range(len(auto.names)) if auto.cyclic[a]]

        def walk(part):
            found = [a for a in walks if auto.dfas[a].accepts(part)]
            return auto.most_specific(np.array(found, dtype=np.int64)) if found else None

        def samples(i, j):
            return self._tokens[j - 1].end - self._tokens[i].start

        lo, hi, head, tail = 0, len(codes), [], []
        prefixes: dict[int, list[int]] = {}  # length -> the walks accepting that many leading tokens
        for a in walks:
            for k in auto.dfas[a].accepting_prefixes(codes[:hi - 1]):
                prefixes.setdefault(k, []).append(a)
        for k in sorted((k for k in prefixes if k > 0), reverse=True):  # the longest leading walk
            if auto.dfas[action].accepts(codes[k:]):
                head, lo = [(s, s + k, auto.most_specific(np.array(prefixes[k], dtype=np.int64)))], k
                break
        for k in range(lo + 1, hi):  # the longest trailing walk that outlasts the rest
            if samples(s + k, p) <= samples(s + lo, s + k):
                break  # the rest only grows and the walk only shrinks from here
            w = walk(codes[k:])
            if w is not None and auto.dfas[action].accepts(codes[lo:k]):
                tail, hi = [(s + k, p, w)], k
                break
        if head or tail:
            rest = codes[lo:hi]
            action = auto.most_specific(np.array([a for a in range(len(auto.names))
                                                  if auto.dfas[a].accepts(rest)], dtype=np.int64))
        return head + [(s + lo, s + hi, action)] + tail

    def _emit_until(self, stop: int) -> list[Segment]:
        if stop <= self._done:
            return []
        path, p = [], stop
        while p > self._done:
            s, action, distance = self._back[p]
            path.append((s, p, action, distance))
            p = s
        out: list[Segment] = []
        for s, p, action, distance in reversed(path):
            t0, t1 = self._tokens[s], self._tokens[p - 1]
            if action is None:
                prev = self._unknown
                self._unknown = Segment(UNKNOWN, s if prev is None else prev.first, p,
                                        t0.start if prev is None else prev.start, t1.end, False, None)
                continue
            if self._unknown is not None:
                out.append(self._unknown)
                self._unknown = None
            if distance == 0.0:
                out += [Segment(self.auto.names[a], i, j, self._tokens[i].start, self._tokens[j - 1].end, True, 0.0)
                        for i, j, a in self._peel(s, p, action)]
                continue
            out.append(Segment(self.auto.names[action], s, p, t0.start, t1.end, False, distance))
        for q in range(self._done, stop):  # forget what is final
            self._tokens.pop(q, None)
            self._best.pop(q, None)
            self._back.pop(q, None)
        self._done = max(self._done, stop)
        return out


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
