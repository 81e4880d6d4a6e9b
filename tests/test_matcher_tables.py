"""The Matcher's interned rows (grammar.rows) give the segments of the plain dense form they
replace — every row stepped as an array and kept while any state is within the threshold —
on random libraries and token strings, with either substitution costs; and the bound that
drops rows early (the longest way to acceptance) is the longest path."""

from dataclasses import astuple

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from doodle.core.tokens import CODES, Token
from grammar.automata import compile_expression, sample
from grammar.matcher import INF, Automaton, Matcher, match
from grammar.recognizer import load_actions
from grammar.blocks import longest_to_accept
from grammar.expr import Alt, Cat, Repeat, Sym

SMALL = ["T_Z", "T_Y", "T_N_Y"]  # a small alphabet, so random languages overlap


def exprs():
    leaf = st.sampled_from(SMALL).map(lambda n: Sym(CODES[n]))
    return st.recursive(leaf, lambda inner: st.one_of(
        st.lists(inner, min_size=2, max_size=3).map(lambda xs: Cat(tuple(xs))),
        st.lists(inner, min_size=2, max_size=3).map(lambda xs: Alt(tuple(xs))),
        st.tuples(inner, st.sampled_from([(0, True), (1, True), (0, False)])).map(lambda t: Repeat(t[0], *t[1]))),
        max_leaves=6)


class DenseMatcher(Matcher):
    """The Matcher before its rows were interned: a row is an array of costs, stepped with
    :meth:`Automaton.step` at every token, and kept while some state is within the
    threshold (the reference)."""

    def __init__(self, automaton, track="c0"):
        super().__init__(automaton, track)
        self._rows = np.empty((0, automaton.n))

    def push(self, token):
        e, auto = self._n, self.auto
        self._tokens[e] = token
        self._n += 1
        rows = auto.step(np.vstack([self._rows, auto.initial]), CODES[token.name])
        starts = np.array(self._starts + [e], dtype=np.int64)
        alive = rows.min(axis=1) <= auto.threshold
        self._rows, self._starts = rows[alive], starts[alive].tolist()
        cost, dist = self._best[e]
        best, back = (cost + self.unknown_cost, dist), (e, None, None)
        accept = auto.accept_costs(rows)
        lengths = e + 1 - starts
        ok = (accept == 0.0) | ((accept <= auto.limits) & (accept < lengths[:, None] / 2))
        low = np.where(ok, accept, INF).min(axis=1)
        for k in np.flatnonzero(ok.any(axis=1)).tolist():
            s, d_k = int(starts[k]), float(low[k])
            c, d = self._best[s]
            option = (c + 1.0 + self.edit_weight * d_k, d + d_k)
            if option < best:
                action = auto.most_specific(np.flatnonzero(ok[k] & (accept[k] == d_k)))
                best, back = option, (s, action, d_k)
        self._best[e + 1], self._back[e + 1] = best, back
        return self._emit_until(self._settled(set(self._starts) | {e + 1}))


def dense_match(tokens, automaton):
    matcher, out = DenseMatcher(automaton), []
    for token in tokens:
        out += matcher.push(token)
    return out + matcher.close()


def tokens_of(words):
    return [Token(w, 3 * i, 3 * i + 3) for i, w in enumerate(words)]


def same(a, b):
    return [astuple(s) for s in a] == [astuple(s) for s in b]


@settings(max_examples=80, deadline=None)
@given(st.lists(exprs(), min_size=1, max_size=4),
       st.lists(st.sampled_from(SMALL + ["T_X", "T_STILL"]), min_size=1, max_size=14),
       st.sampled_from([1.0, 2.0, 3.0]), st.booleans(), st.lists(st.sampled_from([None, 1.0, 4.0]), max_size=4))
def test_interned_rows_give_the_dense_segments(nodes, words, threshold, directional, tolerances):
    dfas = [compile_expression(n) for n in nodes]
    assume(all(d.accept.any() and not d.accept[0] for d in dfas))
    limits = [t if t is not None else threshold for t in (tolerances + [None] * len(dfas))[:len(dfas)]]
    auto = Automaton([f"A{k}" for k in range(len(dfas))], dfas, threshold, directional, limits=limits)
    words = [w for i, w in enumerate(words) if i == 0 or w != words[i - 1]]
    tokens = tokens_of(words)
    assert same(match(tokens, auto), dense_match(tokens, auto))


