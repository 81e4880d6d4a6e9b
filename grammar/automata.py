"""Automata for action expressions: Thompson NFA → compacted DFA → minimal DFA (§4.2.4).

The Matcher reads the *compacted* token stream (no token twice in a row), and every token of
an expression is "effectively repeatable" (§4.2.3: the thesis removes the ``+`` and
enumerates the expression's strings of non-repeating tokens, one token per group). So the
language an action recognises is the strings of its expression that have no token twice in
a row: ``L ∩ NoRepeat``. Each group the expression requires reads its *own* run — two
neighbouring groups never share one (``(T_Y)+ (T_N_Y | T_Y)+`` does not read a lone
``T_Y``; reading it that way let Pick up swallow a Jump whose apex moves forward) — while a
group's own repetition still alternates its options (``(T_Z | T_X_Z)+`` reads
``T_Z T_X_Z T_Z``). The subset construction below builds it directly: a DFA state remembers
the last token so that a repeat is rejected.

A DFA here is a transition table over all token codes (``-1`` rejects) with start state 0
and an accept mask; :func:`minimise` merges equivalent states (Moore's partition
refinement), so only the start and states that can still reach acceptance remain.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from doodle.core.errors import DoodleError
from doodle.core.tokens import CODES, N_CODES, NAMES

SYMBOLS = tuple(sorted(CODES.values()))  # the 53 token codes


@dataclass(frozen=True, eq=False)
class DFA:
    """A deterministic automaton over token codes: its transition table and accepting states."""

    table: np.ndarray  # (n, N_CODES) int: next state, -1 when the token is rejected
    accept: np.ndarray  # (n,) bool; the start state is 0

    @property
    def size(self) -> int:
        return len(self.accept)

    @cached_property
    def _lists(self) -> tuple[list, list]:
        """The table and accept mask as Python lists (a step is a list look-up, not numpy
        indexing: the Matcher asks :meth:`accepts` and :meth:`accepting_prefixes` per segment)."""
        return self.table.tolist(), self.accept.tolist()

    def accepts(self, codes) -> bool:
        table, accept = self._lists
        state = 0
        for c in codes:
            state = table[state][c]
            if state < 0:
                return False
        return accept[state]

    def accepting_prefixes(self, codes) -> list[int]:
        """The lengths ``k`` (``0 ≤ k ≤ len(codes)``) of the prefixes ``codes[:k]`` it
        accepts, in increasing order (one pass)."""
        table, accept = self._lists
        state, out = 0, [0] if accept[0] else []
        for k, c in enumerate(codes, 1):
            state = table[state][c]
            if state < 0:
                break
            if accept[state]:
                out.append(k)
        return out


# --- Thompson's construction -------------------------------------------------------------

class _NFA:
    def __init__(self):
        self.eps: list[list[int]] = []
        self.moves: list[list[tuple[int, int]]] = []

    def state(self) -> int:
        self.eps.append([])
        self.moves.append([])
        return len(self.eps) - 1

    def build(self, node) -> tuple[int, int]:
        """Fragment ``(start, end)`` recognising ``node``."""
        from grammar.expr import Alt, Cat, Repeat, Sym  # here: DFAs read from the cache need no parse tree

        if isinstance(node, Sym):
            s, t = self.state(), self.state()
            self.moves[s].append((node.code, t))
            return s, t
        if isinstance(node, Cat):
            frags = [self.build(p) for p in node.parts]
            for (_, end), (start, _) in zip(frags, frags[1:]):
                self.eps[end].append(start)
            return frags[0][0], frags[-1][1]
        if isinstance(node, Alt):
            s, t = self.state(), self.state()
            for option in node.options:
                a, b = self.build(option)
                self.eps[s].append(a)
                self.eps[b].append(t)
            return s, t
        if isinstance(node, Repeat):
            s, t = self.state(), self.state()
            a, b = self.build(node.node)
            self.eps[s].append(a)
            self.eps[b].append(t)
            if node.least == 0:
                self.eps[s].append(t)
            if node.many:
                self.eps[b].append(a)
            return s, t
        raise TypeError(f"not an expression node: {node!r}")

    def closure(self, states) -> frozenset:
        seen, todo = set(states), list(states)
        while todo:
            for nxt in self.eps[todo.pop()]:
                if nxt not in seen:
                    seen.add(nxt)
                    todo.append(nxt)
        return frozenset(seen)

    def move(self, states, code: int) -> frozenset:
        return self.closure({t for s in states for c, t in self.moves[s] if c == code})


def compile_expression(node, minimal: bool = True) -> DFA:
    """Minimal DFA of the compacted language of an expression tree (with ``minimal``
    False, the subset construction's DFA of the same language, before minimisation: it
    answers the same questions about the language — acceptance, edit distances — and is
    quicker to build)."""
    nfa = _NFA()
    start, final = nfa.build(node)
    first = (nfa.closure({start}), -1)
    index = {first: 0}
    rows, accept = [], []
    todo = deque([first])
    while todo:
        states, last = todo.popleft()
        row = np.full(N_CODES, -1, dtype=np.int64)
        targets: dict[int, set] = {}  # token code → the NFA states it moves to
        for s in states:
            for code, t in nfa.moves[s]:
                targets.setdefault(code, set()).add(t)
        for code in sorted(targets):  # the only codes with a move (in code order)
            if code == last:
                continue
            key = (nfa.closure(targets[code]), code)
            if key not in index:
                index[key] = len(index)
                todo.append(key)
            row[code] = index[key]
        rows.append(row)
        accept.append(final in states)
    dfa = DFA(np.array(rows), np.array(accept, dtype=bool))
    return minimise(dfa) if minimal else dfa


def minimise(dfa: DFA) -> DFA:
    """The equivalent DFA with the fewest states: Moore's partition refinement, then only
    the classes that can still reach acceptance are kept (start first)."""
    n = dfa.size
    table = np.vstack([np.where(dfa.table < 0, n, dfa.table), np.full((1, N_CODES), n)])  # n: dead
    accept = np.append(dfa.accept, False)
    cls = accept.astype(np.int64)
    count = len(np.unique(cls))
    while True:
        _, cls = np.unique(np.column_stack([cls, cls[table]]), axis=0, return_inverse=True)
        cls = cls.ravel()
        if cls.max() + 1 == count:
            break
        count = int(cls.max()) + 1
    rep = np.array([int(np.flatnonzero(cls == c)[0]) for c in range(count)])
    moves = cls[table[rep]]  # (classes, N_CODES)
    good = accept[rep]
    live = good.copy()  # classes that reach acceptance: a backward fixpoint
    while True:
        grown = live | (live[moves].any(axis=1))
        if (grown == live).all():
            break
        live = grown
    start = cls[0]
    keep = [start] + [c for c in range(count) if live[c] and c != start]
    index = np.full(count, -1)
    index[keep] = np.arange(len(keep))
    index[~live] = -1
    return DFA(index[moves[keep]], good[keep])


def check_language(dfa: DFA, action: str) -> None:
    """DoodleError unless the action recognises some non-empty token string and not ``ε``."""
    if dfa.accept[0]:
        raise DoodleError(f"action {action!r}: the expression also matches no tokens at all; "
                          f"make at least one part mandatory (+ instead of *)")
    if not dfa.accept.any():
        raise DoodleError(f"action {action!r}: the expression matches no compacted token string "
                          f"(each group reads its own run: neighbouring groups cannot both need the same token)")


def intersection_witness(a: DFA, b: DFA) -> list[str] | None:
    """A shortest non-empty token string both DFAs accept, or None (breadth-first search
    over the product automaton)."""
    start = (0, 0)
    parent: dict = {start: None}

    def path_to(state) -> list[str]:
        out = []
        while parent[state] is not None:
            state, code = parent[state]
            out.append(NAMES[code])
        return out[::-1]

    todo = deque([start])
    while todo:
        s = todo.popleft()
        ra, rb = a.table[s[0]], b.table[s[1]]
        for code in np.flatnonzero((ra >= 0) & (rb >= 0)):
            t = (int(ra[code]), int(rb[code]))
            if a.accept[t[0]] and b.accept[t[1]]:  # also when t is the start again
                return path_to(s) + [NAMES[int(code)]]
            if t not in parent:
                parent[t] = (s, int(code))
                todo.append(t)
    return None


def sample(dfa: DFA, rng: np.random.Generator, stop: float = 0.3, max_len: int = 40) -> list[str]:
    """A random string of the language: a walk that stops at accepting states with
    probability ``stop`` (every live state can still reach acceptance)."""
    state, out = 0, []
    while True:
        options = np.flatnonzero(dfa.table[state] >= 0)
        if dfa.accept[state] and (len(options) == 0 or rng.random() < stop or len(out) >= max_len):
            return out
        code = int(rng.choice(options))
        out.append(NAMES[code])
        state = int(dfa.table[state, code])


def shortest(dfa: DFA) -> list[str]:
    """A shortest string of the language."""
    parent = {0: None}
    todo = deque([0])
    while todo:
        s = todo.popleft()
        if dfa.accept[s]:
            path = []
            while parent[s] is not None:
                s, code = parent[s]
                path.append(NAMES[code])
            return path[::-1]
        for code in np.flatnonzero(dfa.table[s] >= 0):
            t = int(dfa.table[s, code])
            if t not in parent:
                parent[t] = (s, int(code))
                todo.append(t)
    return []
