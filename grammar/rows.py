"""The Matcher's rows of edit costs, interned: each distinct row is stepped once per token.

A row (one per token position that may start a segment) holds the edit cost of every state
of every action after the tokens read from that position (:class:`grammar.matcher.Automaton`).
What the Matcher asks of a row depends on the row alone, so a row is kept once, under an
id (:class:`RowTable`), with the answers: its successor after each token (computed the first
time that token is read there, from its actions' blocks: :mod:`grammar.blocks`), its best
acceptance (the smallest accept cost of an action within that action's limit, and the
action the Matcher names for it: the narrowest language at that cost) and how many tokens
it must have read to still give a segment. The Matcher's step per token is then a list
look-up per live row; the arithmetic of :meth:`Automaton.step` is done once per new
(row, token). Tokens that every block of a row reads alike (most tokens, for most rows: a
token on none of the transitions from its live states is a substitution or deletion
everywhere) share one successor.

A row is the tuple of its blocks that can still give a segment, so a row whose every block
is dead is the empty row — dead: the Matcher drops it (see :mod:`grammar.blocks` for when a
block can still give a segment). Tables only grow, by about three thousand rows an hour of
random tokens (a few MB): there is no eviction.
"""

from __future__ import annotations

import numpy as np

from doodle.core.tokens import N_CODES
from grammar.blocks import INF, NONE, UNSEEN, Blocks, first_zero


class RowTable:
    """The distinct rows of an :class:`~grammar.matcher.Automaton`, by id (see the module).

    ``next[i][code]`` is the id of row ``i`` after reading ``code`` (:data:`NONE` until
    :meth:`move` has computed it); ``low[i]`` the smallest accept cost of an action within
    its limit (``inf`` when none is), ``pick[i]`` the action named for it (the narrowest
    language among those at that cost), ``shortest[i]`` the length of token string up to
    which the row can give no later segment (``inf``: none, ever; the Matcher counts its
    segment of the moment, then drops it).

    A row is the tuple of its actions' *blocks* that can still give a segment (a block: one
    action's costs, canonical, interned by :class:`Blocks`); each block steps on its own."""

    def __init__(self, auto):
        self.blocks = Blocks(auto)
        rank = np.lexsort((np.arange(len(auto.names)), auto.sizes_counted))  # most specific first
        self._rank = [0] * len(rank)
        for place, a in enumerate(rank.tolist()):
            self._rank[a] = place
        self._index: dict[tuple, int] = {}
        self.next: list[list[int]] = []
        self.low: list[float] = []
        self.pick: list[int] = []
        self.shortest: list[float] = []
        self._rows: list[tuple] = []
        self._special: list[int] = []  # per row: the codes its blocks do not all read alike
        self._common: list[int] = []  # ... and a code they all read alike (-1: none)
        self.start = self._intern(tuple(b for b in self.blocks.initial if b != NONE))

    def __len__(self) -> int:
        return len(self._rows)

    def move(self, i: int, code: int) -> int:
        """The id of row ``i`` after one more token ``code`` (computed once; once for all
        the codes its blocks read alike)."""
        j = self.next[i][code]
        if j != NONE:
            return j
        common = self._common[i]
        if not self._special[i] >> code & 1 and code != common:
            j = self.next[i][code] = self.move(i, common)
            return j
        blocks = self.blocks
        nxt, step, row = blocks.next, blocks.move, []
        for g in self._rows[i]:
            h = nxt[g][code]
            if h == UNSEEN:
                h = step(g, code)
            if h != NONE:
                row.append(h)
        j = self.next[i][code] = self._intern(tuple(row))
        return j

    def _intern(self, row: tuple) -> int:
        found = self._index.get(row)
        if found is not None:
            return found
        i = len(self._rows)
        self._index[row] = i
        self._rows.append(row)
        self.next.append([NONE] * N_CODES)
        accept, action, shortest, special = self.blocks.accept, self.blocks.action, self.blocks.shortest, self.blocks.special
        low, pick, short, unlike, rank = INF, -1, INF, 0, self._rank
        for g in row:
            if accept[g] < low or (accept[g] == low < INF and rank[action[g]] < rank[pick]):
                low, pick = accept[g], action[g]
            short = min(short, shortest[g])
            unlike |= special[g]
        self.low.append(low)
        self.pick.append(pick)
        self.shortest.append(short)
        self._special.append(unlike)
        self._common.append(first_zero(unlike))
        return i