@pytest.mark.parametrize("threshold, directional", [(1.0, False), (2.0, False), (3.0, False), (2.0, True)])
def test_the_built_in_table_on_noisy_strings(threshold, directional):
    compiled = load_actions()
    auto = Automaton(compiled.library.names, list(compiled.dfas), threshold, directional)
    rng, alphabet, words = np.random.default_rng(int(threshold * 10) + directional), sorted(CODES), []
    while len(words) < 600:
        sampled = sample(compiled.dfas[int(rng.integers(len(compiled.dfas)))], rng)
        words += [alphabet[int(rng.integers(len(alphabet)))] if rng.random() < 0.1 else w for w in sampled]
        words.append("T_STILL")
    words = [w for i, w in enumerate(words) if i == 0 or w != words[i - 1]]
    tokens = tokens_of(words)
    assert same(match(tokens, auto), dense_match(tokens, auto))


def test_segments_are_final_sooner_than_the_dense_form_made_them():
    """A walk, a pause: final at the pause, not two motions later (the Idle row that
    deleted the walk cannot give a segment)."""
    compiled = load_actions()
    auto = compiled.automaton()
    words = ["T_STILL", "T_Z", "T_STILL", "T_Y", "T_N_Y", "T_STILL", "T_X", "T_STILL"]
    fast, slow = Matcher(auto), DenseMatcher(auto)
    when_fast, when_slow = {}, {}
    for i, token in enumerate(tokens_of(words)):
        when_fast.update({(s.action, s.first): i for s in fast.push(token)})
        when_slow.update({(s.action, s.first): i for s in slow.push(token)})
    assert when_fast[("Walk", 1)] == 2 < when_slow[("Walk", 1)]


@settings(max_examples=60, deadline=None)
@given(exprs())
def test_longest_way_to_acceptance(node):
    dfa = compile_expression(node)
    assume(dfa.accept.any())
    got = longest_to_accept(dfa.table, dfa.accept)
    q = dfa.size
    for p in range(q):  # brute force: the longest accepted continuation up to 2q tokens, or more
        longest, frontier = (0 if dfa.accept[p] else -np.inf), {p}
        for k in range(1, 2 * q + 2):
            frontier = {int(t) for s in frontier for t in dfa.table[s] if t >= 0}
            if any(dfa.accept[s] for s in frontier):
                longest = k
        expected = np.inf if longest > q else longest
        assert got[p] == expected


def test_an_automaton_read_back_from_its_tables_matches_the_same():
    """What the disk cache keeps (``Automaton.tables``) rebuilds an automaton whose Matcher
    gives the same segments (the interned rows included)."""
    compiled = load_actions()
    key = (2.0, False, None, None)
    fresh = compiled.automaton(*key)
    back = compiled.automaton_from(key, fresh.tables())
    rng, alphabet, words = np.random.default_rng(3), sorted(CODES), []
    while len(words) < 300:
        sampled = sample(compiled.dfas[int(rng.integers(len(compiled.dfas)))], rng)
        words += [alphabet[int(rng.integers(len(alphabet)))] if rng.random() < 0.1 else w for w in sampled]
        words.append("T_STILL")
    tokens = tokens_of([w for i, w in enumerate(words) if i == 0 or w != words[i - 1]])
    assert same(match(tokens, back), match(tokens, fresh))
    with pytest.raises(ValueError):
        compiled.automaton_from(key, {**fresh.tables(), "reads": fresh.tables()["reads"][:-1]})


def test_the_codes_a_state_reads_unlike_most_are_the_rest_of_its_largest_group():
    from grammar.blocks import _unlike

    auto = load_actions().automaton(2.0, True)
    for reads, unlike in zip(auto.reads, (_unlike(r) for r in auto.reads)):
        for p, bits in enumerate(unlike):
            alike = [c for c in range(reads.shape[0]) if not bits >> c & 1]
            assert alike, p
            steps = reads[:, p, :]
            assert all(np.array_equal(steps[c], steps[alike[0]]) for c in alike)  # one step for all
            group = [c for c in range(reads.shape[0]) if np.array_equal(steps[c], steps[alike[0]])]
            assert group == alike  # ... and every code taking it
            sizes = [sum(np.array_equal(steps[c], steps[d]) for d in range(reads.shape[0])) for c in range(reads.shape[0])]
            assert len(alike) == max(sizes)  # the step most codes take
