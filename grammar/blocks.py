"""One action's edit costs in a Matcher row (a *block*), canonical and interned, stepped
with the action's transition table as bit sets.

A block holds, per state of the action's DFA, the edit cost of the tokens read so far
(:class:`grammar.matcher.Automaton`: read a token along a transition, substitute it, or
delete it, then insert up to the threshold). It is kept as *levels* ``((cost, states), …)``
by increasing cost, ``states`` a bit set of the states at exactly that cost; costs over the
action's limit are left out (the cap: costs only grow along a row, so such a state never
again leads to a match of the action). One token moves a block with the action's step for
that token as bit sets (per state, the states reached at each cost: :meth:`Blocks._moves`),
so a step is a few integer ``or``s per state within the limit, with the same additions as
:meth:`grammar.matcher.Automaton.step` (the same floats). Tokens that all the block's
states read alike (each state's step for them is the step most tokens take) share one
successor.

When a block can still give a segment. A segment is an action at accept cost ``c`` over
``L`` tokens with ``c == 0``, or ``c ≤ limit`` and ``c < L/2`` (:mod:`grammar.matcher`).
From a state at cost ``d`` whose longest way to acceptance is ``m`` transitions
(:func:`longest_to_accept`; infinite through a cycle), reading ``k ≥ 1`` more tokens ends at
cost at least ``d + max(0, k − m)`` (each token past the longest path is one more edit). For
``k ≤ m`` that can be a segment only if ``d == 0`` or ``2d < L + m``; for ``k > m`` only if
``d + 1 ≤ limit`` and ``2d < L + m − 1`` (with ``k = m + 1``, the best case) — so a state
with a way on (``m ≥ 1``) can give a later segment only if ``d == 0`` or ``L > 2d − m``, and
one at acceptance with none (``m = 0``) only if ``L > 2d + 1``: the block's
:attr:`Blocks.shortest` is the least such bound over its states. A state that cannot at some
``L`` never can again (its successors are no better placed), so a block, or a row, past that
point is dead for ever — dropping it, once its segment of the moment is counted, changes no
result, only how soon segments are final: an Idle row dies as soon as it has read its pause
(Idle cannot go on), and one that deleted the motion before a pause dies there, instead of
keeping the segmentation open until two more motions have passed.
"""

from __future__ import annotations

import numpy as np

from doodle.core.tokens import N_CODES

NONE = -1  # a row's successor not computed yet; a block that can give no segment
UNSEEN = -2  # a block's successor not computed yet
INF = float("inf")


def longest_to_accept(table: np.ndarray, accept: np.ndarray) -> np.ndarray:
    """Per state of a DFA, the most transitions a path from it to an accepting state can
    take: ``inf`` when a cycle lies on such a path, ``-inf`` when none reaches acceptance."""
    q = len(accept)
    s, a = np.nonzero(table >= 0)
    t = table[s, a]
    step = np.zeros((q, q), dtype=np.int64)
    step[s, t] = 1
    reach = step > 0  # reach[p, r]: a path of one or more transitions from p to r
    for _ in range(q):
        grown = reach | ((reach.astype(np.int64) @ step) > 0)
        if (grown == reach).all():
            break
        reach = grown
    useful = accept | (reach & accept[None, :]).any(axis=1)  # reaches acceptance
    on_cycle = np.diag(reach) & useful
    endless = on_cycle | (reach & on_cycle[None, :]).any(axis=1)
    longest = np.where(accept, 0.0, -np.inf)
    for _ in range(q):  # the other states reach acceptance along a DAG: q rounds settle it
        grown = longest.copy()
        np.maximum.at(grown, s, np.where(endless[t], -np.inf, longest[t] + 1.0))
        if (grown == longest).all():
            break
        longest = grown
    return np.where(endless, np.inf, longest)


class Blocks:
    """The blocks of an Automaton's actions, by id (see the module): ``next[g][code]`` is
    block ``g`` after one more token (:data:`UNSEEN` until :meth:`move` has computed it,
    :data:`NONE` when it can give no segment any more), ``accept[g]`` its accept cost when
    within the action's limit (``inf`` otherwise), ``action[g]`` its action, ``shortest[g]``
    the length of token string up to which it can give no segment, ``special[g]`` the
    codes (a bit set) its states do not all read alike and ``common[g]`` one they do (-1:
    none); ``initial`` each action's block before any token (:data:`NONE` if dead)."""

    def __init__(self, auto):
        self.auto = auto
        self._index: list[dict[tuple, int]] = [{} for _ in auto.names]
        self._levels: list[tuple] = []
        self._members: list[tuple] = []  # per block, its levels with the states listed
        self.next: list[list[int]] = []
        self.accept: list[float] = []
        self.action: list[int] = []
        self.shortest: list[float] = []
        self._tables: list[list] = [[None] * N_CODES for _ in auto.names]  # per action and code: _moves
        self._sets: list[dict] = [{} for _ in auto.names]  # per action and set of states: _set
        self._limit = [float(x) for x in auto.limits]
        self.special: list[int] = []  # per block: the codes its states do not all read alike (a bit set)
        self.common: list[int] = []  # ... and a code they all read alike (-1: none)
        self._unlike = [_unlike(r) for r in auto.reads]  # per action and state: codes read unlike most
        self._longest = [longest_to_accept(d.table, d.accept).tolist() for d in auto.dfas]
        self._accepting = [_bits(np.flatnonzero(d.accept)) for d in auto.dfas]
        self.initial = [self._intern(a, _levels(auto.initial[o:o + q], auto.limits[a]))
                        for a, (o, q) in enumerate(zip(auto.act_offsets, auto.sizes))]

    def __len__(self) -> int:
        return len(self._levels)

    def move(self, g: int, code: int) -> int:
        """Block ``g`` after one more token ``code`` (computed once; once for all the codes
        its states read alike)."""
        if not self.special[g] >> code & 1 and code != self.common[g]:
            h = self.next[g][self.common[g]]
            if h == UNSEEN:
                h = self.move(g, self.common[g])
            self.next[g][code] = h
            return h
        a = self.action[g]
        moves = self._tables[a][code] or self._moves(a, code)
        limit = self._limit[a]
        reached: dict[float, int] = {}
        get = reached.get
        for cost, states in self._members[g]:
            for p in states:
                for w, targets in moves[p]:  # by increasing cost
                    c = cost + w
                    if c > limit:
                        break
                    reached[c] = get(c, 0) | targets
        levels, seen = [], 0
        for c in sorted(reached):  # each state at its smallest cost
            states = reached[c] & ~seen
            if states:
                levels.append((c, states))
                seen |= states
        h = self.next[g][code] = self._intern(a, tuple(levels))
        return h

    def _set(self, a: int, states: int) -> tuple[list[int], int, float]:
        """A set of action ``a``'s states (a bit set) listed, the codes some of them read
        unlike most (a bit set) and the longest way to acceptance from any of them (worked
        out once per set: the same sets recur in many blocks)."""
        unlike, longest, special, most = self._unlike[a], self._longest[a], 0, -INF
        listed = _states(states)
        for p in listed:
            special |= unlike[p]
            most = max(most, longest[p])
        out = self._sets[a][states] = (listed, special, most)
        return out

    def _moves(self, a: int, code: int) -> list:
        """Action ``a``'s step on ``code`` as bit sets: per state, ``((cost, states), …)``
        reached by reading ``code`` (the Automaton's composed read-then-insert step, within
        the limit)."""
        reads = self.auto.reads[a][code]
        found: list[dict] = [{} for _ in range(len(reads))]
        src, dst = np.nonzero(reads <= self.auto.limits[a])
        for p, r, w in zip(src.tolist(), dst.tolist(), reads[src, dst].tolist()):
            found[p][w] = found[p].get(w, 0) | 1 << r
        table = self._tables[a][code] = [tuple(sorted(f.items())) for f in found]
        return table

    def _intern(self, a: int, levels: tuple) -> int:
        """The id of action ``a``'s block with these levels; :data:`NONE` when it can give
        no segment any more."""
        g = self._index[a].get(levels)
        if g is not None:
            return g
        limit, sets = self._limit[a], self._sets[a]
        bound, special = INF, 0  # the block's shortest (see the module); the codes its states read unlike most
        members = []
        for cost, states in levels:
            found = sets.get(states)
            listed, unlike, most = self._set(a, states) if found is None else found
            members.append((cost, listed))
            special |= unlike
            bound = min(bound, _shortest(cost, most, limit))
        members = tuple(members)
        accept = next((cost for cost, states in levels if states & self._accepting[a]), INF)
        if bound == INF and accept == INF:  # nothing now, nothing later
            self._index[a][levels] = NONE
            return NONE
        g = self._index[a][levels] = len(self._levels)
        self._levels.append(levels)
        self._members.append(members)
        self.next.append([UNSEEN if bound < INF else NONE] * N_CODES)  # a segment now, none later: no successor
        self.accept.append(accept)
        self.action.append(a)
        self.shortest.append(bound)
        self.special.append(special)
        self.common.append(first_zero(special))
        return g


def _shortest(cost: float, longest: float, limit: float) -> float:
    """The length of token string a block's states at ``cost``, the longest way to
    acceptance from any of them ``longest`` transitions, must exceed to give a segment
    after one more token or more (see the module)."""
    if longest == -INF:
        return INF
    if longest >= 1:
        return -INF if cost == 0.0 else 2.0 * cost - longest
    return 2.0 * cost + 1.0 if cost + 1.0 <= limit else INF  # at acceptance with no way on: every token an edit


def _unlike(reads: np.ndarray) -> list[int]:
    """Per state, the codes (a bit set) whose step from it differs from the step most codes
    take (``reads`` (codes, q, q): an action's step per code; of steps as common, the
    cheapest — lexicographically least — so the states of a block agree on it)."""
    k, q = reads.shape[:2]
    steps = np.ascontiguousarray(reads.transpose(1, 0, 2)).view(np.dtype((np.void, 8 * q))).reshape(q, k)
    out = []
    for row in steps.tolist():  # per state, its step for each code as one bytes value
        count: dict[bytes, int] = {}
        for step in row:
            count[step] = count.get(step, 0) + 1
        top = max(count.values())
        most = min((s for s, n in count.items() if n == top), key=lambda s: np.frombuffer(s).tolist())
        out.append(sum(1 << c for c, step in enumerate(row) if step != most))
    return out


def first_zero(bits: int) -> int:
    """The lowest token code not in a bit set of codes (-1: none)."""
    free = ~bits & ((1 << N_CODES) - 1)
    return (free & -free).bit_length() - 1 if free else -1


def _bits(states) -> int:
    out = 0
    for s in states:
        out |= 1 << int(s)
    return out


def _states(bits: int) -> list[int]:
    out = []
    while bits:
        bit = bits & -bits
        bits ^= bit
        out.append(bit.bit_length() - 1)
    return out


def _levels(costs: np.ndarray, limit: float) -> tuple:
    """Costs per state as levels ``((cost, states), …)``, the costs within ``limit``."""
    return tuple((c, _bits(np.flatnonzero(costs == c))) for c in sorted(set(costs[costs <= limit].tolist())))
